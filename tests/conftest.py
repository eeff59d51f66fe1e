from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

import rotor  # noqa: E402  (switches float64 on)

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"
SHARED_DATA = ROOT.parent / "shared" / "data"


@pytest.fixture(scope="session")
def diesel():
    return rotor.load_engine("4chn15")


def two_mass_engine(
    lam=0.267,
    R=0.1025,
    m_rec=9.72,
    m_rot=0.0,
    J=1e-6,
    cylinders=1,
    k=0.0,
    throws=None,
    firing=None,
    pressure=None,
    strokes=4,
):
    """A small engine built in Python, for closed-form checks."""
    throws = [0.0] * cylinders if throws is None else throws
    firing = list(range(1, cylinders + 1)) if firing is None else firing
    return rotor.Engine(
        name="test",
        strokes=strokes,
        cylinders=cylinders,
        geometry=rotor.Geometry(bore_m=0.15, stroke_m=2 * R, rod_length_m=R / lam, pin_offset_m=k),
        masses=rotor.Masses(reciprocating_kg=m_rec, rotating_kg=m_rot),
        crankshaft=rotor.Crankshaft(inertia_kgm2=J),
        layout=rotor.Layout(throw_angles_deg=throws, firing_order=firing),
        pressure=rotor.NoPressure() if pressure is None else pressure,
        operating=rotor.Operating(rpm=1000.0),
    )
