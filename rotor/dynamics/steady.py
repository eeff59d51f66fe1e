"""The periodic steady state: one cycle of crank speed that repeats itself exactly.

Found directly, never by integrating until transients die:

- with losses a + c·ω² (friction without its speed-linear term; no load, a constant
  load or a propeller law) the cycle is linear in the kinetic energy E (see
  :mod:`rotor.dynamics.equation`), E(θ) = α(θ)·E₀ + β(θ) once the periodicity condition has
  fixed the balancing load or fuel; the mean-speed condition is one scalar equation in E₀,
  solved by Newton's method (optimistix) on log(E₀ − E*), E* the smallest E₀ that keeps
  E > 0 over the cycle (``method="closed"``);
- otherwise the cycle map of the angle-domain ODE (diffrax) is made periodic at the
  required mean speed by a two-dimensional Newton iteration (``method="shooting"``),
  started from the closed-form solution of the linearised losses.

Balance: with no load, the load torque is set to the engine's cycle-mean torque minus
friction (``result.load_torque_Nm``, and the summary says so); with a load given (a
constant one or one that depends on speed) the load is carried as given: the fuelling is
scaled until the engine's mean torque meets it (``result.fuel_scale``, 1 = the engine
file's pressure). A given load is never replaced. The result states both, the load
carried (``load_torque_Nm``) and the fuel scale (``fuel_scale``), and which was solved
(``solved_for``); a fuel scale above 1.2 warns naming the IMEP it implies, one above 10 or
below 0 is refused (:mod:`rotor.dynamics.operating`).

A periodic solution with a given mean speed always exists in theory, but when the
kinetic energy at its minimum is below 10⁻⁴ of its mean (ω_min < 1 % of ω_mean) the
crankshaft practically stops once a cycle: :class:`rotor.NoSteadyStateError` (a solver
outcome, not an input error) says so and where. Under ``jit``/``vmap``/``grad`` the
compiled program raises the same finding when it runs (``eqx.error_if``; under ``vmap``
if any item has none); ``throw=False`` returns the result with ``result.converged`` False
instead, as optimistix's ``throw=``. The arguments are checked there too: a traced NaN,
infinite or implausible speed, engine field, load or fuelling raises when the program runs,
naming it.
"""

from __future__ import annotations

import functools
import time
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..checks import TRACED, TracedChecks, arrays_only, called_from_outside, concrete, guard_number, is_tracer, tracing
from ..cycles import array_module, cycle_delta, extreme_index
from ..engine.friction import Friction
from ..engine.model import Engine, guard_engine, require_engine
from ..engine.plausible import PLAUSIBLE, guard_fields, what_it_is
from ..errors import EngineError, NoSteadyStateError, SolverError
from ..programs import kept_program
from ..units import RPM_PER_RAD_S
from .crank_train import (
    COL_COMBUSTION,
    COL_I,
    COL_K,
    COL_MOTORED,
    checked_train,
    grid_points,
    shift_inertia,
)
from .equation import (
    Scene,
    friction_coefficients,
    grid_run,
    hermite_cumulative,
    hermite_sum,
    is_zero,
    linear_cycle,
    linear_losses,
    linear_parts,
    quadratic_losses,
    wrap_periodic,
)
from .invariants import check_speed_result, steady_invariants_hold
from .loads import Load, guard_load
from .operating import FUEL_SCALE_MAX, FUEL_SCALE_WARN, check_fuel_scale
from .prepared import PreparedEngine, checked_reference
from .result import SpeedResult, periodic_extremes

__all__ = ["steady_state"]

STOP_FRACTION = 1e-4  # E_min / E_mean below which the crankshaft is taken to stop


_RPM_RANGE = PLAUSIBLE[("operating", "rpm")][:2]


def checked_rpm(rpm: Any, checks: TracedChecks | None, what: str = "rpm") -> Any:
    """``rpm`` [rpm] checked: a real number (else a :class:`TypeError` naming ``what``),
    one speed, finite and within the plausible range of ``[operating] rpm`` (else a
    :class:`rotor.EngineError`). A traced speed is checked when the program runs where
    ``checks`` records the caller's traced checks (:func:`rotor.checks.guard_number`)."""
    lo, hi = _RPM_RANGE
    if type(rpm) in (float, int, np.float64) and lo <= rpm <= hi:  # the usual number (NaN fails here)
        return rpm
    if is_tracer(rpm):
        if np.dtype(rpm.dtype).kind not in "iuf":
            raise TypeError(f"{what}: expected a real number [rpm], got a traced {rpm.dtype} value")
        if rpm.ndim:
            raise EngineError(
                f"{what}: one speed per call [rpm], got a traced array of shape {rpm.shape}; jax.vmap over the "
                "speeds, or rotor.steady_sweep"
            )
        if checks is None:  # rotor's own call: its solver judges the speeds it tries
            return rpm
        return guard_number(rpm, what, lo, hi, unit="rpm", expected="a time-mean crank speed", checks=checks)
    r = None
    if not isinstance(rpm, (bool, np.bool_, str, bytes)) and rpm is not None:
        try:
            r = np.asarray(rpm)  # one copy of a device number
        except (TypeError, ValueError):
            r = None
    if r is None or r.dtype.kind not in "iuf":
        raise TypeError(f"{what}: expected a real number [rpm], e.g. 1250, got {what_it_is(rpm)}")
    r = r.astype(np.float64)
    if r.ndim:
        raise EngineError(
            f"{what} = {rpm!r:.60}: one speed per call [rpm]; jax.vmap over the speeds, or rotor.steady_sweep"
        )
    if not (np.isfinite(r) and lo <= r <= hi):
        raise EngineError(f"{what} = {rpm!r}: must be a positive, finite speed between {lo:g} and {hi:g} rpm")
    return rpm


def _checked_scale(imep_scale: Any, cylinders: int, balance: str, checks: TracedChecks | None) -> Any:
    """``imep_scale`` checked: real numbers (else a :class:`TypeError`), one or one per
    cylinder (else a :class:`rotor.EngineError`); traced values (recorded in ``checks``): finite
    and 0 … :data:`rotor.dynamics.operating.FUEL_SCALE_MAX` with no load (the fuel scale
    given), finite and not negative with one (a pattern the fuelling found multiplies),
    when the program runs. Concrete values are judged by the caller."""
    if isinstance(imep_scale, (float, int)) and not isinstance(imep_scale, bool) and balance == "load":
        return imep_scale  # the fuel scale given: refused or warned about by check_fuel_scale
    if is_tracer(imep_scale):
        dtype, shape = imep_scale.dtype, imep_scale.shape
    else:
        if isinstance(imep_scale, (bool, np.bool_, str, bytes)) or imep_scale is None:
            raise TypeError(f"imep_scale: expected a number or one per cylinder [-], got {what_it_is(imep_scale)}")
        try:
            a = np.asarray(imep_scale)
        except (TypeError, ValueError):
            raise TypeError(
                f"imep_scale: expected a number or one per cylinder [-], got {what_it_is(imep_scale)}"
            ) from None
        dtype, shape = a.dtype, a.shape
    if not (np.issubdtype(dtype, np.floating) or np.issubdtype(dtype, np.integer)):
        raise TypeError(f"imep_scale: expected real numbers [-], got {dtype} values")
    if shape not in ((), (1,), (cylinders,)):
        raise EngineError(
            f"imep_scale: one combustion scale for all cylinders or one per cylinder ({cylinders}) [-], "
            f"got shape {shape}"
        )
    if not is_tracer(imep_scale):
        a = np.asarray(imep_scale, dtype=np.float64)
        if balance == "fuel" and not (np.all(np.isfinite(a)) and np.all(a >= 0)):
            raise EngineError(f"imep_scale = {a.tolist()}: combustion scales must be finite and not negative [-]")
        return imep_scale
    if checks is None:
        return imep_scale
    hi = FUEL_SCALE_MAX if balance == "load" else np.inf
    return guard_number(
        imep_scale, "imep_scale", 0.0, hi, expected="the combustion scale, 1 = the engine file's", checks=checks
    )


