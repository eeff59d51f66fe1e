"""What an engine's numbers may be: Python types at the API edge and plausible ranges.

**Types.** A numeric field of an engine table takes a number (``int``, ``float``, a numpy
or JAX scalar) or, for the lists of the file, a sequence or array of numbers; anything
else (a string, ``None``, a dict) is a :class:`TypeError` that names the key and what it
takes (:func:`number`). The public functions of :mod:`rotor.engine` and
:mod:`rotor.design` check their arguments the same way
(:func:`rotor.engine.model.require_engine`, :func:`require_number`, :func:`require_whole`).

**Plausible ranges** (:data:`PLAUSIBLE`). Finite and positive is not enough: a bore of
1e300 m is finite, and its piston area overflows. Each input must lie within a range
wide enough for every piston engine from a 5 cm³ model engine to the largest two-stroke
ship diesels (bore 0.98 m, stroke 3.15 m, about 100 t of crank train), and no wider
than a mistake of units can hide in:

- ``[geometry] bore_m``: 0.001 … 2 m
- ``[geometry] stroke_m``: 0.001 … 5 m
- ``[geometry] rod_length_m``: 0.001 … 20 m
- ``[geometry] pin_offset_m``: −1 … 1 m
- ``[masses] reciprocating_kg``: 1e-6 … 1e5 kg
- ``[masses] rotating_kg``: 0 … 1e5 kg
- ``[masses] rod_kg``: 0 … 1e5 kg
- ``[masses] rod_cg_from_big_end_m``: 0 … 20 m
- ``[masses] rod_inertia_kgm2``: 0 … 1e5 kg·m²
- ``[masses] rod_big_end_kg``: 0 … 1e5 kg
- ``[crankshaft] inertia_kgm2``: 1e-12 … 1e8 kg·m²
- ``[crankshaft] journal_spacing_m``: 0.001 … 20 m
- ``[[counterweights]] mass_kg``: 0 … 1e5 kg
- ``[[counterweights]] radius_m``: 0 … 5 m
- ``[[counterweights]] angle_deg``: −3600 … 3600 deg
- ``[layout] throw_angles_deg``: −3600 … 3600 deg
- ``[layout] bank_angles_deg``: −3600 … 3600 deg
- ``[operating] rpm``: 0.1 … 100 000 rev/min
- ``[pressure] pressure_pa``: 0 … 1e9 Pa (10 000 bar)
- ``[pressure] crankcase_pa``: 0 … 1e9 Pa (10 000 bar)
- ``[pressure] intake_pa``: 0 … 1e9 Pa (10 000 bar)
- ``[pressure] exhaust_pa``: 0 … 1e9 Pa (10 000 bar)
- ``[pressure] imep_pa``: 0 … 1e9 Pa (10 000 bar)
- ``[pressure] compression_ratio``: 1.5 … 100
- ``[pressure] duration_deg``: 0 … 720 deg
- ``[pressure] form_factor``: 0 … 50
- ``[friction] fmep_pa``: 0 … 1e8 Pa
- ``[friction] fmep_per_speed_pa_s_per_m``: 0 … 1e8 Pa·s/m
- ``[friction] fmep_per_speed2_pa_s2_per_m2``: 0 … 1e8 Pa·s²/m²
- ``[articulated] knuckle_radius_m``: 0 … 5 m
- ``[articulated] rod_length_m``: 0.001 … 20 m
- ``[articulated] knuckle_angle_deg``: −3600 … 3600 deg
- ``[articulated] rod_knuckle_kg``: 0 … 1e5 kg
- ``[torsion] inertias_kgm2``: 1e-12 … 1e8 kg·m²
- ``[torsion] stiffnesses_Nm_per_rad``: 1e-3 … 1e12 N·m/rad
- ``[torsion] absolute_damping_Nms_per_rad``: 0 … 1e9 N·m·s/rad
- ``[torsion] relative_damping_Nms_per_rad``: 0 … 1e9 N·m·s/rad
- ``[torsion] modal_damping_ratio``: 0 … 0.99

Whether a key may be zero is decided by the table's own check (a bore must be > 0, a
rotating mass may be 0); the range bounds what is finite but absurd. A value outside its
range that reads as another unit (a bore of 92: 92 mm) is refused naming that unit
(:func:`unit_slips`).

**Units at the edge** (:data:`EDGE_RANGES`, :func:`check_engine_file_units`,
:func:`check_edge`). An engine file (and a calibration file, whose reader calls
:func:`check_edge`) is held to the ranges of real engines, narrow enough that a value in
another unit falls outside them and is refused naming the unit it looks like:

- intake pressure 0.1 … 5 bar absolute (``intake_pa = 0.95`` is bar); exhaust 0.1 … 10 bar;
  crankcase 0, or 0.1 … 10 bar;
- a pressure table's peak 5 … 300 bar, its points 0.01 … 300 bar (a table in MPa peaks
  below 1000 Pa);
- IMEP up to 40 bar in magnitude; 0 and negative values (a motored or idling engine)
  pass, but a magnitude under 1000 Pa (``imep_pa = 12.5``: bar) is refused;
- FMEP 0, or 0.01 … 20 bar;
- lengths against each other: the stroke 0.2 … 5 bores, the rod 10 strokes at most (a
  stroke in mm beside a bore in m, a rod in cm);
- masses against the bore: a piston group, rod or rotating mass of at most
  :data:`MAX_MASS_PER_BORE3` × bore³ (a mass in grams);
- inertia: the crankshaft's at most :data:`MAX_INERTIA_PER_BORE5` × cylinders × bore⁵, a
  rod's about its centre of mass at most its mass × its length² (an inertia in kg·cm²).

These ranges are not applied to tables built in Python (``WiebeCycle(...)``), which keep
the wide ranges above: a charge scaled by σ (:meth:`rotor.WiebeCycle.scale_charge`) may take
an intake pressure below 0.1 bar.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any, Literal, overload

import jax
import numpy as np

from ..checks import as_f64, concrete, guard_number, has_tracer, is_tracer, where
from ..errors import EngineError

__all__ = [
    "PLAUSIBLE",
    "number",
    "check_plausible",
    "check_fields_plausible",
    "guard_fields",
    "check_results_finite",
    "check_speed_rpm",
    "finite_derived",
    "require_number",
    "require_real",
    "require_known",
    "checked_angle",
    "what_it_is",
    "require_whole",
    "EDGE_RANGES",
    "MAX_MASS_PER_BORE3",
    "MAX_INERTIA_PER_BORE5",
    "UNIT_SLIPS",
    "unit_slips",
    "check_edge",
    "check_pressure_table",
    "check_engine_file_units",
    "check_inertia_kgm2",
]

_PRESSURE = (
    0.0,
    1e9,
    "Pa",
    "an absolute pressure in pascals, e.g. 101325 for 1 atm; peak firing pressures are below 3e7",
)

PLAUSIBLE: dict[tuple[str, str], tuple[float, float, str, str]] = {
    ("geometry", "bore_m"): (1e-3, 2.0, "m", "a bore is metres, e.g. 0.092"),
    ("geometry", "stroke_m"): (1e-3, 5.0, "m", "a stroke is metres, e.g. 0.09"),
    ("geometry", "rod_length_m"): (1e-3, 20.0, "m", "a rod length is metres, centre to centre, e.g. 0.15"),
    ("geometry", "pin_offset_m"): (-1.0, 1.0, "m", "a pin offset is metres, a few mm at most, e.g. 0.001"),
    ("masses", "reciprocating_kg"): (1e-6, 1e5, "kg", "the piston group of one cylinder, e.g. 0.6"),
    ("masses", "rotating_kg"): (0.0, 1e5, "kg", "per cylinder, e.g. 0.5"),
    ("masses", "rod_kg"): (0.0, 1e5, "kg", "one connecting rod, e.g. 0.7"),
    ("masses", "rod_cg_from_big_end_m"): (0.0, 20.0, "m", "a distance in metres along the rod, e.g. 0.05"),
    ("masses", "rod_inertia_kgm2"): (0.0, 1e5, "kg·m²", "about the rod's centre of mass, e.g. 0.004"),
    ("masses", "rod_big_end_kg"): (0.0, 1e5, "kg", "the rod's share at the crank pin, e.g. 0.45"),
    ("crankshaft", "inertia_kgm2"): (1e-12, 1e8, "kg·m²", "crankshaft and flywheel, e.g. 0.3 for a car engine"),
    ("crankshaft", "journal_spacing_m"): (1e-3, 20.0, "m", "main journal centre to centre, e.g. 0.1"),
    ("counterweights", "mass_kg"): (0.0, 1e5, "kg", "one counterweight, e.g. 1.2"),
    ("counterweights", "radius_m"): (0.0, 5.0, "m", "its centre of mass from the crank axis, e.g. 0.04"),
    ("counterweights", "angle_deg"): (-3600.0, 3600.0, "deg", "from its throw, e.g. 180"),
    ("layout", "throw_angles_deg"): (-3600.0, 3600.0, "deg", "crank angles in degrees, e.g. 0, 180"),
    ("layout", "bank_angles_deg"): (-3600.0, 3600.0, "deg", "bank angles in degrees, e.g. 0, 90"),
    ("operating", "rpm"): (0.1, 1e5, "rev/min", "a crank speed in rpm, e.g. 3000"),
    ("pressure", "pressure_pa"): _PRESSURE,
    ("pressure", "crankcase_pa"): _PRESSURE,
    ("pressure", "intake_pa"): _PRESSURE,
    ("pressure", "exhaust_pa"): _PRESSURE,
    ("pressure", "imep_pa"): _PRESSURE,
    ("pressure", "compression_ratio"): (1.5, 100.0, "", "V_max/V_min, e.g. 10 (petrol) or 17 (diesel)"),
    ("pressure", "duration_deg"): (0.0, 720.0, "deg", "the burn in crank degrees, e.g. 50"),
    ("pressure", "form_factor"): (0.0, 50.0, "", "Wiebe's m, usually 0.5…3"),
    ("friction", "fmep_pa"): (0.0, 1e8, "Pa", "a friction mean effective pressure in pascals, e.g. 1e5"),
    ("friction", "fmep_per_speed_pa_s_per_m"): (0.0, 1e8, "Pa·s/m", "e.g. 5000"),
    ("friction", "fmep_per_speed2_pa_s2_per_m2"): (0.0, 1e8, "Pa·s²/m²", "e.g. 400"),
    ("articulated", "knuckle_radius_m"): (0.0, 5.0, "m", "big-end centre to knuckle pin, e.g. 0.05"),
    ("articulated", "rod_length_m"): (1e-3, 20.0, "m", "knuckle pin to piston pin, e.g. 0.2"),
    ("articulated", "knuckle_angle_deg"): (-3600.0, 3600.0, "deg", "an angle in degrees, e.g. 60"),
    ("articulated", "rod_knuckle_kg"): (0.0, 1e5, "kg", "e.g. 0.3"),
    ("torsion", "inertias_kgm2"): (1e-12, 1e8, "kg·m²", "one mass of the chain, e.g. 0.03 for a throw"),
    ("torsion", "stiffnesses_Nm_per_rad"): (1e-3, 1e12, "N·m/rad", "one shaft section, e.g. 1.2e6"),
    ("torsion", "absolute_damping_Nms_per_rad"): (0.0, 1e9, "N·m·s/rad", "e.g. 20 for a viscous damper"),
    ("torsion", "relative_damping_Nms_per_rad"): (0.0, 1e9, "N·m·s/rad", "e.g. 5"),
    ("torsion", "modal_damping_ratio"): (0.0, 0.99, "", "a fraction of critical damping, e.g. 0.02"),
}
"""(table, key) → (low, high, unit, hint): the plausible range of an input (see the module doc)."""


def what_it_is(x: Any) -> str:
    """``x`` in a few words for an error message: its type and the start of its repr."""
    text = repr(x)
    return f"{type(x).__name__} {text if len(text) <= 40 else text[:37] + '...'}"


def number(table: str, key: str, *, optional: bool = False) -> Callable[[Any], Any]:
    """The field converter of ``[table] key``: a number, or a sequence or array of numbers,
    becomes a float64 JAX array (tracers pass); anything else raises a :class:`TypeError`
    naming the key. ``optional``: ``None`` is kept (the key is absent)."""

    def convert(x: Any) -> Any:
        if optional and x is None:
            return None
        if isinstance(x, jax.core.Tracer):
            return x
        kind = "?"
        if not isinstance(x, (str, bytes, dict)) and x is not None:
            try:
                kind = np.asarray(x).dtype.kind
            except (TypeError, ValueError):
                kind = "?"
        if kind not in "biuf":  # a boolean is refused by as_f64 with its own message
            raise TypeError(
                f"{where(table, key)} = {x!r:.40}: expected a number (or a list of numbers), not a {type(x).__name__}"
            )
        return as_f64(x)

    convert.__qualname__ = convert.__name__ = f"number_{table}_{key}"
    return convert


def check_plausible(table: str, key: str, value: Any) -> None:
    """Raise :class:`rotor.EngineError` if the concrete ``value`` of ``[table] key`` (units
    as in its name) lies outside its :data:`PLAUSIBLE` range; tracers and unknown keys pass."""
    if (table, key) not in PLAUSIBLE or value is None:
        return
    v = concrete(value)
    if v is None:
        return
    lo, hi, unit, hint = PLAUSIBLE[(table, key)]
    bad = v[~((v >= lo) & (v <= hi))] if v.ndim else (v if not (lo <= v <= hi) else np.empty(0))
    if np.size(bad):
        b = float(np.ravel(bad)[0])
        shown = f" = {b:g}" if v.ndim == 0 else f": {b:g}"
        u = f" {unit}" if unit else ""
        raise EngineError(
            f"{where(table, key)}{shown} lies outside the plausible {lo:g} … {hi:g}{u} of any piston engine ({hint})"
            + _slip_text(b, lo, hi, unit, _typical(hint))
        )


@overload
def require_number(value: Any, call: str, unit: str = "", *, optional: Literal[False] = False) -> float: ...


@overload
def require_number(value: Any, call: str, unit: str = "", *, optional: bool) -> float | None: ...


def require_number(value: Any, call: str, unit: str = "", *, optional: bool = False) -> float | None:
    """``value`` as a Python float if it is a real number (a Python, numpy or concrete JAX
    scalar; not a bool or a string), else a :class:`TypeError` naming ``call`` (e.g.
    ``"design_flywheel(delta)"``) and the ``unit`` it takes, also for a value traced by
    ``jax.jit``/``vmap``/``grad`` (the functions that take numbers this way compute on the
    host). ``optional``: ``None`` passes as ``None``. Whether the number is in range is the
    caller's check."""
    if value is None and optional:
        return None
    if is_tracer(value):
        u = f" [{unit}]" if unit else ""
        raise TypeError(
            f"{call}: takes a number{u} known when it is called, not a value traced by jax.jit, vmap or grad; "
            "call it outside the transformation"
        )
    ok = not isinstance(value, (bool, np.bool_, str, bytes)) and value is not None
    if ok and not isinstance(value, (int, float, np.integer, np.floating)):
        a = concrete(value) if hasattr(value, "dtype") else None
        ok = a is not None and a.ndim == 0 and np.asarray(value).dtype.kind in "iuf"
    if not ok:
        u = f" [{unit}]" if unit else ""
        raise TypeError(f"{call}: expected a number{u}, got {what_it_is(value)}")
    return float(value)


