"""The pressure channel's work: ∮u·dV of the recorded signal per cycle, and the IMEP it measures.

A single-cylinder recording's pressure channel u (a signal, p = g·u + b) does the work
∫u·A·s′(θ) dθ over the crank angle θ (A the piston area, s the piston's displacement);
with the sensor's gain g it gives each cycle's IMEP, ∮p·dV / V_h (the offset b drops out
of a closed cycle). :func:`rotor.calibrate` fits its energy balance on this work and
:func:`rotor.diagnose` compares the identified IMEP with :func:`measured_imep`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import EngineError
from ..logs.analysis import LogAnalysis

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = ["measured_imep", "signal_work", "piston_displacement", "check_single_cylinder"]


def check_single_cylinder(engine: Engine, what: str) -> None:
    """Raise :class:`rotor.EngineError` unless ``engine`` has one cylinder: a log of one
    pressure channel holds every cylinder's pressure only then (``what`` begins the message)."""
    if engine.cylinders != 1:
        raise EngineError(
            f"{what}: engine {engine.name!r} has {engine.cylinders} cylinders; a calibration from a "
            f"pressure channel needs every cylinder's pressure, which a log of one channel has only "
            f"for a single-cylinder engine (not yet: several cylinders)"
        )


def piston_displacement(engine: Engine, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cylinder 1's piston displacement s [m] and ds/dθ [m/rad] at the crank angles ``theta``."""
    from ..engine.mechanism import engine_piston_motion

    pm = engine_piston_motion(engine, np.asarray(theta))
    return np.asarray(pm.s)[..., 0], np.asarray(pm.ds)[..., 0]


def signal_work(engine: Engine, analysis: LogAnalysis) -> np.ndarray:
    """∫ u·A·s′ dθ per cycle from the cycle start, at the speed's grid angles ((cycles, P+1),
    the last column the whole cycle), u the pressure signal averaged in bins
    (:func:`rotor.diagnostics.pegging.binned_pressure`)."""
    from .pegging import binned_pressure

    centres, sig = binned_pressure(analysis)
    h = analysis.cycle_rad / centres.size
    _, ds = piston_displacement(engine, centres)
    area = float(engine.geometry.piston_area_m2)
    edges = np.arange(centres.size + 1) * h
    cum = np.concatenate([np.zeros((sig.shape[0], 1)), np.cumsum(sig * ds * area * h, axis=1)], axis=1)
    P = analysis.points_per_cycle
    psi = np.arange(P + 1) * analysis.cycle_rad / P
    return np.stack([np.interp(psi, edges, row) for row in cum])


def measured_imep(engine: Engine, analysis: LogAnalysis, pressure_gain: float) -> np.ndarray:
    """IMEP of each complete cycle from the recording's pressure channel, ∮p·dV / V_h [Pa].

    **Arguments:** ``engine`` (its geometry: the swept volume and the crank mechanism);
    ``analysis``: a :class:`rotor.LogAnalysis` with a pressure channel and TDC;
    ``pressure_gain``: pascal per unit of the signal (the offset drops out of ∮p·dV).

    **Returns:** (cycles,) [Pa].
    """
    check_single_cylinder(engine, "measured_imep")
    w = signal_work(engine, analysis)[:, -1]
    return float(pressure_gain) * w / float(engine.geometry.displacement_m3)
