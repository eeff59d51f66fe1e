"""Invariants every speed result must satisfy, checked at the end of every run.

A result that breaks one is not printed as an answer: :func:`check_speed_result` raises
:class:`rotor.SolverError` (a solver outcome, exit code 1 on the command line) with one line
naming the invariant and what to tighten (a smaller ``step_deg``/``grid_deg``, more
``steps_per_cycle``, a tighter ``rtol``, or ``method='time'``).

- time t strictly increasing over the samples;
- the crank angle θ non-decreasing over the samples sampled uniformly in angle, and
  wherever the speed is not negative (a run with ``stop_at_stall=False`` may turn backwards);
- ω, the engine and load torques and dω/dt finite; the kinetic energy ½·I·ω² finite
  (ω² finite: the inertia is checked with the engine);
- ω ≥ 0 on the samples sampled uniformly in angle, and > 0 there where the angle domain
  produced them all (``method`` closed, grid, angle or shooting) unless the run stalled;
- min_rpm ≤ mean_rpm ≤ max_rpm (within rounding);
- the per-cycle figures of a run that kept only its last cycles' samples: cycle times
  increasing, cycle mean speeds finite and positive;
- a steady state: period_s positive and finite; the balancing load or fuel scale and the
  textbook figures finite.

Only the result's public fields and properties are read. Under ``jit``/``vmap``/``grad``
(the arrays are tracers) nothing is checked: no error can be raised on a traced value.

The closed-form steady state's compiled program evaluates the same invariants on its
arrays (:func:`steady_invariants_hold`) and hands back one flag with them: where it is
set, the host has nothing left to check; where it is not, :func:`check_speed_result`
runs and names what is broken.
"""

from __future__ import annotations

from typing import Any, NoReturn

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import SolverError
from ..units import RPM_PER_RAD_S
from .result import SpeedResult

__all__ = ["check_speed_result", "steady_invariants_hold"]

#: relative slack of min ≤ mean ≤ max (rounding of the time-mean speed against the samples)
MEAN_SLACK = 1e-6
#: a decrease of the crank angle [rad] below this is the solver's noise about rest (an
#: engine that does not turn wanders by ~1e-11 rad), not a step backwards
ANGLE_SLACK_RAD = 1e-9


def _traced(x: Any) -> bool:
    return any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(x))


def _remedy(result: SpeedResult) -> str:
    """What to tighten for the method that produced ``result``."""
    method = str(result.method)
    if result.kind == "steady":
        return "solve it again with a smaller grid_deg, or simulate the run with rotor.simulate(..., method='time')"
    if method.endswith("time"):
        return "run it again with a tighter rtol (or a larger step_deg that saves fewer samples)"
    if method.startswith("closed"):
        return "run it again with a smaller grid_deg, or with method='time'"
    if method.startswith("grid"):
        return "run it again with more steps_per_cycle (or a smaller grid_deg), or with method='time'"
    if method.startswith("angle"):
        return "run it again with a tighter rtol, or with method='time'"
    return "run it again with a tighter rtol, a smaller grid_deg, or method='time'"


def _where(result: SpeedResult, theta: np.ndarray, i: int) -> str:
    """Where sample ``i`` lies: the cycle (from 1) and the crank angle within it [deg]."""
    cyc = float(result.cycle_rad)
    th = float(theta[..., i].reshape(-1)[0]) if theta.size else 0.0
    if not np.isfinite(th):
        return f"sample {i + 1}"
    k = int(np.floor(th / cyc + 1e-9))
    return f"cycle {k + 1} at crank angle {np.rad2deg(th - k * cyc):.1f}°"


def _first(mask: np.ndarray) -> int:
    """Index (along the last axis) of the first True of ``mask`` (any batch row)."""
    return int(np.argmax(np.any(mask.reshape(-1, mask.shape[-1]), axis=0)))


def _number(x: Any) -> np.ndarray | None:
    return None if x is None else np.asarray(x, dtype=np.float64)


