"""A recording's crank angle: time and speed as functions of the wheel angle.

From tooth edges (:func:`tooth_angle`): the edges as read and placed on the wheel
(:func:`rotor.logs.track.read_track`, repairs where the pattern proves how; each in
``track.repairs`` and a note), each edge's angle corrected by the wheel's tooth-spacing
errors (measured by a wheel file, estimated from the log, given, or none), time as a
function of angle t(φ) a cubic spline through the edges, and the speed ω(φ) = 1/t'(φ).
From a speed log (``rpm``, :func:`speed_angle`): the angle integrated from the speed.
:func:`rotor.analyze_log` samples these on each cycle's grid.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import LogError
from ..units import RPM_PER_RAD_S
from .edges import Edges
from .pattern import repairs_summary
from .plausibility import check_speed_time_base
from .reader import Log
from .track import ChoiceSource, WheelReading
from .wheel import ToothErrors, ToothTrack, estimate_tooth_errors

if TYPE_CHECKING:
    from ..engine.model import Engine
    from .patterns import PatternFit

__all__ = ["CrankAngle", "ToothErrorPlan", "speed_angle", "tooth_angle", "pattern_angle", "firing_run_note"]

TWO_PI = 2.0 * np.pi
SPEED_LOG_MAX_ORDER = 12.0  # the highest order reported of a speed log, by default
MIN_ESTIMATE_TEETH = 12
"""A wheel of fewer teeth a revolution has its tooth errors left alone by the default
``tooth_errors="estimate"`` (too few orders to tell them from the engine's; a note says so)."""
SPEED_LOG_TEETH = 60  # a speed log's grid by default as for a wheel of this many teeth


@dataclasses.dataclass(frozen=True)
class CrankAngle:
    """Time and speed as functions of the wheel angle φ [rad] over ``phi_lo`` … ``phi_hi``:
    ``t_of`` (t(φ) [s]), ``omega_of`` (ω(φ) [rad/s]), ``phi_of`` (φ(t)); ``teeth`` of the
    wheel (None for a speed log), ``track``, ``edges``, ``reading`` as read (None for a
    speed log), ``tooth_errors`` applied (or None) and ``tooth_errors_asked`` (the
    argument as resolved: a wheel file's measured errors replace ``"estimate"``), and the
    notes of the reading."""

    t_of: Callable[[Any], Any]
    omega_of: Callable[[Any], Any]
    phi_of: Callable[[Any], Any]
    phi_lo: float
    phi_hi: float
    teeth: int | None = None
    track: ToothTrack | None = None
    edges: Edges | None = None
    reading: WheelReading | None = None
    tooth_errors: ToothErrors | None = None
    tooth_errors_asked: Any = None
    notes: tuple[str, ...] = ()

    @property
    def default_max_order(self) -> float:
        """The highest order reported by default: a quarter of the teeth per revolution
        (12 for a speed log)."""
        return SPEED_LOG_MAX_ORDER if self.teeth is None else self.teeth / 4

    @property
    def pitch_points(self) -> int:
        """Grid points per revolution by default: two per tooth pitch."""
        return 2 * (SPEED_LOG_TEETH if self.teeth is None else self.teeth)


@dataclasses.dataclass(frozen=True)
class ToothErrorPlan:
    """What :func:`tooth_angle` applies: ``tooth_errors`` (``"estimate"``, ``"none"``, None,
    a :class:`rotor.ToothErrors` or a file), and what an estimate needs: ``engine_orders``,
    ``cylinders``, ``strokes``, an ``engine`` whose inertia ripple is taken out (with
    ``tdc_deg``)."""

    tooth_errors: str | os.PathLike | ToothErrors | None
    engine_orders: str | Sequence[int]
    strokes: int
    cylinders: int
    engine: Engine | None
    tdc_deg: float | None


def speed_angle(log: Log, name: str, revs: int) -> CrankAngle:
    """The angle of a speed log (``time``, ``rpm``): integrated from the speed (trapezoids),
    refused where it covers less than a revolution."""
    from scipy.interpolate import CubicSpline, PchipInterpolator

    t = log["time"]
    check_speed_time_base(t, log["rpm"], name)
    omega_s = log["rpm"] / RPM_PER_RAD_S
    phi_s = np.concatenate([[0.0], np.cumsum(0.5 * (omega_s[1:] + omega_s[:-1]) * np.diff(t))])
    angle = CrankAngle(
        t_of=CubicSpline(phi_s, t),
        omega_of=CubicSpline(phi_s, omega_s),
        phi_of=PchipInterpolator(t, phi_s),
        phi_lo=float(phi_s[0]),
        phi_hi=float(phi_s[-1]),
    )
    if angle.phi_hi - angle.phi_lo < TWO_PI:
        raise LogError(
            f"{name}: the speed log covers {np.rad2deg(angle.phi_hi - angle.phi_lo) / 360:.2f} revolutions; "
            f"a cycle needs {revs}"
        )
    return angle


def tooth_angle(reading: WheelReading, name: str, plan: ToothErrorPlan) -> CrankAngle:
    """The angle of the tooth edges placed on the wheel (``reading``), corrected by the tooth
    errors of ``plan``; refused where the edges span less than a cycle."""
    from scipy.interpolate import CubicSpline, PchipInterpolator

    track = reading.track
    revs = plan.strokes // 2
    span_rev = float((track.t.size - 1) / track.wheel.edges_per_rev)
    if span_rev < revs:
        raise LogError(
            f"{name}: the {track.t.size} tooth edges span about {span_rev:.2f} revolutions; a "
            f"{plan.strokes}-stroke cycle needs {revs} (a longer log)"
        )
    te, asked = _tooth_errors(track, name, plan)
    phi_e = te.angles(track) if te is not None else track.nominal_angle
    t_of = CubicSpline(phi_e, track.t)
    dt_dphi = t_of.derivative()

    def omega_of(x):
        return 1.0 / dt_dphi(x)

    return CrankAngle(
        t_of=t_of,
        omega_of=omega_of,
        phi_of=_Lazy(PchipInterpolator, track.t, phi_e),  # built only where a pressure or cam channel needs it
        phi_lo=float(phi_e[0]),
        phi_hi=float(phi_e[-1]),
        teeth=track.wheel.teeth,
        track=track,
        edges=reading.edges,
        reading=reading,
        tooth_errors=te,
        tooth_errors_asked=asked,
        notes=_reading_notes(reading)
        + (
            (
                f"tooth errors not estimated: a wheel of {track.wheel.edges_per_rev} teeth a revolution has "
                f"too few to tell them from the engine's (at least {MIN_ESTIMATE_TEETH})",
            )
            if asked == "none" and plan.tooth_errors == "estimate"
            else ()
        ),
    )


def pattern_angle(fit: PatternFit, name: str, strokes: int, notes: Sequence[str] = ()) -> CrankAngle:
    """The angle of edges read as a catalogue pattern (:func:`rotor.logs.patterns.decode_edges`):
    t(φ) a cubic spline through the kept edges at their pattern angles; refused where they
    span less than a cycle. No tooth-error correction: a pattern's edges sit where its
    description puts them."""
    from scipy.interpolate import CubicSpline, PchipInterpolator

    revs = strokes // 2
    if fit.revolutions < revs:
        raise LogError(
            f"{name}: the edges read as {fit.pattern.name} span {fit.revolutions:.2f} revolutions; a "
            f"{strokes}-stroke cycle needs {revs} (a longer log)"
        )
    t_of = CubicSpline(fit.angle_rad, fit.t)
    dt_dphi = t_of.derivative()

    def omega_of(x):
        return 1.0 / dt_dphi(x)

    per_rev = fit.pattern.edges_per_turn * 360.0 / fit.pattern.period_deg
    return CrankAngle(
        t_of=t_of,
        omega_of=omega_of,
        phi_of=_Lazy(PchipInterpolator, fit.t, fit.angle_rad),
        phi_lo=float(fit.angle_rad[0]),
        phi_hi=float(fit.angle_rad[-1]),
        teeth=max(2, int(round(per_rev))),
        notes=tuple(notes),
    )


def _reading_notes(reading: WheelReading) -> tuple[str, ...]:
    """The reading's notes, the wheel and edge it found (with their evidence), and the
    edges it repaired."""
    notes = list(reading.notes)
    wheel_choice = reading.choice("wheel")
    if wheel_choice is not None and wheel_choice.source is ChoiceSource.FOUND:
        notes.append(wheel_choice.evidence)
    edge_choice = reading.choice("edge")
    if edge_choice is not None and edge_choice.source is ChoiceSource.FOUND:
        notes.append(f"edge: {edge_choice.value} ({edge_choice.evidence})")
    track = reading.track
    if track.repairs:
        notes.append(f"edges repaired to follow the {track.wheel.spec} wheel: {repairs_summary(track.repairs)}")
    return tuple(notes)


def _tooth_errors(track: ToothTrack, name: str, plan: ToothErrorPlan) -> tuple[ToothErrors | None, Any]:
    """The tooth errors to apply, and ``plan.tooth_errors`` as resolved (a wheel file's
    measured tooth angles in place of ``"estimate"``)."""
    tooth_errors = plan.tooth_errors
    w = track.wheel
    if isinstance(tooth_errors, str) and tooth_errors == "estimate" and w.angles_deg is not None:
        measured = np.deg2rad(np.asarray(w.angles_deg)) - w.tooth_angles_rad
        tooth_errors = ToothErrors(w.spec, measured, "measured (the wheel file's tooth angles)")
    if isinstance(tooth_errors, str) and tooth_errors == "estimate" and w.edges_per_rev < MIN_ESTIMATE_TEETH:
        return None, "none"  # too few teeth to tell their errors from the engine's: the note says so
    if isinstance(tooth_errors, str) and tooth_errors == "estimate":
        if plan.engine is not None and plan.tdc_deg is None:
            raise LogError(
                "engine given to take its inertia ripple out of the tooth-error estimate: give tdc_deg=… "
                "as well (the angle from the gap to cylinder 1's TDC [deg])"
            )
        te = estimate_tooth_errors(
            track,
            engine_orders=plan.engine_orders,
            strokes=plan.strokes,
            cylinders=plan.cylinders,
            source=name,
            engine=plan.engine,
            tdc_deg=plan.tdc_deg,
        )
    elif tooth_errors is None or (isinstance(tooth_errors, str) and tooth_errors == "none"):
        te = None
    elif isinstance(tooth_errors, ToothErrors):
        te = tooth_errors
    else:
        te = ToothErrors.load(tooth_errors)
    return te, tooth_errors


class _Lazy:
    """``cls(*args)``, built on its first call."""

    def __init__(self, cls, *args):
        self._make, self._f = (lambda: cls(*args)), None

    def __call__(self, x):
        if self._f is None:
            self._f = self._make()
        return self._f(x)


def firing_run_note(te: ToothErrors, cylinders: int, strokes: int, max_order: float) -> str:
    """What a tooth-error estimate from a firing run leaves out, and what it may cost δ."""
    ks = [k for k in te.engine_orders]
    if ks:
        shown = ", ".join(map(str, ks)) if len(ks) <= 6 else f"{ks[0]}, {ks[1]}, … {ks[-1]}"
        s = (
            f"tooth errors estimated from this firing run: the wheel's errors at orders {shown} were left to the "
            f"engine (a firing run cannot tell them from the engine's fluctuation) and stay in the speed"
        )
        if te.order_rms_rad is not None:
            kk = np.array([k for k in ks if k <= max_order + 1e-9], dtype=float)
            u = 2.0 * te.order_rms_rad * float(np.sqrt(np.sum(kk**2)))
            s += (
                f"; at the other orders the wheel's errors are {np.rad2deg(te.order_rms_rad):.3f}° rms per order, "
                f"which at these would change δ by about ±{u:.2g}"
            )
    else:
        s = "tooth errors estimated from this firing run: no order stood out as the engine's, so none was left to it"
    s += "; a calibration saved from a coast-down or motored run (tooth_errors=FILE) gives the full wheel pattern"
    if cylinders == 1 and not (strokes == 4 and len(ks) > 0):
        s += (
            "; for an engine of several cylinders give cylinders=N, or its fluctuation at the firing "
            "orders may be taken for the wheel's errors"
        )
    return s
