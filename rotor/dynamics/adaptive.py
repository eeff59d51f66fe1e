"""The adaptive integrators of the equation of motion (:mod:`rotor.dynamics.equation`):
the ``"angle"`` method, the energy form integrated in θ by diffrax (Dopri8, steps of at
most 4°) for a chosen tolerance, and the ``"time"`` method, θ and ω integrated in time
(a start from rest, a stall), with the solve's dense output read at given angles.

A module of its own so that what needs no adaptive solve (the steady state, the closed
form, the grid) does not import diffrax; and diffrax is imported where a solve is traced
(:func:`_diffrax`), so that a process that runs a kept program (:mod:`rotor.programs`)
never imports it.
"""

from __future__ import annotations

import contextlib
import functools
import sys
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..programs import kept_program
from .crank_train import COL_I
from .equation import Scene, report_progress, speed_from_energy


@functools.cache
def _diffrax() -> tuple[Any, Any, type]:
    """diffrax, optimistix and the progress meter class (imported on the first trace)."""
    import diffrax as dfx
    import optimistix as optx

    class BarMeter(dfx.AbstractProgressMeter):
        """diffrax's progress hook reporting to the progress bar with key ``meter`` (about every
        1 % of the solve)."""

        meter: Any

        def init(self):
            return jnp.asarray(0.0)

        def step(self, state, progress):
            due = (progress - state >= 0.01) | (progress >= 1.0)
            jax.lax.cond(jnp.all(due), lambda: report_progress(self.meter, progress), lambda: None)
            return jnp.where(due, progress, state)

        def close(self, state):
            report_progress(self.meter, jnp.asarray(1.0))

    return dfx, optx, BarMeter


# ----------------------------------------------------------------------------- diffrax
def angle_field(theta, y, args):
    """The equation of motion in the angle domain, as the ``"angle"`` method integrates it:
    at engine angle ``theta`` [rad] the derivatives in θ of y = (E/E_ref, t·ω_ref, z) (the
    kinetic energy over ``e_ref`` [J], time scaled by ``w_ref`` [rad/s], the governor's
    state), ``args`` = (:class:`Scene`, e_ref, w_ref)."""
    scene, e_ref, w_ref = args
    e, tau, z = y
    E = e * e_ref
    t = tau / w_ref
    val, der, s = scene.terms(theta)
    omega = speed_from_energy(E, val[COL_I])
    m_eng = scene.engine_torque(val, s, omega, z)
    m_loss = scene.loss(omega, t)
    dz = scene.governor.error(omega) / omega if scene.governor is not None else jnp.zeros_like(omega)
    return (m_eng - m_loss) / e_ref, w_ref / omega, dz


# the adaptive angle-domain solver never steps over more than 4°: a local error estimate
# over a longer step misses features of the torque (at rtol 1e-3 it was off by 6 %)
MAX_ANGLE_STEP = float(np.deg2rad(4.0))


def _controller(rtol, dtmax=None):
    dfx, _, _ = _diffrax()
    return dfx.PIDController(rtol=rtol, atol=rtol, pcoeff=0.0, icoeff=1.0, dtmax=dtmax)


def _solver():
    # Dopri8: on these piecewise-cubic tables Tsit5's error estimate is too optimistic
    # (rtol 1e-9 gave 1e-6 in ω over two cycles); Dopri8 stays near its tolerance. Its
    # stages written out (rotor.rungekutta): the same steps, in less time a step
    from ..rungekutta import UnrolledDopri8

    return UnrolledDopri8()


@contextlib.contextmanager
def save_points_checked_on_the_host():
    """While tracing a solve whose save points the caller has built itself (increasing,
    within the solve's span): diffrax's run-time check of them becomes a status (NaN save
    points, an unsuccessful solve) instead of a host callback, which the persistent
    compilation cache cannot store. Equinox reads its error mode (``EQX_ON_ERROR``) when a
    check is traced; a mode the user chose other than the default ``raise`` (such as
    ``breakpoint``, to debug) is left as it is."""
    errors = sys.modules.get("equinox._errors")
    mode = getattr(errors, "EQX_ON_ERROR", None)
    if errors is None or mode != "raise":
        yield
        return
    errors.EQX_ON_ERROR = "nan"
    try:
        yield
    finally:
        errors.EQX_ON_ERROR = mode


