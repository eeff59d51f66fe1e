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
file's pressure). A given load is never replaced.

A periodic solution with a given mean speed always exists in theory, but when the
kinetic energy at its minimum is below 10⁻⁴ of its mean (ω_min < 1 % of ω_mean) the
crankshaft practically stops once a cycle: :class:`rotor.NoSteadyStateError` (a solver
outcome, not an input error) says so and where. Under ``jit``/``vmap``/``grad`` no error
can be raised on a traced value: there ``result.converged`` says whether the solution is
usable, and the caller must look at it.
"""

from __future__ import annotations

import time
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import ArrayLike

from ..checks import arrays_only, concrete
from ..engine.friction import Friction
from ..engine.model import Engine
from ..engine.plausible import PLAUSIBLE
from ..errors import EngineError, NoSteadyStateError
from ..units import RPM_PER_RAD_S
from .crank_train import COL_COMBUSTION, COL_MOTORED, check_fidelity, grid_points, train_from_engine
from .equation import (
    Scene,
    count_trace,
    friction_coefficients,
    grid_run,
    hermite_cumulative,
    linear_cycle,
    linear_losses,
    linear_parts,
    wrap_periodic,
)
from .invariants import check_speed_result
from .loads import Load
from .result import SpeedResult

__all__ = ["steady_state"]

STOP_FRACTION = 1e-4  # E_min / E_mean below which the crankshaft is taken to stop


def _check_rpm(rpm, what="rpm"):
    r = concrete(rpm)
    lo, hi, _, _ = PLAUSIBLE[("operating", "rpm")]
    if r is not None and not (r.ndim == 0 and np.isfinite(r) and lo <= r <= hi):
        raise EngineError(f"{what} = {rpm!r}: must be a positive, finite speed between {lo:g} and {hi:g} rpm")


def _closed_solution(train, s_nodes, a, c, omega_m, balance):
    """E on the nodes 0…N, t on the nodes, x (load or fuel), Newton result."""
    parts0 = linear_parts(train, s_nodes, a, c)
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
    Q0 = hermite_cumulative(F0 / phi, (dF0 + F0 * G) / phi, h)
    Q1 = hermite_cumulative(F1 / phi, (dF1 + F1 * G) / phi, h)
    # periodicity: Φ_N·(E0 + Q0_N + x·Q1_N) = E0  →  x = (E0·(1/Φ_N − 1) − Q0_N)/Q1_N
    p = 1.0 / phi[-1] - 1.0
    alpha = phi * (1.0 + p * Q1 / Q1[-1])
    beta = phi * (Q0 - Q0[-1] * Q1 / Q1[-1])
    e_ref = 0.5 * train.mean_inertia * omega_m**2
    e_star = jnp.max(jnp.where(alpha > 0, -beta / alpha, -jnp.inf))
    e_star = jax.lax.stop_gradient(jnp.maximum(e_star, 0.0)) + 0.0 * e_star
    period = train.cycle_rad / omega_m
    # E and dE/dθ = F − G·E are affine in E0 too (x is): only the time integral is nonlinear
    x0, x1 = -Q0[-1] / Q1[-1], p / Q1[-1]  # x = x0 + x1·E0
    dE_a = x1 * F1 - G * alpha
    dE_b = F0 + x0 * F1 - G * beta
    i_ratio = dinertia / inertia

    def period_of(E0):
        E = alpha * E0 + beta
        omega = jnp.sqrt(2 * jnp.maximum(E, 1e-300) / inertia)
        r = 1.0 / omega
        dr = -0.5 * r * ((dE_a * E0 + dE_b) / jnp.maximum(E, 1e-300) - i_ratio)
        return hermite_cumulative(r, dr, h)[-1]

    def residual(eta, _):
        return jnp.log(period_of(e_star + e_ref * jnp.exp(eta)) / period)

    eta0 = jnp.log(jnp.maximum(e_ref - e_star, 1e-6 * e_ref) / e_ref)
    sol = optx.root_find(
        residual,
        optx.Newton(rtol=1e-14, atol=1e-14),
        eta0,
        max_steps=200,
        adjoint=optx.ImplicitAdjoint(),
        throw=False,
    )
    E0 = e_star + e_ref * jnp.exp(sol.value)
    x = x0 + x1 * E0
    parts = (inertia, dinertia, F0 + x * F1, dF0 + x * dF1, G, dG)
    E, omega, t, _ = linear_cycle(train, parts, E0, 0.0)
    return E, t, x, sol.result == optx.RESULTS.successful, Q1[-1]


@eqx.filter_jit
def _closed_kernel(train, s, a, c, omega_m, balance):
    count_trace()
    s_nodes = jnp.broadcast_to(s, (train.points + 1, train.cylinders))
    return _closed_solution(train, s_nodes, a, c, omega_m, balance)


@eqx.filter_jit
def _closed_steady(engine, fidelity, points, s, fr, load, a, c, omega_m, balance):
    """The whole closed-form steady state in one compiled call: tables, solution, arrays."""
    count_trace()
    train = train_from_engine(engine, fidelity, points)
    E, t, x, ok, _ = _closed_kernel(train, s, a, c, omega_m, balance)
    scene = _balanced_scene(Scene(train, s[None, :], fr, load), x, balance)
    return train, scene, E[:-1], t[:-1], x, ok, _finish_arrays(engine, scene, E[:-1], t[:-1], omega_m)


def _balanced_scene(scene, x, balance):
    """The scene with the balancing load torque (added to friction) or fuel scale applied."""
    if balance == "load":
        return eqx.tree_at(lambda sc: sc.friction, scene, scene.friction.at[0].add(x))
    return eqx.tree_at(lambda sc: sc.scales, scene, scene.scales * x)


def _solve_newton(residual: Any, u0: jnp.ndarray, tol: float = 1e-13, max_steps: int = 30) -> tuple[Any, Any]:
    """Newton's method (optimistix) on a small system ``residual(u) = 0`` from ``u0``.

    Differentiable by the implicit function theorem (``optx.ImplicitAdjoint``): the
    derivative of the root is −J⁻¹·∂r/∂p at the root, whatever the iterations did.
    Returns the root and whether it is one (finite, max |r| < 1e-8).
    """
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
def _shooting_kernel(engine, scene, omega_m, guess_E0, guess_x, balance):
    """Newton on (E0, x) so that the cycle map is periodic with mean speed ω_m.

    The cycle map is RK4 with one step per table node, so it is a smooth function of
    (E0, x) (no adaptive step choices) and Newton converges to rounding. Returns the
    arrays of the result as well."""
    count_trace()
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
    return x, scene, E, t, y_end[0], ok, _finish_arrays(engine, scene, E, t, omega_m)


def steady_state(
    engine: Engine,
    rpm: ArrayLike | None = None,
    load: Load | None = None,
    *,
    fidelity: str = "variable",
    friction: Friction | Literal[False] | None = None,
    imep_scale: ArrayLike = 1.0,
    method: str = "auto",
    grid_deg: float = 0.25,
) -> SpeedResult:
    """The periodic steady state over one cycle at time-mean speed ``rpm``.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``rpm``: time-mean crank speed (angle travelled / time taken) [rpm]; default the
      engine file's ``[operating] rpm``.
    - ``load``: None (the load torque becomes the engine's mean torque minus friction:
      ``result.load_torque_Nm``), or a load to carry, :class:`rotor.ConstantLoad` [N·m] or
      speed-dependent (:class:`rotor.PolynomialLoad`, :class:`rotor.PropellerLoad`,
      :class:`rotor.TableLoad`): the fuelling is scaled until the engine carries it
      (``result.fuel_scale``); a motored engine (no combustion) cannot, and is refused.
    - ``fidelity``: ``"variable"`` (default), ``"series"`` (λ-series kinematics),
      ``"coefficients"`` or ``"constant"`` (see :mod:`rotor.dynamics.crank_train`).
    - ``friction``: a :class:`rotor.Friction`, None (the engine file's, if any) or False.
    - ``imep_scale``: combustion scale per cylinder (a number or one per cylinder) [-].
    - ``method``: ``"auto"`` (closed form where the losses allow, else shooting),
      ``"closed"`` or ``"shooting"``.
    - ``grid_deg``: node spacing of the tables and of the result [deg].

    **Returns:** a :class:`rotor.SpeedResult` over one cycle (``kind="steady"``) with
    ``load_torque_Nm`` [N·m] or ``fuel_scale`` [-], ``period_s`` [s], ``excess_work_J``
    [J], ``textbook_delta`` [-], ``periodicity_error`` (|E(Θ) − E(0)|/E(0), shooting)
    and ``converged``.

    **Raises:** :class:`rotor.NoSteadyStateError` (a :class:`rotor.SolverError`) where the
    kinetic energy would reach zero, when the values are concrete; under ``jit``/``vmap``
    the result's ``converged`` is False instead. :class:`rotor.SolverError` where the
    solution breaks an invariant of every run (:func:`rotor.dynamics.invariants.check_speed_result`).
    :class:`rotor.EngineError` for impossible arguments.
    """
    start = time.perf_counter()
    rpm = engine.operating.rpm if rpm is None else rpm
    _check_rpm(rpm)
    if load is not None and load.time_dependent:
        raise EngineError(
            "a steady state needs a load that does not change in time; use rotor.simulate for a load step"
        )
    if method not in ("auto", "closed", "shooting"):
        raise EngineError(f"method = {method!r}: a steady state is found by 'auto', 'closed' or 'shooting'")
    check_fidelity(fidelity, engine)
    points = grid_points(engine.strokes, grid_deg)
    engine, load = arrays_only(engine), arrays_only(load)
    n = engine.cylinders
    xp = jnp if any(isinstance(v, jax.core.Tracer) for v in (rpm, imep_scale)) else np  # numpy: no dispatch
    s = xp.broadcast_to(xp.asarray(imep_scale, dtype=xp.float64), (n,))
    fr = friction_coefficients(engine, friction)
    omega_m = xp.asarray(rpm, dtype=xp.float64) / RPM_PER_RAD_S
    balance = "load" if load is None else "fuel"  # a given load is carried, never replaced
    speed_load = None if balance == "load" else load
    lin = linear_losses(speed_load, fr)
    if method == "closed" and lin is None:
        raise EngineError(
            "method='closed' needs losses of the form a + c·ω² (no speed-linear friction term, no table load); "
            "use method='auto' or 'shooting'"
        )
    if lin is not None and method != "shooting":
        a_lin, c_lin = lin
        train, scene, E, t, x, ok, arrays = _closed_steady(
            engine, fidelity, points, s, fr, speed_load, a_lin, c_lin, omega_m, balance
        )
        _check_combustion(train, balance)
        return _finish(engine, train, scene, E, t, x, ok, balance, "closed", fidelity, omega_m, start, None, arrays)
    train = train_from_engine(engine, fidelity, points)
    _check_combustion(train, balance)
    # start from the closed form with the losses linearised about ω_m
    a_lin, c_lin = fr[0] + fr[1] * omega_m, fr[2]
    if balance == "fuel":
        m0 = load.torque(omega_m, 0.0)
        c_l = jax.grad(lambda w: load.torque(w, 0.0))(omega_m) / (2 * omega_m)
        a_lin, c_lin = a_lin + m0 - c_l * omega_m**2, c_lin + c_l
    E_g, _, x_g, _, _ = _closed_kernel(train, s, a_lin, c_lin, omega_m, balance)
    if balance == "load":
        x_g = x_g + a_lin - fr[0]  # the balancing load on top of the real friction law
    scene = Scene(train, s[None, :], fr, speed_load)
    x, scene, E, t, E_end, ok, arrays = _shooting_kernel(engine, scene, omega_m, E_g[0], x_g, balance)
    return _finish(engine, train, scene, E, t, x, ok, balance, "shooting", fidelity, omega_m, start, E_end, arrays)


def _check_combustion(train, balance):
    work = concrete(jnp.sum(train.imep_combustion_pa))
    if balance == "fuel" and work is not None and not work > 0:
        raise EngineError(
            "a given load needs a firing engine: the fuelling is scaled to carry it, but this engine's pressure has "
            "no combustion; give no load (load=None, --load none) to balance the mean engine torque instead"
        )


@eqx.filter_jit
def _finish_arrays(engine, scene, E, t, omega_m):
    count_trace()
    train = scene.train
    theta = train.nodes()
    val, der, sc = train.values, train.slopes, scene.scales[0]  # the result lies on the table nodes
    inertia, dinertia = val[:, 0], der[:, 0]
    omega = jnp.sqrt(2 * jnp.maximum(E, 0.0) / inertia)
    m_eng = scene.engine_torque(val, sc, omega, 0.0)
    m_loss = scene.loss(omega, t)
    accel = (m_eng - m_loss - 0.5 * dinertia * omega**2) / inertia
    # Shishkov, "Dinamika dvigatelei" (SUSU 2014) §3.2.12: δ ≈ L_excess / (J·ω²) from the textbook total torque at constant speed:
    # the gas torque at this point's fuelling plus the reciprocating inertia torque
    gas = val[:, COL_MOTORED] + jnp.sum(sc * val[:, COL_COMBUSTION:], axis=1)
    total = gas + train.textbook_k * omega_m**2
    work = jnp.cumsum(total - jnp.mean(total)) * train.step_rad
    excess = jnp.max(work) - jnp.min(work)
    return {
        "theta": theta,
        "omega": omega,
        "torque": m_eng,
        "load_torque": m_loss,
        "accel": accel,
        "imep_pa": (train.imep_motored_pa + sc * train.imep_combustion_pa)[None, :],
        "period_s": train.cycle_rad / omega_m,
        "excess_work_J": excess,
        "textbook_delta": excess / (train.mean_inertia * omega_m**2),
        "e_ratio": jnp.min(E) / jnp.mean(E),
        "i_min": jnp.argmin(E),
    }


def _finish(engine, train, scene, E, t, x, ok, balance, method, fidelity, omega_m, start, E_end, arrays):
    a = arrays
    converged = ok & jnp.isfinite(a["e_ratio"]) & (a["e_ratio"] >= STOP_FRACTION)
    if concrete(a["e_ratio"]) is not None:  # one transfer from the device for the three checks
        good, i_min, x_found = jax.device_get((converged, a["i_min"], x))
        if not np.all(np.isfinite(x_found)):
            what = "load torque" if balance == "load" else "fuel scale"
            raise NoSteadyStateError(
                f"no steady state at {float(omega_m * RPM_PER_RAD_S):g} rpm: the periodic solution's balancing "
                f"{what} is not a finite number; check that the "
                "load and the fuelling are in units the engine can carry (N·m, a torque of the engine's size)"
            )
        if not good:
            raise NoSteadyStateError(
                f"no steady state at {float(omega_m * RPM_PER_RAD_S):g} rpm: the kinetic energy would reach zero at "
                f"crank angle {float(np.rad2deg(i_min * train.cycle_rad / train.points)):.1f}° of the cycle (the "
                "crankshaft stops once a cycle). Raise the speed or the crankshaft/flywheel inertia ([crankshaft] "
                "inertia_kgm2), or simulate the run with rotor.simulate to see it stall"
            )
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
        load_torque_Nm=x if balance == "load" else None,
        fuel_scale=x if balance == "fuel" else None,
        excess_work_J=a["excess_work_J"],
        textbook_delta=a["textbook_delta"],
        periodicity_error=None if E_end is None else jnp.abs(E_end - E[0]) / E[0],
        converged=converged,
    )
    check_speed_result(result)  # concrete values only: under jit/vmap ``converged`` says it
    return result
