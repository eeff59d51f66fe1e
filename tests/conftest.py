import gc
import os
import shutil
import tempfile
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

# JAX's persistent compilation cache in a folder of this test session's own (inherited by
# the CLI subprocesses the tests start), not the user's ~/.cache/rotor/jax: a run starts
# from what it compiles itself, as on a fresh machine, never reads entries that other
# processes wrote, and recompiles cheaply after _free_compiled_code below.
_OWN_CACHE = None
if "ROTOR_COMPILATION_CACHE" not in os.environ:
    _OWN_CACHE = os.environ["ROTOR_COMPILATION_CACHE"] = tempfile.mkdtemp(prefix="rotor-test-jax-cache-")


# The kept outputs of `rotor table` and `rotor info` (rotor/cli/kept.py) are off: every CLI
# test computes what it checks; tests/test_cli_latency.py switches them on in a folder of its own.
os.environ.setdefault("ROTOR_OUTPUT_CACHE", "off")


def pytest_sessionfinish(session, exitstatus):
    if _OWN_CACHE is not None:
        shutil.rmtree(_OWN_CACHE, ignore_errors=True)


import jax  # noqa: E402

import rotor  # noqa: E402  (switches float64 on)

# Switched on for the tests in this process too, not only once a CLI command has run in it:
# most of the suite's time is XLA compiling rotor's kernels, and many modules (and both
# xdist workers, the CLI subprocesses and the notebook kernels of tests/test_notebooks.py,
# which share the folder) compile the same ones. A kernel compiled once in the session is
# read back instead of compiled again, also after _free_compiled_code below drops it.
# ROTOR_COMPILATION_CACHE=off runs the suite without it.
COMPILATION_CACHE = rotor.enable_compilation_cache()

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"
SHARED_DATA = ROOT.parent / "shared" / "data"


@pytest.fixture(autouse=True, scope="module")
def _free_compiled_code():
    """Drop JAX's compiled executables after each test module. Every loaded CPU executable
    holds memory mappings; one process running the whole suite otherwise passes Linux's
    vm.max_map_count (65530) about 85 % of the way through and XLA crashes in the next
    compile (two test modules alone leave 24 000 mappings; after clear_caches, 1 100)."""
    yield
    jax.clear_caches()
    gc.collect()


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