def _resolved(engine: Any, checks: TracedChecks | None) -> tuple[PreparedEngine | None, Engine]:
    """The prepared engine (or None) and the :class:`rotor.Engine` of :func:`steady_state`'s
    ``engine`` (a :class:`TypeError` for anything else), their traced fields recorded in
    ``checks``: a prepared engine's crankshaft and friction (its table inputs are compared
    with those it was prepared from, :func:`rotor.dynamics.prepared.checked_reference`)."""
    if isinstance(engine, PreparedEngine):
        prepared = engine
        if checks is not None:
            guarded_engine = guard_engine(prepared.engine, ("crankshaft", "friction"), checks)
            prepared = eqx.tree_at(lambda p: p.engine, prepared, guarded_engine)
        return prepared, prepared.engine
    engine = require_engine(engine, "steady_state(engine)")
    return None, guard_engine(engine, checks=checks) if checks is not None else engine


def _checked_arguments(
    load: Any, friction: Any, imep_scale: Any, throw: Any, cylinders: int, checks: TracedChecks | None
) -> tuple:
    """:func:`steady_state`'s ``load``, ``friction``, ``imep_scale`` and ``throw`` checked
    (a :class:`TypeError` naming the argument for the wrong type; :func:`_checked_scale`);
    their traced fields recorded in ``checks`` (a caller's traced values). Returns the
    load, friction and fuelling to use."""
    if load is not None and not isinstance(load, Load):
        raise TypeError(
            f"steady_state(load): expected a rotor load (e.g. rotor.ConstantLoad) or None, got {what_it_is(load)}"
        )
    if friction is not None and friction is not False and not isinstance(friction, Friction):
        raise TypeError(f"steady_state(friction): expected a rotor.Friction, None or False, got {what_it_is(friction)}")
    if not isinstance(throw, (bool, np.bool_)):
        raise TypeError(f"steady_state(throw): expected True or False, got {what_it_is(throw)}")
    imep_scale = _checked_scale(imep_scale, cylinders, "load" if load is None else "fuel", checks)
    if checks is not None:
        load = guard_load(load, checks)
        friction = guard_fields(friction, checks) if isinstance(friction, Friction) else friction
    return load, friction, imep_scale


NO_STEADY_STATE_TRACED = (
    "no steady state: the kinetic energy would reach zero within the cycle (the crankshaft stops once a cycle), "
    "or the balancing load or fuel scale is not finite, at values traced under jax.jit, vmap or grad "
    "(rotor.NoSteadyStateError for known values); raise the speed or the crankshaft/flywheel inertia "
    "([crankshaft] inertia_kgm2), check that a load is in N·m of the engine's size, or pass throw=False to read "
    "result.converged instead"
)
"""The run-time error of a traced steady state with none (``throw=True``)."""

FUEL_SCALE_TRACED = (
    f"the load needs a fuel scale outside 0 … {FUEL_SCALE_MAX:g} (not an operating point of the engine); check "
    f"the load's units (N·m) and size; {TRACED}"
)
"""The run-time error of a traced steady state whose solved fuel scale is no operating point."""


def _closed_solution(train, s_nodes, a, c, omega_m, balance, rest=None, passes=0):
    """E on the nodes 0…N, t on the nodes, x (load or fuel), whether Newton converged and
    the fixed point's last change: losses a + c·ω² + R(ω) (``rest``,
    :func:`speed_remainder`), R first at the mean speed, then ``passes`` times at the last
    pass's ω(θ) (as :func:`flat_fixed_point`; the last output its estimated error)."""
    r_mean = 0.0 if rest is None else rest(omega_m)
    parts0 = linear_parts(train, s_nodes, a + r_mean, c)
    inertia, dinertia, F, dF, G, dG = parts0
    v, d = wrap_periodic(train.values), wrap_periodic(train.slopes)
    comb = jnp.sum(s_nodes * v[:, COL_COMBUSTION:], axis=1)
    dcomb = jnp.sum(s_nodes * d[:, COL_COMBUSTION:], axis=1)
    if balance == "load":
        F0, dF0, F1, dF1 = F, dF, -jnp.ones_like(F), jnp.zeros_like(F)
    else:
        F0, dF0, F1, dF1 = F - comb, dF - dcomb, comb, dcomb
    h = train.step_rad
    phi = jnp.exp(-hermite_cumulative(G, dG, h))
    Q1 = hermite_cumulative(F1 / phi, (dF1 + F1 * G) / phi, h)
    # periodicity: Φ_N·(E0 + Q0_N + x·Q1_N) = E0  →  x = (E0·(1/Φ_N − 1) − Q0_N)/Q1_N
    p = 1.0 / phi[-1] - 1.0
    alpha = phi * (1.0 + p * Q1 / Q1[-1])
    e_ref = 0.5 * train.mean_inertia * omega_m**2
    period = train.cycle_rad / omega_m
    i_ratio = dinertia / inertia
    x1 = p / Q1[-1]  # x = x0 + x1·E0
    dE_a = x1 * F1 - G * alpha

    def solve(F0, dF0, eta0):
        Q0 = hermite_cumulative(F0 / phi, (dF0 + F0 * G) / phi, h)
        beta = phi * (Q0 - Q0[-1] * Q1 / Q1[-1])
        e_star = jnp.max(jnp.where(alpha > 0, -beta / alpha, -jnp.inf))
        e_star = jax.lax.stop_gradient(jnp.maximum(e_star, 0.0)) + 0.0 * e_star
        # E and dE/dθ = F − G·E are affine in E0 too (x is): only the time integral is nonlinear
        x0 = -Q0[-1] / Q1[-1]
        dE_b = F0 + x0 * F1 - G * beta

        def period_of(E0):
            E = alpha * E0 + beta
            omega = jnp.sqrt(2 * jnp.maximum(E, 1e-300) / inertia)
            r = 1.0 / omega
            dr = -0.5 * r * ((dE_a * E0 + dE_b) / jnp.maximum(E, 1e-300) - i_ratio)
            return hermite_sum(r, dr, h)

        def residual(eta):
            return jnp.log(period_of(e_star + e_ref * jnp.exp(eta)) / period)

        if eta0 is None:
            eta0 = jnp.log(jnp.maximum(e_ref - e_star, 1e-6 * e_ref) / e_ref)
        eta, ok = scalar_newton(residual, eta0)
        E0 = e_star + e_ref * jnp.exp(eta)
        return E0, x0 + x1 * E0, alpha * E0 + beta, (dE_a * E0 + dE_b), eta, ok

    E0, x, E, dE, eta, ok = solve(F0, dF0, None)
    error = jnp.zeros(())
    if rest is not None and passes:
        changes = []
        for _ in range(passes):
            omega, domega = speed_of_energy(E, dE, 1.0 / inertia, dinertia)
            X, dX = jax.jvp(rest, (omega,), (domega,))
            E_last = E
            E0, x, E, dE, eta, ok = solve(F0 + r_mean - X, dF0 - dX, eta)
            changes.append(jnp.max(jnp.abs(E - E_last)) / jnp.mean(E_last))
        F0, dF0 = F0 + r_mean - X, dF0 - dX
        error = _estimated_error(changes)
    parts = (inertia, dinertia, F0 + x * F1, dF0 + x * dF1, G, dG)
    E, omega, t, _ = linear_cycle(train, parts, E0, 0.0)
    return E, t, x, ok, error