def check_speed_result(result: SpeedResult) -> None:
    """Raise :class:`rotor.SolverError` (one line) where ``result`` breaks an invariant of
    every run (see :mod:`rotor.dynamics.invariants`); return None where it keeps them all.

    **Arguments:** ``result``: a :class:`rotor.SpeedResult` from :func:`rotor.simulate` or
    :func:`rotor.steady_state` (samples: ``t`` [s], ``theta`` [rad], ``omega`` [rad/s],
    ``accel`` [rad/s²], ``torque`` and ``load_torque`` [N·m]; a steady state's
    ``period_s`` [s], ``load_torque_Nm`` [N·m], ``fuel_scale`` [-]). Nothing is checked
    when its arrays are tracers (under ``jit``, ``vmap`` or ``grad``).
    """
    arrays = (result.t, result.theta, result.omega, result.accel, result.torque, result.load_torque)
    if _traced(arrays) or _traced((result.period_s, result.load_torque_Nm, result.fuel_scale)):
        return
    # one array at a time: jax.device_get's own bookkeeping costs more than the copies
    t, theta, omega, accel, torque, load = (np.asarray(a, dtype=np.float64) for a in arrays)

    def fail(what: str) -> NoReturn:
        kind = "steady state" if result.kind == "steady" else f"run (method {result.method!r})"
        raise SolverError(f"the {kind} breaks an invariant: {what}; the result cannot be trusted: {_remedy(result)}")

    n = t.shape[-1]
    if n == 0 or any(a.shape[-1] != n for a in (theta, omega, accel, torque, load)):
        fail("its sample arrays are empty or of different lengths")
    # every value finite, ω² too, in one pass (a NaN or an infinity anywhere makes the sum one);
    # where it is not, the checks one by one name the first sample (a sum of finite values
    # that overflows passes them all)
    with np.errstate(over="ignore", invalid="ignore"):
        total = sum(float(a.sum()) for a in (t, theta, omega, torque, load, accel)) + float((0.5 * omega * omega).sum())
    if not np.isfinite(total):
        for name, a in (("time", t), ("crank angle", theta)):
            if not np.isfinite(a).all():
                fail(f"the {name} is not finite at {_where(result, theta, _first(~np.isfinite(a)))}")
        for name, a in (
            ("the speed", omega),
            ("the engine torque", torque),
            ("the friction and load torque", load),
            ("the acceleration", accel),
        ):
            if not np.isfinite(a).all():
                fail(f"{name} is not finite at {_where(result, theta, _first(~np.isfinite(a)))}")
        with np.errstate(over="ignore"):
            if not np.isfinite(0.5 * omega * omega).all():
                fail("the kinetic energy overflows (the speed is beyond what float64 can square)")
    if n > 1:
        dt = np.diff(t, axis=-1)
        if not (dt > 0).all():
            fail(f"time does not increase from one sample to the next at {_where(result, theta, _first(dt <= 0))}")
    # the samples sampled uniformly in angle (the periodic cycle of a steady state)
    kept = int(getattr(result, "kept_cycles", result.uniform_cycles))
    m = min(n, max(kept, 0) * int(result.points_per_cycle))
    if m:
        wu = omega[..., :m]
        # a start from rest (the time domain) begins at ω = 0; the angle domain never reaches it
        strict = not result.stalled and str(result.method) in ("closed", "grid", "angle", "shooting")
        low = (wu <= 0) if strict else (wu < 0)
        if low.any():
            sign = "not positive" if strict else "negative"
            fail(f"the speed is {sign} at {_where(result, theta, _first(low))}, in the angle domain")
    if n > 1:
        dth = np.diff(theta, axis=-1)
        # no step back by more than the slack anywhere: none by more than the slack that grows with θ
        if dth.size and dth.min() < -ANGLE_SLACK_RAD:
            forward = (omega[..., :-1] >= 0) & (omega[..., 1:] >= 0)
            back = (dth < -(ANGLE_SLACK_RAD + 1e-12 * np.abs(theta[..., 1:]))) & forward
            if back.any():
                fail(f"the crank angle decreases while the speed is positive at {_where(result, theta, _first(back))}")
    if result.kind == "steady":
        period = _number(result.period_s)
        if period is None or not (np.isfinite(period).all() and (period > 0).all()):
            fail("the period of the cycle is not positive and finite")
        for key, what in (
            ("load_torque_Nm", "the balancing load torque"),
            ("fuel_scale", "the fuel scale"),
            ("excess_work_J", "the textbook excess work"),
            ("textbook_delta", "the textbook δ"),
            ("periodicity_error", "the periodicity error"),
        ):
            v = _number(getattr(result, key, None))
            if v is not None and not np.isfinite(v).all():
                fail(f"{what} is not finite")
    if getattr(result, "cycle_summary", None) is None:  # the extremes of the samples at hand
        lo, hi = (np.asarray(f(omega, axis=-1) * RPM_PER_RAD_S) if omega.size else np.nan for f in (np.min, np.max))
    else:  # of every sample, kept or not
        lo, hi = np.asarray(result.min_rpm, dtype=np.float64), np.asarray(result.max_rpm, dtype=np.float64)
    mean = np.asarray(result.mean_rpm, dtype=np.float64)
    if not (np.isfinite(lo).all() and np.isfinite(mean).all() and np.isfinite(hi).all()):
        fail("the mean, lowest or highest speed is not finite")
    slack = MEAN_SLACK * np.maximum(np.abs(lo), np.abs(hi)) + 1e-300
    if not ((lo <= mean + slack).all() and (mean <= hi + slack).all()):
        fail("the time-mean speed (angle travelled / time taken) lies outside the lowest and highest sampled speed")
    summary = getattr(result, "cycle_summary", None)
    if summary is not None:
        starts = _number(getattr(summary, "t_start_s", None))
        ends = _number(getattr(summary, "t_end_s", None))
        if starts is not None and ends is not None and starts.size:
            if not (np.all(np.isfinite(starts)) and np.all(np.isfinite(ends)) and np.all(ends > starts)):
                fail("a cycle's time does not increase (per-cycle figures of the cycles whose samples were dropped)")
            if starts.size > 1 and not np.all(np.diff(starts) > 0):
                fail("the cycles' start times do not increase (per-cycle figures)")
        means = _number(getattr(summary, "mean_omega", None))
        if means is not None and means.size and not (np.all(np.isfinite(means)) and np.all(means > 0)):
            fail("a cycle's mean speed is not finite and positive (per-cycle figures)")


