"""Charge scaling: the engine file's cycle scaled as a whole until it explains the speed.

A throttled spark-ignition engine changes its load by the intake pressure, and the whole
cylinder pressure (compression and combustion) scales with the trapped charge;
:func:`rotor.identify` scales only the combustion part of the engine file's cycle (a
diesel's way). :func:`fit_charge` therefore scales the file's Wiebe cycle as a whole
(intake pressure and IMEP by one factor σ, :meth:`rotor.WiebeCycle.scale_charge`) and
iterates σ (a secant iteration on log σ, within :data:`SIGMA_RANGE`) until the firings'
mean combustion scale is 1. ``scaling="none"`` keeps the file's cycle (diesels, or a
table pressure): one identification.

A record without firing (a coast-down, a fuel cut: the firings' mean combustion scale
below the misfire floor, :data:`rotor.diagnostics.misfire.FLOOR_SCALE`) stops the
iteration with σ kept, and :attr:`ChargeFit.no_firing` says so.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import equinox as eqx
import numpy as np

from ..errors import EngineError
from .identification import NO_FIRING_NOTE, Identification
from .misfire import FLOOR_SCALE

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = ["ChargeFit", "fit_charge", "check_scaling", "scaled", "mean_scale", "SCALINGS", "SIGMA_RANGE"]

SCALINGS = ("charge", "none")
SIGMA_RANGE = (0.05, 5.0)  # the charge scale's physical range: intake pressure × σ (a deep throttle … a big boost)
SETTLED = 1e-3  # |log of the mean combustion scale| at which σ has settled


def scaled(engine: Engine, sigma: float) -> Engine:
    """The engine with its pressure's whole charge scaled by σ (:meth:`scale_charge`)."""
    return eqx.tree_at(lambda e: e.pressure, engine, engine.pressure.scale_charge(sigma))


def check_scaling(scaling: str, engine: Engine, hint: str = "") -> None:
    """Raise :class:`rotor.EngineError` unless ``scaling`` is one of :data:`SCALINGS` and,
    for ``"charge"``, the engine's pressure can be charge-scaled (``hint`` ends that message)."""
    if scaling not in SCALINGS:
        raise EngineError(f"scaling={scaling!r}: one of {', '.join(SCALINGS)}", argument="scaling")
    if scaling == "charge" and not engine.pressure.charge_scalable:
        raise EngineError(
            f"scaling='charge' scales a Wiebe cycle (intake_pa, imep_pa); engine {engine.name!r} has "
            f"{type(engine.pressure).__name__}{hint}",
            argument="scaling",
        )


def mean_scale(ident: Identification) -> float:
    """The mean combustion scale of the normal identified firings (of all identified ones
    where every one is a misfire)."""
    ok = ident.identified & ~ident.misfire
    if not ok.any():
        ok = ident.identified
    return float(np.mean(ident.scale[ok]))


@dataclasses.dataclass(frozen=True)
class ChargeFit:
    """What :func:`fit_charge` found: the identification at σ, σ itself [-], the
    identifications it took, whether the record holds no firing, and its notes."""

    identification: Identification
    sigma: float
    iterations: int
    no_firing: bool
    notes: tuple[str, ...] = ()


def fit_charge(
    engine: Engine,
    speed: Any,
    scaling: str,
    sigma: float,
    max_iterations: int,
    identify_kwargs: dict,
) -> ChargeFit:
    """Identify ``speed`` on ``engine`` with its charge scaled by σ (``scaling="charge"``,
    from ``sigma``, at most ``max_iterations`` identifications), or as it is
    (``scaling="none"``); ``identify_kwargs`` go to :func:`rotor.identify`."""
    if scaling != "charge":
        return _unscaled(engine, speed, identify_kwargs)
    try:
        return _iterate(engine, speed, min(max(sigma, SIGMA_RANGE[0]), SIGMA_RANGE[1]), max_iterations, identify_kwargs)
    except ArithmeticError as e:
        raise EngineError(
            f"scaling='charge': the charge-scale iteration failed ({e}); try scaling='none'", argument="scaling"
        ) from None


def _unscaled(engine, speed, identify_kwargs) -> ChargeFit:
    from .identification import identify  # looked up at each call

    ident = identify(engine, speed, **identify_kwargs)
    notes: tuple[str, ...] = ()
    no_firing = False
    if ident.identified.any() and not mean_scale(ident) > FLOOR_SCALE:
        no_firing = True
        if NO_FIRING_NOTE not in ident.notes:
            notes = (
                f"no firing (mean combustion scale below the misfire floor {FLOOR_SCALE:g}): every firing a misfire",
            )
    return ChargeFit(ident, 1.0, 0, no_firing, notes)


def _iterate(engine, speed, sigma, max_iterations, identify_kwargs) -> ChargeFit:
    """The secant iteration on log σ towards a mean combustion scale of 1."""
    from .identification import identify

    lo, hi = (math.log(v) for v in SIGMA_RANGE)
    xa = math.log(sigma)
    ident = identify(scaled(engine, sigma), speed, **identify_kwargs)
    iters = 1
    ma = mean_scale(ident)
    if not (math.isfinite(ma) and ma > FLOOR_SCALE):
        note = (
            f"charge scaling stopped: no firing (mean combustion scale {ma:.3f}, below the misfire "
            f"floor {FLOOR_SCALE:g}): every firing a misfire, σ kept at {sigma:.4g}"
        )
        return ChargeFit(ident, sigma, iters, True, (note,))
    ga = math.log(ma)
    xb = min(max(xa + ga, lo), hi)
    while abs(ga) > SETTLED and iters < max_iterations and xb != xa:
        idb = identify(scaled(engine, math.exp(xb)), speed, **identify_kwargs)
        iters += 1
        mb = mean_scale(idb)
        if not (math.isfinite(mb) and mb > FLOOR_SCALE):
            break  # keep the last σ with a firing
        gb = math.log(mb)
        xn = xb - gb * (xb - xa) / (gb - ga) if gb != ga else xb
        xa, ga, ident = xb, gb, idb
        xb = min(max(xn, lo), hi)
    sigma = math.exp(xa)
    notes: tuple[str, ...] = ()
    if abs(ga) > SETTLED:
        at = " (at the bound of its range)" if xb in (lo, hi) or xa in (lo, hi) else ""
        notes = (
            f"the charge scale did not settle in {iters} identification{'s' if iters != 1 else ''}{at} (σ {sigma:.4g}, "
            f"mean combustion scale {math.exp(ga):.3f})",
        )
    return ChargeFit(ident, sigma, iters, False, notes)