def scalar_newton(residual: Any, x0: Any, tol: float = 1e-14, max_steps: int = 60) -> tuple[Any, Any]:
    """Newton's method on a scalar ``residual(x) = 0`` from ``x0``: a ``lax.while_loop``
    with the derivative by forward-mode differentiation (one pass per step), stopped when
    a step is below ``tol``·(1 + |x|). One more step, outside the loop, makes the root
    differentiable by the implicit function theorem: its derivative is divided by the
    (constant) slope, dx/dp = −(∂r/∂p)/(∂r/∂x). Returns the root and whether it is one
    (finite, |r| < 1e-8 before the last step, which then leaves an error of order r²)."""

    def cond(state):
        x, step, i = state
        return (jnp.abs(step) > tol * (1.0 + jnp.abs(x))) & (i < max_steps) & jnp.isfinite(step)

    def body(state):
        x, _, i = state
        r, dr = jax.jvp(residual, (x,), (jnp.ones_like(x),))
        step = r / dr
        return x - step, step, i + 1

    start = jax.lax.stop_gradient(x0)
    x, _, _ = jax.lax.while_loop(cond, body, (start, jnp.full_like(start, 1e300), 0))
    x = jax.lax.stop_gradient(x)
    r, dr = jax.jvp(residual, (x,), (jnp.ones_like(x),))
    root = x - r / jax.lax.stop_gradient(dr)
    return root, jnp.isfinite(root) & (jnp.abs(jax.lax.stop_gradient(r)) < 1e-8)


COARSE_NODES = 360  # nodes per cycle of the coarse grid: blocks in which the flat closed form finds ω's extremes