@kept_program(static_argnames=("max_steps", "meter"))
@eqx.filter_jit
def angle_run(scene: Scene, theta0, y0, theta_out, rtol, e_switch, max_steps: int, meter=None):
    """Adaptive solve in the angle domain from θ0 with y0 = (E, t, z), saving at ``theta_out``.

    Ends early (a stall hand-over) where E falls to ``e_switch``; ``meter``: the key of a
    progress bar to report to (diffrax's progress-meter hook, :func:`_diffrax`), or None. Returns the saved
    (E, t, z), the final θ and state, and whether it ended early."""
    dfx, optx, BarMeter = _diffrax()
    E0, t0, z0 = y0
    e_ref = E0
    w_ref = jnp.sqrt(2 * E0 / scene.train.mean_inertia)
    y = (jnp.ones_like(E0), t0 * w_ref, z0)
    event = dfx.Event(lambda t, y, args, **kw: y[0] - e_switch / e_ref, optx.Newton(1e-12, 1e-12), direction=False)
    with save_points_checked_on_the_host():  # theta_out: increasing from past θ0, built by the caller
        sol = dfx.diffeqsolve(
            dfx.ODETerm(angle_field),
            _solver(),
            theta0,
            theta_out[-1],
            None,
            y,
            args=(scene, e_ref, w_ref),
            saveat=dfx.SaveAt(ts=theta_out, t1=True),
            stepsize_controller=_controller(rtol, MAX_ANGLE_STEP),
            event=event,
            max_steps=max_steps,
            throw=False,
            progress_meter=BarMeter(meter) if meter is not None else dfx.NoProgressMeter(),
        )
    e, tau, z = sol.ys
    n = theta_out.shape[0]
    out = (e[:n] * e_ref, tau[:n] / w_ref, z[:n])
    end = (sol.ts[-1], e[-1] * e_ref, tau[-1] / w_ref, z[-1])
    stopped = sol.event_mask
    ok = sol.result == dfx.RESULTS.successful
    return out, end, stopped, ok, sol.stats["num_steps"]


def _time_field(t, y, args):
    scene, w_ref = args
    theta, w, z = y
    omega = w * w_ref
    val, der, s = scene.terms(theta)
    inertia, dinertia = val[COL_I], der[COL_I]
    m_eng = scene.engine_torque(val, s, omega, z)
    m_loss = scene.loss(omega, t, signed=True)
    accel = (m_eng - m_loss - 0.5 * dinertia * omega**2) / inertia
    dz = scene.governor.error(omega) if scene.governor is not None else jnp.zeros_like(omega)
    return omega, accel / w_ref, dz


@eqx.filter_jit  # not kept: it returns diffrax's solution whole (its dense output)
def time_run(scene: Scene, t0, y0, theta_end, t_end, rtol, omega_ref, stop_at_stall: bool, max_steps: int):
    """Adaptive solve in time from (θ, ω, z) = y0 until θ reaches ``theta_end``, ω falls to
    zero (if ``stop_at_stall``) or t reaches ``t_end``. Returns every accepted step."""
    dfx, optx, _ = _diffrax()
    conds = [lambda t, y, args, **kw: y[0] - theta_end]
    dirs = [True]
    if stop_at_stall:
        # ω/ω_ref + 1e-12: a start from rest that rolls backwards is a stall too
        conds.append(lambda t, y, args, **kw: y[1] + 1e-12)
        dirs.append(False)
    event = dfx.Event(conds, optx.Newton(1e-12, 1e-12), direction=dirs)
    theta0, omega0, z0 = y0
    sol = dfx.diffeqsolve(
        dfx.ODETerm(_time_field),
        _solver(),
        t0,
        t_end,
        None,
        (theta0, omega0 / omega_ref, z0),
        args=(scene, omega_ref),
        saveat=dfx.SaveAt(t0=True, steps=True, dense=True),
        stepsize_controller=_controller(rtol),
        event=event,
        max_steps=max_steps,
        throw=False,
    )
    theta, w, z = sol.ys
    return sol.ts, (theta, w * omega_ref, z), sol.event_mask, sol.result == dfx.RESULTS.successful, sol


@eqx.filter_jit
def dense_at_angles(sol, t_guess, theta_q, omega_ref):
    """(t, ω, z) where the time-domain solution passes the angles ``theta_q``: Newton's
    method (optimistix) on θ(t) = θ_q with the solver's dense output, from the guesses
    ``t_guess``."""
    _, optx, _ = _diffrax()

    def one(t0, th_q):
        sol_t = optx.root_find(
            lambda t, _: sol.evaluate(t)[0] - th_q,
            optx.Newton(rtol=1e-13, atol=1e-10),
            t0,
            max_steps=16,
            throw=False,
        )
        theta, w, z = sol.evaluate(sol_t.value)
        return sol_t.value, w * omega_ref, z

    return jax.vmap(one)(t_guess, theta_q)