def steady_invariants_hold(
    t: Any,
    theta: Any,
    omega: Any,
    accel: Any,
    torque: Any,
    load: Any,
    period_s: Any,
    numbers: Any,
    cycle_rad: float,
    omega_range: tuple[Any, Any] | None = None,
) -> jax.Array:
    """Whether a steady state of the angle domain (one periodic cycle, not stalled) surely
    keeps every invariant :func:`check_speed_result` checks, as a JAX bool: computed inside
    the steady state's compiled program, so that the host reads one flag instead of
    checking the arrays again. Where it is False, :func:`check_speed_result` runs on the
    result and names the invariant that is broken.

    **Arguments:** the cycle's samples ``t`` [s], ``theta`` [rad], ``omega`` [rad/s],
    ``accel`` [rad/s²], ``torque`` and ``load`` [N·m] (equal lengths, at least one sample);
    ``period_s`` [s]; ``numbers``: the steady state's balancing load [N·m], fuel scale [-],
    textbook excess work [J] and textbook δ [-]; ``cycle_rad``: the cycle [rad];
    ``omega_range``: the lowest and highest sample of ``omega`` where the caller has them
    [rad/s] (else found here).

    Never looser than the host's checks, stricter where that is cheaper: every value finite
    (ω² too; their sum finite), time strictly increasing, ω > 0, the crank angle never back
    by more than :data:`ANGLE_SLACK_RAD`, the period positive, and min ≤ mean ≤ max with
    half the host's slack (rounding that differs between the program and NumPy cannot let a
    result through that the host would refuse)."""
    # every value finite, ω² too: their sum is finite only where each is (a sum of finite
    # values that overflows fails the screen, and the host's checks decide); few reductions,
    # each a pass over the samples
    total = jnp.sum(t + theta + omega + accel + torque + load + 0.5 * omega * omega) + period_s + sum(numbers)
    steps = (t[1:] > t[:-1]) & (theta[1:] - theta[:-1] >= -ANGLE_SLACK_RAD) & (omega[1:] > 0)
    ok = jnp.isfinite(total) & jnp.all(steps) & (omega[0] > 0) & (period_s > 0)
    lowest, highest = (jnp.min(omega), jnp.max(omega)) if omega_range is None else omega_range
    lo, hi = lowest * RPM_PER_RAD_S, highest * RPM_PER_RAD_S
    mean = cycle_rad / period_s * RPM_PER_RAD_S
    slack = 0.5 * MEAN_SLACK * jnp.maximum(jnp.abs(lo), jnp.abs(hi))
    return ok & (lo <= mean + slack) & (mean <= hi + slack)