def require_real(call: str, name: str, value: Any, unit: str) -> None:
    """A :class:`TypeError` naming ``call(name)`` and the ``unit`` it takes where ``value``
    is not real numbers (a string, a complex number, a bool, None); traced values too."""
    if is_tracer(value):
        kind = np.dtype(value.dtype).kind
    elif isinstance(value, (str, bytes, bool, np.bool_)) or value is None:
        kind = "?"
    else:
        try:
            kind = np.asarray(value).dtype.kind
        except (TypeError, ValueError):
            kind = "?"
    if kind not in "iuf":
        raise TypeError(f"{call}({name}): expected real numbers [{unit}], got {what_it_is(value)}")


def require_known(call: str, why: str, **values: Any) -> None:
    """Refuse a value traced by ``jax.jit``/``vmap``/``grad`` (a :class:`TypeError` naming
    ``call(argument)``) in a function that computes on the host; ``why`` says what it
    does there (e.g. ``"the design searches on the host"``), the message what to do."""
    for name, value in values.items():
        if has_tracer(value):
            raise TypeError(
                f"{call}({name}): takes values known when it is called, not values traced by jax.jit, vmap or grad "
                f"({why}); call it outside the transformation"
            )


def checked_angle(call: str, name: str, theta: Any, unit: str = "rad") -> Any:
    """``theta`` (an angle [rad], or a speed: ``unit``) of a public function ``call``: real
    numbers (else a :class:`TypeError`), all finite (else a :class:`rotor.EngineError`, or
    for a traced value an error when the program runs,
    :func:`rotor.checks.guard_number`), each naming ``call(name)``. Returns the value to use."""
    require_real(call, name, theta, unit)
    if is_tracer(theta):
        return guard_number(theta, f"{call}({name})", unit=unit)
    a = np.asarray(theta, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise EngineError(f"{call}({name}): must be finite [{unit}], got a NaN or an infinity")
    return theta


def require_whole(value: Any, call: str, lo: int = 1) -> int:
    """``value`` as an ``int`` if it is a whole number ≥ ``lo`` (a Python or numpy integer,
    not a bool): a :class:`TypeError` naming ``call`` for another type, a
    :class:`rotor.EngineError` below ``lo``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{call}: expected a whole number, got {what_it_is(value)}")
    if value < lo:
        raise EngineError(f"{call} = {value}: must be {lo} or more")
    return int(value)


def finite_derived(what: str, value: Any, unit: str, cause: str, *, positive: bool = True) -> None:
    """Raise :class:`rotor.EngineError` if a concrete derived quantity is not finite (or,
    with ``positive``, not > 0): ``what`` names it, ``unit`` is its unit, ``cause`` the
    inputs it came from (e.g. ``"[geometry] bore_m = 1e+300"``), first in the message."""
    v = concrete(value)
    if v is None:
        return
    finite = bool(np.all(np.isfinite(v)))
    if finite and (not positive or bool(np.all(v > 0))):
        return
    shown = float(np.ravel(v)[~np.isfinite(np.ravel(v))][0]) if not finite else float(np.min(v))
    how = "overflows" if not finite and not math.isnan(shown) else "is not a number" if not finite else "vanishes"
    raise EngineError(f"{cause}: {what} {how} ({shown:g} {unit}); check the units of these inputs")


def check_fields_plausible(module: Any) -> None:
    """:func:`check_plausible` on every field of an engine table ``module`` (its ``table``
    names it in the file)."""
    import dataclasses

    table = getattr(module, "table", "")
    for f in dataclasses.fields(module):
        check_plausible(table, f.name, getattr(module, f.name))


def guard_fields(module: Any, checks: Any = None) -> Any:
    """``module`` (an engine table, or a :class:`rotor.Friction`) with each traced field
    checked when the program runs (:func:`rotor.checks.guard_number`; with ``checks``, a
    :class:`rotor.checks.TracedChecks`, recorded there): finite and within its
    :data:`PLAUSIBLE` range (a key without one: finite), the message naming the key. The
    same module where no field is traced (its concrete values were checked when it was
    built, or by :meth:`rotor.Engine.check`)."""
    import dataclasses

    import equinox as eqx

    table = getattr(module, "table", "")
    changes: dict[str, Any] = {}
    for f in dataclasses.fields(module):
        value = getattr(module, f.name)
        if is_tracer(value):
            lo, hi, unit, hint = PLAUSIBLE.get((table, f.name), (-math.inf, math.inf, "", ""))
            changes[f.name] = guard_number(value, where(table, f.name), lo, hi, unit=unit, expected=hint, checks=checks)
    if not changes:
        return module
    names = list(changes)
    return eqx.tree_at(lambda m: [getattr(m, k) for k in names], module, [changes[k] for k in names])


def check_speed_rpm(rpm: Any, call: str) -> float:
    """A crank speed argument [rev/min] as a float: a number (else :class:`TypeError` naming
    ``call``), finite, positive and within the plausible range of ``[operating] rpm``
    (else :class:`rotor.EngineError`)."""
    v = require_number(rpm, call, "rpm")
    lo, hi, unit, _ = PLAUSIBLE[("operating", "rpm")]
    if not (math.isfinite(v) and lo <= v <= hi):
        raise EngineError(
            f"{call} = {rpm!r}: must be a positive, finite speed between {lo:g} and {hi:g} {unit} (in rpm, e.g. 3000)"
        )
    return v


def check_results_finite(what: str, values: dict[str, Any]) -> None:
    """Refuse a result whose numbers are not all finite: ``values`` maps each quantity's
    name (units in the name) to a number or an array; ``what`` says whose they are (e.g.
    ``"the summary of engine '4chn15'"``). A number that should exist and does not is an
    error, never a NaN or an infinity in JSON or CSV."""
    for key, value in values.items():
        a = np.asarray(value, dtype=np.float64)
        bad = ~np.isfinite(a)
        if np.any(bad):
            shown = float(np.ravel(a)[np.flatnonzero(np.ravel(bad))[0]])
            raise EngineError(
                f"{what}: {key} is {shown:g}, not a finite number; the engine's inputs are outside what its "
                "equations can carry (check their units)"
            )


# ----------------------------------------------------------------------------- units at the edge
UNIT_SLIPS: dict[str, tuple[tuple[str, float], ...]] = {
    "m": (("mm", 1e-3), ("cm", 1e-2), ("in", 0.0254)),
    "Pa": (("bar", 1e5), ("MPa", 1e6), ("kPa", 1e3)),
    "kg": (("g", 1e-3),),
    "kg·m²": (("kg·cm²", 1e-4), ("kg·mm²", 1e-6), ("g·cm²", 1e-7)),
    "Pa/unit": (("bar/unit", 1e5), ("MPa/unit", 1e6)),
}
"""An SI unit → the units a value in it is often given in by mistake, each with its size
in the SI unit."""


@dataclasses.dataclass(frozen=True)
class EdgeRange:
    """The plausible range of a quantity at the edge (a file): ``lo`` … ``hi`` in ``unit``
    (the magnitude, with ``signed``), ``zero``: 0 passes; ``what`` says it in words with its
    range in the unit people write it in; ``typical``: a value in the middle [unit], which
    ranks the units a slip may be in."""

    lo: float
    hi: float
    unit: str
    what: str
    typical: float
    zero: bool = False
    signed: bool = False


EDGE_RANGES: dict[str, EdgeRange] = {
    "intake_pa": EdgeRange(1e4, 5e5, "Pa", "an absolute intake pressure, 0.1 … 5 bar", 1e5),
    "exhaust_pa": EdgeRange(1e4, 1e6, "Pa", "an absolute exhaust pressure, 0.1 … 10 bar", 1.1e5),
    "crankcase_pa": EdgeRange(1e4, 1e6, "Pa", "an absolute crankcase pressure, 0.1 … 10 bar (or 0)", 1e5, zero=True),
    "peak_pa": EdgeRange(5e5, 3e7, "Pa", "a peak cylinder pressure, 5 … 300 bar", 5e6),
    "cylinder_pa": EdgeRange(1e3, 3e7, "Pa", "an absolute cylinder pressure, 0.01 … 300 bar", 1e6),
    "imep_pa": EdgeRange(
        1e3,
        4e6,
        "Pa",
        "an IMEP of at most 40 bar in magnitude; 0 and below pass, for a motored engine",
        1e6,
        zero=True,
        signed=True,
    ),
    "fmep_pa": EdgeRange(1e3, 2e6, "Pa", "a friction mean effective pressure, 0.01 … 20 bar (or 0)", 1e5, zero=True),
    "pressure_gain_pa": EdgeRange(1e3, 1e10, "Pa/unit", "a pressure sensor's gain in Pa per unit of its signal", 1e6),
    "inertia_kgm2": EdgeRange(1e-7, 1e8, "kg·m²", "an inertia in kg·m²", 0.3),
}
"""A quantity's name → its :class:`EdgeRange`: the ranges of the module doc, for the
engine-file keys and a calibration file's values (:func:`check_edge`)."""

MAX_MASS_PER_BORE3 = 2e5
"""The heaviest piston group, rod or rotating mass of one cylinder per bore³ [kg/m³]: car
engines carry about 1000, the largest two-stroke crosshead engines about 30 000; a mass in
grams gives 10⁶ and more."""
MAX_INERTIA_PER_BORE5 = 1e7
"""The largest crankshaft and flywheel inertia per cylinder per bore⁵ [kg·m²/m⁵]: the
presets carry 3e3 … 3e4, a single cylinder with a heavy flywheel about 3e5; an inertia in
kg·cm² gives 3e7 and more."""
STROKE_PER_BORE = (0.2, 5.0)
"""The plausible stroke/bore ratio [-]: short-stroke racing engines about 0.5, long-stroke
marine two-strokes about 4."""
MAX_ROD_PER_STROKE = 10.0
"""The longest connecting rod in strokes [-]: rods are 1.5 … 2.5 strokes; 10 is room for a
crosshead's."""


def _typical(hint: str) -> float | None:
    """The example value of a :data:`PLAUSIBLE` hint (``"…, e.g. 0.092"``)."""
    import re

    m = re.search(r"e\.g\. (-?[\d.]+(?:e-?\d+)?)", hint)
    return float(m.group(1)) if m else None


def unit_slips(value: float, lo: float, hi: float, unit: str, typical: float | None = None) -> list[tuple[str, float]]:
    """The units of :data:`UNIT_SLIPS` in which ``value`` (its magnitude) lies within
    ``lo`` … ``hi`` [``unit``]: (the unit, the value in ``unit``), the one nearest
    ``typical`` (on a log scale) first."""
    x = abs(float(value))
    out = [(u, x * f) for u, f in UNIT_SLIPS.get(unit, ()) if lo <= x * f <= hi and x > 0]
    if typical:
        out.sort(key=lambda uv: abs(math.log(uv[1] / abs(typical))))
    return out


def _slip_text(value: float, lo: float, hi: float, unit: str, typical: float | None) -> str:
    """``"; it reads as mm (92 mm = 0.092 m): give it in m"`` for a value that fits another
    unit (:func:`unit_slips`), else ``""``."""
    slips = unit_slips(value, lo, hi, unit, typical)
    if not slips:
        return ""
    sign = -1.0 if value < 0 else 1.0
    shown = " or ".join(f"{u} ({value:g} {u} = {sign * v:.4g} {unit})" for u, v in slips[:2])
    return f"; it reads as {shown}: give it in {unit}"


def check_edge(where_: str, value: Any, quantity: str) -> None:
    """Raise :class:`rotor.EngineError` where the number ``value`` of ``quantity`` (a key of
    :data:`EDGE_RANGES`, e.g. ``"intake_pa"``) lies outside its plausible range, naming
    ``where_`` (e.g. ``"[pressure] intake_pa"`` or ``"calibration.json: imep_measured_pa"``)
    and the unit it reads as where one fits (``intake_pa = 0.95``: bar). For the readers of
    files (engine files, calibrations); ``None`` passes."""
    if value is None:
        return
    r = EDGE_RANGES[quantity]
    v = float(value)
    if not math.isfinite(v):
        raise EngineError(f"{where_} = {v:g}: not a finite number ({r.what})")
    if v == 0 and r.zero:
        return
    mag = abs(v) if r.signed else v
    if r.lo <= mag <= r.hi:
        return
    shown = f"{r.lo:g} … {r.hi:g} {r.unit}" if not r.signed else f"±({r.lo:g} … {r.hi:g}) {r.unit}"
    raise EngineError(
        f"{where_} = {v:g} lies outside the plausible {shown} ({r.what})" + _slip_text(v, r.lo, r.hi, r.unit, r.typical)
    )


def check_pressure_table(where_: str, values: Any) -> None:
    """Raise :class:`rotor.EngineError` where a cylinder-pressure trace ``values`` [Pa]
    peaks outside 5 … 300 bar or has a point outside 0.01 … 300 bar, naming the unit it
    reads as (a table in MPa or bar)."""
    p = np.asarray(values, dtype=np.float64).reshape(-1)
    if p.size == 0:
        return
    peak = float(np.max(p))
    check_edge(f"{where_}: its peak", peak, "peak_pa")
    low = float(np.min(p))
    check_edge(f"{where_}: its lowest point", low, "cylinder_pa")


def _ratio_slip(
    what: str, a: tuple[str, float, str, float], b: tuple[str, float, str, float], lo: float, hi: float, typical: float
) -> None:
    """Refuse a ratio ``a/b`` of two lengths (or masses, …) outside ``lo`` … ``hi`` (about
    ``typical``), naming which of the two reads as another unit: ``a``, ``b``: (where,
    value, SI unit, a typical value), the unit named only where the value in it lies within
    a factor of 30 of the typical one."""
    (wa, va, _, _), (wb, vb, _, _) = a, b
    if vb <= 0 or va <= 0:
        return
    ratio = va / vb
    if lo <= ratio <= hi:
        return
    fixes = []
    for side, (w, v, u, usual) in (("a", a), ("b", b)):
        for unit, f in UNIT_SLIPS.get(u, ()):
            r = (va * f / vb) if side == "a" else (va / (vb * f))
            if lo <= r <= hi and abs(math.log10(v * f / usual)) < math.log10(30.0):
                fixes.append((abs(math.log(r / typical)), w, v, unit, v * f, u))
    fixes.sort(key=lambda x: x[0])
    hint = ""
    if fixes:
        _, w, v, unit, si, u = fixes[0]
        hint = f"; {w} reads as {unit} ({v:g} {unit} = {si:.4g} {u}): give it in {u}"
    raise EngineError(f"{wa} = {va:g} and {wb} = {vb:g}: {what} is {ratio:.3g} (plausible {lo:g} … {hi:g}){hint}")


def check_engine_file_units(data: dict) -> None:
    """Raise :class:`rotor.EngineError` where an engine file's values (``data``: the parsed
    file, its types already checked) lie outside the ranges of real engines (the module
    doc's "Units at the edge"), naming the key and the unit a value reads as."""
    pressure = data.get("pressure") or {}
    for key in ("intake_pa", "exhaust_pa", "crankcase_pa", "imep_pa"):
        if key in pressure:
            check_edge(where("pressure", key), pressure[key], key)
    if "pressure_pa" in pressure:
        check_pressure_table(where("pressure", "pressure_pa"), pressure["pressure_pa"])
    friction = data.get("friction") or {}
    if "fmep_pa" in friction:
        check_edge(where("friction", "fmep_pa"), friction["fmep_pa"], "fmep_pa")
    g, m = data.get("geometry", {}), data.get("masses", {})
    bore, stroke, rod = (float(g[k]) if k in g else None for k in ("bore_m", "stroke_m", "rod_length_m"))
    if bore and stroke:
        _ratio_slip(
            "the stroke/bore ratio",
            (where("geometry", "stroke_m"), stroke, "m", 0.09),
            (where("geometry", "bore_m"), bore, "m", 0.09),
            *STROKE_PER_BORE,
            1.0,
        )
    if stroke and rod:
        _ratio_slip(
            "the rod/stroke ratio",
            (where("geometry", "rod_length_m"), rod, "m", 0.15),
            (where("geometry", "stroke_m"), stroke, "m", 0.09),
            0.0,
            MAX_ROD_PER_STROKE,
            1.8,
        )
    if bore:
        for key in ("reciprocating_kg", "rotating_kg", "rod_kg", "rod_big_end_kg"):
            if key in m:
                _per_bore(where("masses", key), float(m[key]), bore**3, MAX_MASS_PER_BORE3, "kg", "bore³ [kg/m³]")
        J = (data.get("crankshaft") or {}).get("inertia_kgm2")
        n = data.get("cylinders")
        if J is not None and isinstance(n, int) and n > 0:
            _per_bore(
                where("crankshaft", "inertia_kgm2"),
                float(J),
                n * bore**5,
                MAX_INERTIA_PER_BORE5,
                "kg·m²",
                "cylinders × bore⁵ [kg·m²/m⁵]",
            )
    rod_kg, rod_J = m.get("rod_kg"), m.get("rod_inertia_kgm2")
    if rod_J and rod_kg and rod:
        _per_bore(
            where("masses", "rod_inertia_kgm2"),
            float(rod_J),
            float(rod_kg) * rod**2,
            1.0,
            "kg·m²",
            "rod_kg × rod_length_m²",
        )


def _per_bore(where_: str, value: float, scale: float, limit: float, unit: str, per: str) -> None:
    """Refuse ``value`` [``unit``] over ``limit`` × ``scale`` (a mass per bore³, an inertia
    per bore⁵), naming the unit it reads as."""
    if value <= limit * scale:
        return
    slips = [(u, value * f) for u, f in UNIT_SLIPS[unit] if value * f <= limit * scale]
    hint = (
        f"; it reads as {slips[0][0]} ({value:g} {slips[0][0]} = {slips[0][1]:.4g} {unit}): give it in {unit}"
        if slips
        else ""
    )
    raise EngineError(
        f"{where_} = {value:g} is {value / scale:.3g} × {per}, over the {limit:g} of any piston engine{hint}"
    )


def check_inertia_kgm2(where_: str, value: Any, *, bore_m: float | None = None, cylinders: int = 1) -> None:
    """Raise :class:`rotor.EngineError` where a crankshaft inertia ``value`` [kg·m²] (a
    calibration's) lies outside :data:`EDGE_RANGES` ``"inertia_kgm2"``, or, with the
    engine's ``bore_m`` [m] and ``cylinders``, over :data:`MAX_INERTIA_PER_BORE5` ×
    cylinders × bore⁵, naming the unit it reads as (kg·cm²)."""
    check_edge(where_, value, "inertia_kgm2")
    if bore_m is not None and float(bore_m) > 0 and cylinders > 0:
        _per_bore(
            where_,
            float(value),
            cylinders * float(bore_m) ** 5,
            MAX_INERTIA_PER_BORE5,
            "kg·m²",
            "cylinders × bore⁵ [kg·m²/m⁵]",
        )
