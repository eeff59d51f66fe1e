"""The operating point: the load an engine carries and the fuelling that carries it.

A **load** is a torque the engine carries against its rotation [N·m] (friction apart). The
**fuel scale** is the combustion of every firing as a multiple of the engine file's
pressure trace [-]: 1 the file's cycle, 0 none (a motored engine); the IMEP is affine in
it, IMEP = IMEP_motored + fuel_scale·(IMEP_file − IMEP_motored).

At a steady operating point one of the two is given and the other solved so that the
engine's mean torque meets the load and friction: :func:`rotor.steady_state` solves the
fuel scale for a given load, or the load for a given fuel scale (``load=None``);
``rotor simulate`` keeps the fuel scale given (1 unless ``--fuel-scale``) and solves it
only when asked (``--balance``). Every result says which was given and which solved
(``solved_for``).

A fuel scale above :data:`FUEL_SCALE_WARN` burns more than an engine of the file's rating
can: a :class:`FuelScaleWarning` names the IMEP it implies. Above :data:`FUEL_SCALE_MAX`,
or below 0, it is no operating point of the engine and is refused
(:class:`rotor.EngineError`), usually a load in the wrong units.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import EngineError
from ..units import PA_PER_BAR

__all__ = [
    "FUEL_SCALE_MAX",
    "FUEL_SCALE_WARN",
    "FuelScaleWarning",
    "check_fuel_scale",
    "given_operating_point",
    "implied_imep_pa",
]

FUEL_SCALE_WARN = 1.2
"""The fuel scale [-] above which a warning names the IMEP it implies."""
FUEL_SCALE_MAX = 10.0
"""The largest fuel scale [-] taken as an operating point; more is refused."""


class FuelScaleWarning(UserWarning):
    """A fuel scale above :data:`FUEL_SCALE_WARN`: more fuel than the engine file's rating."""


def implied_imep_pa(fuel_scale: float, imep_motored_pa: object, imep_combustion_pa: object) -> float:
    """The mean IMEP over the cylinders [Pa] at ``fuel_scale`` [-], from each cylinder's
    motored IMEP and the part its combustion adds at fuel scale 1 [Pa]."""
    m = float(np.mean(np.asarray(imep_motored_pa, dtype=np.float64)))
    c = float(np.mean(np.asarray(imep_combustion_pa, dtype=np.float64)))
    return m + fuel_scale * c


def check_fuel_scale(
    fuel_scale: float,
    imep_motored_pa: object,
    imep_combustion_pa: object,
    *,
    solved: bool,
    load_Nm: float | None = None,
    name: str = "fuel scale",
) -> None:
    """Refuse a fuel scale [-] outside 0 … :data:`FUEL_SCALE_MAX` and warn
    (:class:`FuelScaleWarning`) above :data:`FUEL_SCALE_WARN`, naming the IMEP it implies
    (``imep_*_pa``: per cylinder, see :func:`implied_imep_pa`; None where not known, e.g.
    under ``jax.grad``). ``solved``: whether it was solved to carry the load ``load_Nm``
    [N·m] (the message says so) or given as ``name``."""
    x = float(fuel_scale)
    if 0 <= x <= FUEL_SCALE_WARN:
        return
    what = (
        f"the load of {load_Nm:.6g} N·m needs the fuelling ×{x:.3g} the engine file's"
        if solved and load_Nm is not None
        else f"{name} {x:.6g}: the fuelling ×{x:.3g} the engine file's"
    )
    if imep_motored_pa is None or imep_combustion_pa is None:
        implied = "an IMEP beyond the engine's rating"
    else:
        rated = implied_imep_pa(1.0, imep_motored_pa, imep_combustion_pa)
        imep = implied_imep_pa(x, imep_motored_pa, imep_combustion_pa)
        implied = f"IMEP {imep / PA_PER_BAR:.1f} bar against its {rated / PA_PER_BAR:.2f} bar"
    if not np.isfinite(x) or x < 0 or x > FUEL_SCALE_MAX:
        hint = "check the load's units (N·m) and size" if solved else f"give 0 … {FUEL_SCALE_MAX:g}"
        raise EngineError(f"{what} ({implied}): outside 0 … {FUEL_SCALE_MAX:g}, not an operating point; {hint}")
    if x > FUEL_SCALE_WARN:
        warnings.warn(
            f"{what} ({implied}): above ×{FUEL_SCALE_WARN:g}, more than the engine is rated for",
            FuelScaleWarning,
            stacklevel=3,
        )


def given_operating_point(load: object, scales: object, governed: bool) -> tuple[object, float | None]:
    """The load torque [N·m] and the fuel scale [-] of a run given them both (a transient:
    nothing solved): the torque of a constant ``load`` (None for another load, 0 for none),
    and the one combustion scale of every firing ``scales`` (cycles, cylinders) where they
    are all the same and no governor (``governed``) changes them (else None: a pattern, or
    values under ``jax`` tracing)."""
    from .loads import ConstantLoad

    torque = 0.0 if load is None else (load.torque_Nm if isinstance(load, ConstantLoad) else None)
    fuel = None
    if not governed:
        try:
            values = np.unique(np.asarray(scales, dtype=np.float64))
        except Exception:  # noqa: BLE001 - a traced value has no number to state
            values = np.array([])
        fuel = float(values[0]) if values.size == 1 else None
    return torque, fuel