def coarse_stride(points: int) -> int:
    """The largest step in nodes that divides ``points`` and leaves at least
    :data:`COARSE_NODES` nodes per cycle (1: no coarse grid)."""
    for k in range(max(points // COARSE_NODES, 1), 0, -1):
        if points % k == 0:
            return k
    return 1


def flat_balance(train, s, a, balance):
    """The parts of the flat closed form (:func:`_flat_solution`) that depend on the
    tables, the fuelling ``s`` and the losses ``a`` alone: β(θ) and dE/dθ on the nodes
    0…N, and x (the balancing load [N·m] or the fuel scale [-])."""
    means, B = train.torque_means, train.work
    mot_mean, comb_mean = means[0], means[1:]
    if balance == "load":
        x = mot_mean + comb_mean @ s - a  # the load that balances the mean torque
        w = s
    else:
        x = (a - mot_mean) / (comb_mean @ s)  # the fuelling that carries the load
        w = x * s
    # every product with the whole tables, never a copy of their columns: the motored column
    # and the combustion columns weighted (1, w), the others by zero
    w1 = jnp.concatenate([jnp.ones(1), w])
    column_weights = jnp.concatenate([jnp.zeros(COL_COMBUSTION).at[COL_MOTORED].set(1.0), w])
    beta = B @ w1
    dE = wrap_periodic(train.values @ column_weights - means @ w1)
    return beta, dE, x


# the mean-speed condition expanded in the fluctuations: the coefficient of y^j·x^k in
# (1+y)^(1/2)·(1+x)^(-1/2), binomial series, total order up to 4
_SERIES_ORDER = 4


def _binomial(a: float, n: int) -> float:
    out = 1.0
    for i in range(n):
        out *= (a - i) / (i + 1)
    return out


_SERIES = np.array(
    [
        [_binomial(0.5, j) * _binomial(-0.5, k) if j + k <= _SERIES_ORDER else 0.0 for k in range(_SERIES_ORDER + 1)]
        for j in range(_SERIES_ORDER + 1)
    ]
)


def energy_moments(train, beta):
    """The cycle means of (I − Ī)^j·(β − β̄)^k, j, k = 0…4, and β̄ [J]: what
    :func:`flat_energy`'s first estimate of E(0) needs from the tables and β. They depend
    on the fuelling but on neither the speed nor the crankshaft inertia, so that a sweep
    over those computes them once."""
    d = train.values[:, COL_I] - train.mean_inertia  # the node mean (with the tables)
    beta = beta[: train.points]  # the cycle's nodes (β on 0…N or 0…N−1)
    beta_mean = jnp.mean(beta)
    b = beta - beta_mean
    powers_d = jnp.stack([d**j for j in range(_SERIES_ORDER + 1)])  # (5, N) times (N, 5): no transposed product
    powers_b = jnp.stack([b**k for k in range(_SERIES_ORDER + 1)], axis=1)
    return powers_d @ powers_b / d.shape[0], beta_mean


def mean_energy_estimate(moments, mean_inertia, omega_m):
    """The cycle-mean energy ē = E(0) + β̄ [J] at time-mean speed ``omega_m`` [rad/s] by
    the mean-speed condition ∫dθ/ω = Θ/ω_m expanded to fourth order in the fluctuations
    y = (I − Ī)/(Ī + J) and x = (β − β̄)/ē (``moments``: :func:`energy_moments`,
    ``mean_inertia`` Ī + J [kg·m²]): mean((1+y)^½(1+x)^−½) = ω_m⁻¹·√(2ē/(Ī+J)), solved for
    ē by fixed-point iteration. Its error is of fifth order in the fluctuations: a start for
    Newton's method on the full grid that one step finishes where δ is small."""
    j = np.arange(_SERIES_ORDER + 1)
    scaled = jnp.asarray(_SERIES) * moments / mean_inertia ** j[:, None]
    e = 0.5 * mean_inertia * omega_m**2
    for _ in range(4):  # contracts by the square of the fluctuation each time
        f = jnp.sum(scaled / e ** j[None, :])
        e = 0.5 * mean_inertia * omega_m**2 * f**2
    return e


def flat_energy(train, d_inertia, beta, omega_m, guess=None):
    """E(0) [J] of the flat closed form with β(θ) (:func:`flat_balance`) at time-mean
    speed ``omega_m`` [rad/s], whether Newton converged, and the blocks of
    :func:`coarse_stride` nodes where ω is largest and smallest at the first estimate
    (the caller looks for the extreme node in and beside them).

    Newton's method on η, E(0) = E* + E_ref·e^η (E* the smallest E(0) that keeps E ≥ 0),
    for log(T/T_m) = 0, T = ∫dθ/ω = h·Σ√(I/2E) and T_m = Θ/ω_m on the full grid, from
    the fourth-order estimate of :func:`mean_energy_estimate`, until a step is below 1e-7: one
    pass over the nodes where δ is small (the step then leaves an error of order step²),
    more where the fluctuation is large or near a stall. T′ is summed in the same pass as
    T. The derivatives of E(0) are those of the first pass (the implicit function theorem,
    as in :func:`scalar_newton`), exact where its step is small. ``guess``: a first E(0)
    [J] instead of the estimate (the fixed point on the speed-dependent losses starts each
    pass from the one before)."""
    h = train.step_rad
    inertia = train.values[:, COL_I] + d_inertia  # the N nodes of the cycle (periodic)
    mean_inertia = train.mean_inertia + d_inertia
    e_ref = 0.5 * mean_inertia * omega_m**2
    e_star = jax.lax.stop_gradient(jnp.maximum(jnp.max(-beta), 0.0))
    period = train.cycle_rad / omega_m
    k = coarse_stride(train.points)

    def energy(eta):
        return e_star + e_ref * jnp.exp(eta)

    def fine(eta):  # the residual and its slope in η, in one pass over the nodes
        E = jnp.maximum(energy(eta) + beta[: train.points], 1e-300)
        inv_e = 1.0 / E
        q = 0.5 * inertia * inv_e  # 1/ω²
        r = jnp.sqrt(q)
        T, dT = h * jnp.sum(r), -0.5 * h * jnp.sum(r * inv_e)
        blocks = q.reshape(-1, k)  # where ω is largest and smallest, to a block of k nodes
        extremes = extreme_index(jnp, jnp.min(blocks, axis=1), False), extreme_index(jnp, jnp.max(blocks, axis=1), True)
        return jnp.log(T / period), dT * e_ref * jnp.exp(eta) / T, extremes

    def cond(state):
        eta, step, i = state
        return (jnp.abs(step) > 1e-7 * (1.0 + jnp.abs(eta))) & (i < 60) & jnp.isfinite(step)

    def body(state):
        eta, _, i = state
        res, slope, _ = fine(eta)
        step = res / slope
        return eta - step, step, i + 1

    if guess is None:
        mom, beta_mean = energy_moments(train, beta)  # once per batch under vmap over speed or inertia
        guess = mean_energy_estimate(jax.lax.stop_gradient(mom), jax.lax.stop_gradient(mean_inertia), omega_m)
        guess = guess - beta_mean
    guess = jax.lax.stop_gradient(guess)
    eta_g = jnp.log(jnp.maximum(guess - e_star, 1e-6 * e_ref) / e_ref)
    eta_g = jax.lax.stop_gradient(jnp.where(jnp.isfinite(eta_g), eta_g, 0.0))
    res, slope, extremes = fine(eta_g)  # the derivatives of E(0) come from this pass
    step = jax.lax.stop_gradient(res / slope)
    # usually the step is below 1e-7 and the loop does nothing: the one step from the
    # estimate leaves an error of order step²
    eta, step, _ = jax.lax.while_loop(cond, body, (eta_g - step, step, 0))
    eta = jax.lax.stop_gradient(eta) - (res - jax.lax.stop_gradient(res)) / jax.lax.stop_gradient(slope)
    ok = jnp.isfinite(eta) & (jnp.abs(step) <= 1e-7 * (1.0 + jnp.abs(eta)))
    return energy(eta), ok, extremes


SPEED_TERM_PASSES = 3
"""Passes of the fixed point on the losses that are not a + c·ω² (friction's speed-linear
term, a load's) in :func:`steady_state`: each solves the closed form with them taken at
the last pass's ω(θ). A pass shrinks the change of E(θ) by about 10⁻⁴ (the docs' friction
on 4chn15) … 10⁻² (ten times it, at idle): two leave it near 10⁻¹⁴, and the derivatives
through the passes are as exact. :func:`rotor.steady_sweep` takes two."""

SPEED_TERM_TOL = 1e-12
"""The largest error of E(θ) over its mean, estimated after the last pass as its change
times the ratio of its last two changes (the passes contract geometrically), below which
the fixed point is converged; else the steady state is found by shooting, and says why."""


def speed_remainder(fr, load, a, c):
    """The part R(ω) [N·m] of friction ``fr`` (a, b, c) plus ``load`` that is not ``a`` +
    ``c``·ω² (those go into the closed form as they are), a function of ω [rad/s]."""

    def rest(omega):
        m = fr[0] + fr[1] * omega + fr[2] * omega**2 - a - c * omega**2
        return m if load is None else m + load.torque(omega, 0.0)

    return rest


def _estimated_error(changes):
    """The error left after fixed-point passes whose largest changes were ``changes`` (at
    least two): the last change times the ratio of the last two (a geometric contraction)."""
    last, before = changes[-1], changes[-2]
    return jax.lax.stop_gradient(jnp.where(before > 0, last * last / jnp.where(before > 0, before, 1.0), 0.0))


def speed_of_energy(E, dE, inv_inertia, dinertia):
    """ω [rad/s] and dω/dθ on the nodes from E [J], dE/dθ, 1/I [1/(kg·m²)] and I′:
    ω² = 2E/I, dω/dθ = (dE − ½·I′·ω²)/(I·ω); one reciprocal square root."""
    q = 2 * jnp.maximum(E, 1e-300) * inv_inertia
    r = jax.lax.rsqrt(q)
    return q * r, (dE - 0.5 * dinertia * q) * r * inv_inertia


def flat_fixed_point(train, d_inertia, s, a, omega_m, balance, rest, passes):
    """The flat closed form (:func:`flat_balance`, :func:`flat_energy`) with losses a +
    R(ω) (``rest``: :func:`speed_remainder`, or None: a alone): R first at the mean speed
    ``omega_m`` [rad/s] (a constant, added to ``a``), then ``passes`` (two or more) times
    at the last pass's ω(θ) (its cycle mean added to ``a``, the rest into β by the Hermite
    rule with R′ = dR/dω·dω/dθ). Returns β, dE/dθ and x as :func:`flat_balance`'s, E(0),
    whether Newton converged, the extreme blocks (as :func:`flat_energy`'s) and the
    estimated error of E over its mean (:func:`_estimated_error`; 0 with no passes)."""
    r_mean = 0.0 if rest is None else rest(omega_m)
    if rest is None or passes == 0:
        beta, dE, x = flat_balance(train, s, a + r_mean, balance)
        E0, ok, extremes = flat_energy(train, d_inertia, beta, omega_m)
        return beta, dE, x, E0, ok, extremes, jnp.zeros(())
    # β, dE/dθ and x are affine in the constant loss: their values and slopes once
    one = jnp.ones_like(a + r_mean)
    base, slope = jax.jvp(lambda a_: flat_balance(train, s, a_, balance), (a + r_mean,), (one,))
    (beta, dE, x), h = base, train.step_rad
    E0, ok, extremes = flat_energy(train, d_inertia, beta, omega_m)
    inv_inertia = 1.0 / (wrap_periodic(train.values[:, COL_I]) + d_inertia)
    dinertia = wrap_periodic(train.slopes[:, COL_I])
    E = E0 + beta
    changes = []
    for _ in range(passes):
        omega, domega = speed_of_energy(E, dE, inv_inertia, dinertia)
        X, dX = jax.jvp(rest, (omega,), (domega,))
        X_mean = jnp.mean(X[:-1])
        shift, wave = X_mean - r_mean, X - X_mean  # the cycle mean's change from R(ω_m); the rest
        beta = base[0] + shift * slope[0] - hermite_cumulative(wave, dX, h)
        dE, x = base[1] + shift * slope[1] - wave, base[2] + shift * slope[2]
        E0, ok, extremes = flat_energy(train, d_inertia, beta, omega_m, guess=E0)
        E_last, E = E, E0 + beta
        changes.append(jnp.max(jnp.abs(E - E_last)) / jnp.mean(E_last))
    return beta, dE, x, E0, ok, extremes, _estimated_error(changes)


def _flat_solution(train, d_inertia, s, a, omega_m, balance, rest=None, passes=0):
    """The closed form where nothing in the losses grows with ω² and I(θ) carries the
    reciprocating inertia (G = 2(c − k)/I ≡ 0): E(θ) = E0 + β(θ), β the cumulative
    integral of the torque with its cycle mean balanced, β = B_mot + Σ w_c·B_c, where the
    cumulative integrals B of the motored and of each combustion column are kept with the
    tables (``train.work``). The mean-speed condition ∫dθ/ω = Θ/ω_m starts from its
    fourth-order expansion in the fluctuations (:func:`mean_energy_estimate`) and is
    finished by Newton's method on the full grid (:func:`flat_energy`). ``d_inertia`` [kg·m²] is added to I(θ) (another
    crankshaft inertia than the tables'). Returns E and t on the nodes 0…N, x (load [N·m]
    or fuel scale [-]), whether Newton converged and the fixed point's estimated error
    (:func:`flat_fixed_point`: losses a + ``rest``(ω))."""
    beta, dE, x, E0, ok, _, change = flat_fixed_point(train, d_inertia, s, a, omega_m, balance, rest, passes)
    inertia = wrap_periodic(train.values[:, COL_I]) + d_inertia  # the column alone, not the tables, wrapped
    dinertia = wrap_periodic(train.slopes[:, COL_I])
    E = E0 + beta
    omega = jnp.sqrt(2 * jnp.maximum(E, 0.0) / inertia)
    r = 1.0 / omega
    dr = -0.5 * r * (dE / jnp.maximum(E, 1e-300) - dinertia / inertia)
    return E, hermite_cumulative(r, dr, train.step_rad), x, ok, change


@eqx.filter_jit
def _closed_kernel(train, d_inertia, s, a, c, omega_m, balance, flat, rest=None, passes=0):
    """E, t on the nodes 0…N, x, convergence and the fixed point's estimated error:
    :func:`_flat_solution` where ``flat`` (static: G ≡ 0), else the general closed form
    (:func:`_closed_solution`); losses a + c·ω² + ``rest``(ω) (:func:`speed_remainder`)."""
    if flat:
        return _flat_solution(train, d_inertia, s, a, omega_m, balance, rest, passes)
    train = shift_inertia(train, d_inertia)
    s_nodes = jnp.broadcast_to(s, (train.points + 1, train.cylinders))
    return _closed_solution(train, s_nodes, a, c, omega_m, balance, rest, passes)


@kept_program(static_argnames=("balance", "flat", "passes"))
@functools.partial(jax.jit, static_argnames=("balance", "flat", "passes"))
def _closed_steady(train, numbers, load, balance, flat, passes=0):
    """The whole closed-form steady state in one compiled call, solution and arrays packed
    in one vector (:func:`_pack`; ``jax.jit``: its dispatch is a quarter of
    ``eqx.filter_jit``'s on these arguments). ``numbers``: the crankshaft inertia's change
    [kg·m²], the fuelling per cylinder [-], the friction's (a, b, c), the losses' a [N·m]
    and c [N·m·s²] and the mean speed [rad/s] in one vector (one transfer, not six).
    ``passes`` (static): of the fixed point on the rest of the losses (:func:`speed_remainder`;
    0: they are a + c·ω²)."""
    n = train.cylinders
    d_inertia, s, fr, (a, c, omega_m) = numbers[0], numbers[1 : 1 + n], numbers[1 + n : 4 + n], numbers[4 + n :]
    rest = speed_remainder(fr, load, a, c) if passes else None
    E, t, x, ok, error = _closed_kernel(train, d_inertia, s, a, c, omega_m, balance, flat, rest, passes)
    ok = ok & (error <= SPEED_TERM_TOL)
    scene = _balanced_scene(Scene(train, s[None, :], fr, load), x, balance)
    arrays = _finish_arrays(scene, E[:-1], t[:-1], omega_m, d_inertia)
    # δ and the invariants of every run, with the arrays: the host reads two numbers
    cycle, period = train.cycle_rad, arrays["period_s"]
    high, low, highest, lowest = periodic_extremes(jnp, arrays["omega"])
    arrays["delta"] = cycle_delta(high, low, cycle / period)
    carried = x if balance == "load" else arrays["carried_load"]
    figures = (carried, arrays["fuel_scale"], arrays["excess_work_J"], arrays["textbook_delta"])
    keys = ("theta", "omega", "accel", "torque", "load_torque")
    arrays["invariants_hold"] = steady_invariants_hold(
        t[:-1], *(arrays[k] for k in keys), period, figures, cycle, omega_range=(lowest, highest)
    )
    arrays["fixed_point_error"] = error
    return _pack(t[:-1], x, ok, arrays)


# the closed form's outputs in its packed vector: the rows on the nodes, then the numbers,
# then the IMEP per cylinder
_ROWS = (
    "t",
    "theta",
    "omega",
    "accel",
    "torque",
    "load_torque",
    "gas_torque",
    "reciprocating_torque",
    "inertia_term_torque",
    "total_torque",
)
_NUMBERS = (
    "x",
    "ok",
    "fuel_scale",
    "carried_load",
    "period_s",
    "excess_work_J",
    "textbook_delta",
    "e_ratio",
    "i_min",
    "delta",
    "invariants_hold",
    "fixed_point_error",
)


def _pack(t, x, ok, arrays):
    """t, x, ok and the result's arrays as one float64 vector: the host copies it once
    (a program's every output is a device array of its own, each with its own dispatch,
    wait and copy: 21 of them cost more than the program runs). One concatenation of the
    rows and numbers: the rows are written into it once."""
    parts = {**arrays, "t": t, "x": x, "ok": ok}
    numbers = jnp.stack([jnp.asarray(parts[k], dtype=jnp.float64).reshape(()) for k in _NUMBERS])
    return jnp.concatenate([parts[k] for k in _ROWS] + [numbers, arrays["imep_pa"].ravel()])


def _unpack(pack, points, cylinders):
    """:func:`_pack`'s vector back to t, x, ok and the arrays: NumPy views of one copy
    where it is concrete, slices of it where it is traced. ``points`` and ``cylinders``:
    those of the tables the program solved with."""
    k, m = len(_ROWS), len(_NUMBERS)
    assert pack.shape == (k * points + m + cylinders,), "the packed steady state's layout"
    if isinstance(pack, jax.core.Tracer):  # one slice per part: XLA then drops what the caller does not use
        rows = [pack[i * points : (i + 1) * points] for i in range(k)]
        numbers = [pack[k * points + i] for i in range(m)]
    else:
        pack = np.asarray(pack)
        rows, numbers = pack[: k * points].reshape(k, points), pack[k * points : k * points + m]
    out = dict(zip(_ROWS, rows, strict=True))
    out.update(zip(_NUMBERS, numbers, strict=True))
    out["imep_pa"] = pack[k * points + m :].reshape(1, cylinders)
    out["ok"] = out["ok"] > 0.5
    out["invariants_hold"] = out["invariants_hold"] > 0.5
    out["i_min"] = out["i_min"].astype(np.int64)
    return out.pop("t"), out.pop("x"), out.pop("ok"), out


def _balanced_scene(scene, x, balance):
    """The scene with the balancing load torque (added to friction) or fuel scale applied."""
    if balance == "load":
        return eqx.tree_at(lambda sc: sc.friction, scene, scene.friction.at[0].add(x))
    return eqx.tree_at(lambda sc: sc.scales, scene, scene.scales * x)


def _solve_newton(residual: Any, u0: jnp.ndarray, tol: float = 1e-13, max_steps: int = 30) -> tuple[Any, Any]:
    """Newton's method (optimistix) on a small system ``residual(u) = 0`` from ``u0``.

    Differentiable by the implicit function theorem (``optx.ImplicitAdjoint``): the
    derivative of the root is −J⁻¹·∂r/∂p at the root, whatever the iterations did.
    Returns the root and whether it is one (finite, max |r| < 1e-8). Optimistix is imported
    here, where a kernel is traced: a warm process that runs a kept program never needs it.
    """
    import optimistix as optx

    sol: Any = optx.root_find(
        lambda u, _: residual(u),
        optx.Newton(rtol=tol, atol=tol),
        u0,
        max_steps=max_steps,
        adjoint=optx.ImplicitAdjoint(),
        throw=False,
    )
    u = sol.value
    r = jax.lax.stop_gradient(residual(u))
    ok = jnp.all(jnp.isfinite(u)) & (jnp.max(jnp.abs(r)) < 1e-8)
    return u, ok


@eqx.filter_jit
def _shooting_kernel(scene, omega_m, guess_E0, guess_x, balance):
    """Newton on (E0, x) so that the cycle map is periodic with mean speed ω_m.

    The cycle map is RK4 with one step per table node, so it is a smooth function of
    (E0, x) (no adaptive step choices) and Newton converges to rounding. Returns the
    arrays of the result as well."""
    train = scene.train
    period = train.cycle_rad / omega_m
    e_ref = jax.lax.stop_gradient(guess_E0)
    x_ref = jax.lax.stop_gradient(jnp.where(jnp.abs(guess_x) > 0, jnp.abs(guess_x), 1.0))

    def cycle(u):
        E0 = e_ref * (1 + u[0])
        x = x_ref * u[1]
        (E, t, _), y_end, _ = grid_run(
            _balanced_scene(scene, x, balance), jnp.asarray(0.0), (E0, 0.0, 0.0), 1, train.points, 1, jnp.asarray(0.0)
        )
        return E0, x, E[0], t[0], y_end

    def residual(u):
        E0, _, _, _, y_end = cycle(u)
        return jnp.stack([(y_end[0] - E0) / e_ref, jnp.log(y_end[1] / period)])

    u, ok = _solve_newton(residual, jnp.stack([jnp.zeros_like(guess_x / x_ref), guess_x / x_ref]))
    E0, x, E, t, y_end = cycle(u)
    scene = _balanced_scene(scene, x, balance)
    return x, E, t, y_end[0], ok, _finish_arrays(scene, E, t, omega_m, 0.0)


def _fuelling(imep_scale: Any, n: int, load: Any, train: Any, xp: Any) -> Any:
    """The fuelling of each of the ``n`` cylinders [-] (NumPy or JAX, as ``xp``); a fuel
    scale given with no load is refused or warned about here (:func:`check_fuel_scale`, the
    IMEP named where the tables are concrete)."""
    s: Any
    if isinstance(imep_scale, (float, int)) and not isinstance(imep_scale, bool) and xp is np:  # one number: no array
        s, given = np.full(n, float(imep_scale)), None
        if load is None and not 0.0 <= imep_scale <= FUEL_SCALE_WARN:
            given = s[:1]
    else:
        s = xp.broadcast_to(xp.asarray(imep_scale, dtype=xp.float64), (n,))
        given = concrete(s)
        given = None if given is None or np.all((given >= 0) & (given <= FUEL_SCALE_WARN)) else given
    if given is not None and load is None:
        imep_m, imep_c = concrete(train.imep_motored_pa), concrete(train.imep_combustion_pa)
        for value in np.unique(given):
            check_fuel_scale(float(value), imep_m, imep_c, solved=False)
    return s


def _fixed_point_note(method: str, error: Any, passes: int) -> str | None:
    """None where the closed form's fixed point on the speed-dependent losses converged
    (or is traced: its flag is in ``converged``), else why the steady state is shot instead;
    a :class:`rotor.SolverError` where ``method="closed"`` was asked for."""
    if is_tracer(error) or not error > SPEED_TERM_TOL:
        return None
    why = (
        f"the closed form's fixed point on the speed-dependent losses (friction's speed-linear term, the load's) "
        f"left an estimated error of {float(error):.1e} of the kinetic energy after {passes} passes (they are large "
        "against the engine's inertia torque at this speed)"
    )
    if method == "closed":
        raise SolverError(f"method='closed': {why}; use method='auto' or 'shooting'")
    return f"found by shooting: {why}"


def steady_state(
    engine: Engine | PreparedEngine,
    rpm: ArrayLike | None = None,
    load: Load | None = None,
    *,
    fidelity: str | None = None,
    friction: Friction | Literal[False] | None = None,
    imep_scale: ArrayLike = 1.0,
    method: str = "auto",
    grid_deg: float | None = None,
    throw: bool = True,
) -> SpeedResult:
    """The periodic steady state over one cycle at time-mean speed ``rpm``.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`, or a :class:`rotor.PreparedEngine`
      (:func:`rotor.prepare`: its tables are reused; so are an engine's from an earlier
      call with the same values, :func:`rotor.dynamics.crank_train.train_from_engine`; an
      engine object is checked and its tables found once, :func:`rotor.dynamics.crank_train.checked_train`).
    - ``rpm``: time-mean crank speed (angle travelled / time taken) [rpm]; default the
      engine file's ``[operating] rpm``.
    - ``load``: None (the load torque becomes the engine's mean torque minus friction:
      ``result.load_torque_Nm``), or a load to carry, :class:`rotor.ConstantLoad` [N·m] or
      speed-dependent (:class:`rotor.PolynomialLoad`, :class:`rotor.PropellerLoad`,
      :class:`rotor.TableLoad`): the fuelling is scaled until the engine carries it
      (``result.fuel_scale``); a motored engine (no combustion) cannot, and is refused.
    - ``fidelity``: ``"variable"`` (default; a prepared engine's own), ``"series"``
      (λ-series kinematics), ``"coefficients"`` or ``"constant"`` (see
      :mod:`rotor.dynamics.crank_train`).
    - ``friction``: a :class:`rotor.Friction`, None (the engine file's, if any) or False.
    - ``imep_scale``: combustion scale per cylinder (a number or one per cylinder) [-].
    - ``method``: ``"auto"`` (closed form where the losses allow, else shooting),
      ``"closed"`` or ``"shooting"``.
    - ``grid_deg``: node spacing of the tables and of the result [deg] (default 0.25; a
      prepared engine's own).
    - ``throw``: True (default): where there is no steady state, raise
      (:class:`rotor.NoSteadyStateError`, or under ``jit``/``vmap``/``grad`` an
      ``eqx.error_if`` error when the program runs); False: return the result with
      ``converged`` False instead (as optimistix's ``throw=``), and for an invalid traced
      argument NaN numbers with it.

    Every argument may be traced (``jax.jit``, ``jax.vmap``, ``jax.grad``) and is checked
    when the program runs, as a concrete one is at once: a NaN, infinite or implausible
    speed, engine field, load or fuelling raises a one-line error naming it (all checks in
    one ``eqx.error_if``, whose host callback costs a compiled call about 20 µs on a CPU),
    or with ``throw=False`` gives ``converged`` False and NaN numbers, never a plausible one.

    **Returns:** a :class:`rotor.SpeedResult` over one cycle (``kind="steady"``) with
    ``load_torque_Nm`` [N·m] and ``fuel_scale`` [-] (``solved_for`` says which was
    solved), the torque's parts (``gas_torque``, ``reciprocating_torque``,
    ``inertia_term_torque``, ``total_torque``) [N·m], ``period_s`` [s], ``excess_work_J``
    [J], ``textbook_delta`` [-], ``periodicity_error`` (|E(Θ) − E(0)|/E(0), shooting)
    and ``converged``. Where the closed form solved concrete values, the arrays are
    read-only NumPy arrays and the numbers NumPy scalars (copied from the compiled program
    in one piece); JAX arrays otherwise (the shooting method, or under ``jit``/``vmap``/``grad``).

    **Raises:** :class:`rotor.NoSteadyStateError` (a :class:`rotor.SolverError`) where the
    kinetic energy would reach zero (with ``throw``; under ``jit``/``vmap``/``grad`` the
    program raises its message when it runs). :class:`rotor.SolverError` where the
    solution breaks an invariant of every run (:func:`rotor.dynamics.invariants.check_speed_result`).
    :class:`rotor.EngineError` for impossible arguments, a :class:`TypeError` for
    arguments of the wrong type (an engine's name instead of the engine:
    ``rotor.load_engine(name)`` first), each naming the argument.
    """
    start = time.perf_counter()
    # a caller's traced values: checked when the program runs, all at once (_finish)
    checks = TracedChecks() if called_from_outside() and tracing() else None
    prepared, engine = _resolved(engine, checks)
    if prepared is not None:
        fidelity = prepared.fidelity if fidelity is None else fidelity
        grid_deg = prepared.grid_deg if grid_deg is None else grid_deg
    fidelity = "variable" if fidelity is None else fidelity
    grid_deg = 0.25 if grid_deg is None else grid_deg
    rpm = checked_rpm(engine.operating.rpm if rpm is None else rpm, checks)
    load, friction, imep_scale = _checked_arguments(load, friction, imep_scale, throw, engine.cylinders, checks)
    if load is not None and load.time_dependent:
        raise EngineError(
            "a steady state needs a load that does not change in time; use rotor.simulate for a load step"
        )
    if method not in ("auto", "closed", "shooting"):
        raise EngineError(f"method = {method!r}: a steady state is found by 'auto', 'closed' or 'shooting'")
    points = grid_points(engine.strokes, grid_deg)
    if prepared is not None and (fidelity, points) == (prepared.fidelity, prepared.points):
        # checked when prepared; what may have changed since is checked here
        train = prepared.train
        d_inertia = prepared.engine.crankshaft.inertia_kgm2 - checked_reference(prepared, checks)
    else:
        train = checked_train(engine, fidelity, points)  # checked and kept once per engine object
        d_inertia = np.float64(0.0)
    load = arrays_only(load)  # the engine itself enters no compiled call: its tables and numbers do
    n = engine.cylinders
    xp = array_module(rpm, imep_scale)  # numpy where concrete: no dispatch
    s = _fuelling(imep_scale, n, load, train, xp)
    fr = friction_coefficients(engine, friction)
    omega_m = (np.float64(rpm) if isinstance(rpm, (float, int)) else xp.asarray(rpm, dtype=xp.float64)) / RPM_PER_RAD_S
    balance = "load" if load is None else "fuel"  # a given load is carried, never replaced
    speed_load = None if balance == "load" else load
    lin = linear_losses(speed_load, fr)
    passes = 0 if lin is not None else SPEED_TERM_PASSES  # the rest of the losses by a fixed point
    note = None
    if lin is None:
        lin = quadratic_losses(speed_load, fr)
    if method != "shooting":
        a_lin, c_lin = lin
        flat = is_zero(c_lin) and fidelity != "constant"  # G ≡ 0: E = E0 + β(θ)
        # one number each (a load's one-element array too), the fuelling and friction whole
        xq = array_module(d_inertia, s, fr, a_lin, c_lin, omega_m)
        scalars = (d_inertia, a_lin, c_lin, omega_m)
        if xq is np and all(np.ndim(v) == 0 for v in scalars):  # the usual numbers: no reshaping
            numbers = np.concatenate(((d_inertia,), s, fr, scalars[1:]), dtype=np.float64)
        else:
            parts = ((d_inertia, 1), (s, n), (fr, 3), (a_lin, 1), (c_lin, 1), (omega_m, 1))
            numbers = xq.concatenate([xq.reshape(xq.asarray(v, dtype=xq.float64), (size,)) for v, size in parts])
        pack = _closed_steady(train, numbers, speed_load, balance, flat, passes)
        t, x, ok, arrays = _unpack(pack, points, n)
        _check_combustion(train, balance)
        note = _fixed_point_note(method, arrays.pop("fixed_point_error"), passes)
        if note is None:
            return _finish(
                engine, train, None, t, x, ok, balance, "closed", fidelity, omega_m, start, None, arrays, throw, checks
            )
    _check_combustion(train, balance)
    train = shift_inertia(train, d_inertia)
    # start from the closed form with the losses linearised about ω_m
    a_lin, c_lin = fr[0] + fr[1] * omega_m, fr[2]
    if balance == "fuel":
        assert load is not None  # a given load is what the fuelling is balanced against
        m0 = load.torque(omega_m, 0.0)
        c_l = jax.grad(lambda w: load.torque(w, 0.0))(omega_m) / (2 * omega_m)
        a_lin, c_lin = a_lin + m0 - c_l * omega_m**2, c_lin + c_l
    E_g, _, x_g, _, _ = _closed_kernel(train, 0.0, s, a_lin, c_lin, omega_m, balance, False)
    if balance == "load":
        x_g = x_g + a_lin - fr[0]  # the balancing load on top of the real friction law
    scene = Scene(train, s[None, :], fr, speed_load)
    x, E, t, E_end, ok, arrays = _shooting_kernel(scene, omega_m, E_g[0], x_g, balance)
    return _finish(
        engine, train, E, t, x, ok, balance, "shooting", fidelity, omega_m, start, E_end, arrays, throw, checks, note
    )


def _check_combustion(train, balance):
    if balance != "fuel":
        return
    work = concrete(train.imep_combustion_pa)
    if work is not None and not np.sum(work) > 0:
        raise EngineError(
            "a given load needs a firing engine: the fuelling is scaled to carry it, but this engine's pressure has "
            "no combustion; give no load (load=None) to balance the mean engine torque instead"
        )


def textbook_excess(train, scales, omega_m):
    """The excess work [J] of the textbook total torque at constant speed ``omega_m``
    [rad/s] (Shishkov, "Dinamika dvigatelei" (SUSU 2014) §3.2.12: δ ≈ L_excess/(J·ω²)):
    the largest minus the smallest cumulative work of the gas torque at the fuelling
    ``scales`` [-] plus the reciprocating inertia torque. The cumulative work is linear in
    the fuelling and in ω²: its two parts depend on the tables and the fuelling alone, so
    that a sweep over speed or inertia sums them once."""
    w = train.textbook_work  # (textbook_k, motored, combustion…) summed once with the tables
    work = w @ jnp.concatenate([jnp.reshape(omega_m**2, (1,)), jnp.ones(1), scales])
    return jnp.max(work) - jnp.min(work)


def _no_steady_state(train, balance, omega_m, converged, i_min, x_found):
    """Raise :class:`rotor.NoSteadyStateError` for a solution that did not converge or whose
    balancing load or fuel scale is not finite (concrete values)."""
    # a fuel scale of a million or more and no steady state: a load in the wrong units
    absurd = balance == "fuel" and not np.all(converged) and np.all(np.abs(x_found) >= 1e6)
    if not np.all(np.isfinite(x_found)) or absurd:
        what = "load torque" if balance == "load" else "fuel scale"
        trouble = f"gives no finite speed (it is {float(x_found):.3g})" if absurd else "is not a finite number"
        raise NoSteadyStateError(
            f"no steady state at {float(omega_m * RPM_PER_RAD_S):g} rpm: the periodic solution's balancing "
            f"{what} {trouble}; check that the "
            "load and the fuelling are in units the engine can carry (N·m, a torque of the engine's size)"
        )
    raise NoSteadyStateError(
        f"no steady state at {float(omega_m * RPM_PER_RAD_S):g} rpm: the kinetic energy would reach zero at "
        f"crank angle {float(np.rad2deg(i_min * train.cycle_rad / train.points)):.1f}° of the cycle (the "
        "crankshaft stops once a cycle). Raise the speed or the crankshaft/flywheel inertia ([crankshaft] "
        "inertia_kgm2), or simulate the run with rotor.simulate to see it stall"
    )


@eqx.filter_jit
def _finish_arrays(scene, E, t, omega_m, d_inertia):
    """The result's arrays on the table nodes; ``d_inertia`` [kg·m²] is added to the
    tables' I(θ) (the crankshaft inertia of a prepared engine changed)."""
    train = scene.train
    theta = train.nodes()
    val, der, sc = train.values, train.slopes, scene.scales[0]  # the result lies on the table nodes
    inertia, dinertia = val[:, COL_I] + d_inertia, der[:, COL_I]
    omega = jnp.sqrt(2 * jnp.maximum(E, 0.0) / inertia)
    m_eng = scene.engine_torque(val, sc, omega, 0.0)
    m_loss = scene.loss(omega, t)
    m_ripple = -0.5 * dinertia * omega**2  # the varying inertia's term, −½·I′(θ)·ω²
    accel = (m_eng - m_loss + m_ripple) / inertia
    excess = textbook_excess(train, sc, omega_m)
    dwell = 1.0 / omega  # the time-mean of the load carried (friction apart), where it is a model
    carried = 0.0 if scene.load is None else jnp.sum(scene.load.torque(omega, t) * dwell) / jnp.sum(dwell)
    i_min = extreme_index(jnp, E, False)  # the lowest energy (its first NaN where there is one)
    return {
        "theta": theta,
        "fuel_scale": jnp.mean(sc),
        "carried_load": carried,
        "omega": omega,
        "torque": m_eng,
        "gas_torque": m_eng - val[:, COL_K] * omega**2,
        "reciprocating_torque": train.textbook_k * omega**2,
        "inertia_term_torque": m_ripple,
        "total_torque": m_eng + m_ripple,
        "load_torque": m_loss,
        "accel": accel,
        "imep_pa": (train.imep_motored_pa + sc * train.imep_combustion_pa)[None, :],
        "period_s": train.cycle_rad / omega_m,
        "excess_work_J": excess,
        "textbook_delta": excess / ((train.mean_inertia + d_inertia) * omega_m**2),
        "e_ratio": E[i_min] / jnp.mean(E),
        "i_min": i_min,
    }


def _finish(
    engine, train, E, t, x, ok, balance, method, fidelity, omega_m, start, E_end, arrays, throw, checks, note=None
):
    a = arrays
    checkable = not isinstance(a["e_ratio"], jax.core.Tracer)
    if checkable:  # NumPy where the closed form's packed vector came back; else one transfer
        ok, e_ratio, i_min, x_found = (ok, a["e_ratio"], a["i_min"], x)
        if any(isinstance(v, jax.Array) for v in (ok, e_ratio, i_min, x_found)):
            ok, e_ratio, i_min, x_found = jax.device_get((ok, e_ratio, i_min, x_found))
        converged = np.asarray(ok & np.isfinite(e_ratio) & (e_ratio >= STOP_FRACTION) & np.isfinite(x_found))
        if throw and not converged.all():
            _no_steady_state(train, balance, omega_m, converged, i_min, x_found)
    else:
        converged = ok & jnp.isfinite(a["e_ratio"]) & (a["e_ratio"] >= STOP_FRACTION) & jnp.isfinite(x)
        checks = TracedChecks() if checks is None else checks
        outputs = (t, x, E, E_end, a)
        if throw:  # one check for the arguments and the solution, carried by every output
            more = []
            if balance == "fuel":  # the fuelling found must be an operating point (known values: check_fuel_scale)
                fuel = a["fuel_scale"]
                more.append((converged & ~((fuel >= 0) & (fuel <= FUEL_SCALE_MAX)), FUEL_SCALE_TRACED))
            more.append((~converged, NO_STEADY_STATE_TRACED))
            t, x, E, E_end, a = checks.tie(outputs, more)
        elif checks.items:  # a status instead: an invalid argument gives NaN numbers, converged False
            valid = checks.valid()
            t, x, E, E_end, a = jax.tree_util.tree_map(
                lambda v: jnp.where(valid, v, jnp.nan) if jnp.issubdtype(jnp.result_type(v), jnp.inexact) else v,
                outputs,
            )
            converged = converged & valid
        if balance == "fuel":
            fuel = a["fuel_scale"]
            converged = converged & (fuel >= 0) & (fuel <= FUEL_SCALE_MAX)
    load_carried = x if balance == "load" else a["carried_load"]
    if checkable and balance == "fuel" and bool(np.all(converged)):
        fuel, carried = np.asarray(a["fuel_scale"]), np.asarray(load_carried)
        if fuel.ndim == 0:
            imep_m, imep_c = concrete(train.imep_motored_pa), concrete(train.imep_combustion_pa)
            check_fuel_scale(float(fuel), imep_m, imep_c, solved=True, load_Nm=float(carried))
    result = SpeedResult(
        t=t,
        theta=a["theta"],
        omega=a["omega"],
        accel=a["accel"],
        torque=a["torque"],
        load_torque=a["load_torque"],
        imep_pa=a["imep_pa"],
        method=method,
        fidelity=fidelity,
        kind="steady",
        strokes=engine.strokes,
        cycle_rad=train.cycle_rad,
        points_per_cycle=train.points,
        uniform_cycles=1,
        engine_name=engine.name,
        wall_s=time.perf_counter() - start,
        period_s=a["period_s"],
        load_torque_Nm=load_carried,
        fuel_scale=a["fuel_scale"],
        solved_for="load" if balance == "load" else "fuel_scale",
        gas_torque=a["gas_torque"],
        reciprocating_torque=a["reciprocating_torque"],
        inertia_term_torque=a["inertia_term_torque"],
        total_torque=a["total_torque"],
        excess_work_J=a["excess_work_J"],
        textbook_delta=a["textbook_delta"],
        periodicity_error=None if E_end is None else jnp.abs(E_end - E[0]) / E[0],
        converged=converged,
        note=note,
        _known_delta=(a["omega"], a["period_s"], train.cycle_rad, a["delta"]) if "delta" in a else None,
    )
    # concrete values only (under jit/vmap ``converged`` says it); the closed form's program
    # has checked the invariants already where its flag is set; a result with no steady
    # state (throw=False) is returned as it is, ``converged`` False
    if not (checkable and a.get("invariants_hold", False)) and (throw or not checkable or bool(np.all(converged))):
        check_speed_result(result)
    return result
