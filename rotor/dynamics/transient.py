"""Transient runs: the crank speed over many cycles from a given start.

:func:`simulate` starts at crank angle 0 with speed ``rpm`` (0: from rest) and runs
``cycles`` cycles, or until the crankshaft stops (a stall: ``result.stalled``, with the
time and angle). See :mod:`rotor.dynamics.equation` for the formulations ``"closed"``,
``"grid"``, ``"angle"`` and ``"time"``; ``method="auto"`` picks the cheapest valid one:
``"time"`` from rest, ``"closed"`` where the losses are a + c·ω² and nothing changes in
time, ``"grid"`` otherwise.
"""

from __future__ import annotations

import sys
import time
import warnings
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..checks import arrays_only, concrete
from ..engine.friction import Friction
from ..engine.model import Engine
from ..errors import EngineError
from ..units import RPM_PER_RAD_S
from .crank_train import COL_COMBUSTION, COL_MOTORED, crank_train
from .equation import (
    PROGRESS,
    Scene,
    angle_run,
    closed_run,
    count_trace,
    dense_at_angles,
    friction_coefficients,
    grid_run,
    linear_losses,
    time_run,
)
from .loads import Governor, Load
from .result import SpeedResult

__all__ = ["simulate", "METHODS"]

METHODS = ("auto", "closed", "grid", "angle", "time")
DEFAULT_RTOL = 1e-9  # the cheapest that meets 1e-6 in ω on every scene (benchmarks/defaults.py)
STALL_HANDOVER = 0.02  # the angle domain hands over to the time domain below 2 % of the start speed
TIME_DOMAIN_STEPS = 200_000


class Progress:
    """A one-line progress bar on stderr, shown only after ~2 s and only on a terminal.

    ``total``: cycles in the run; ``enabled``: True, False or None (when stderr is a terminal).
    """

    def __init__(self, total: int, enabled: bool | None):
        self.total, self.start, self.shown, self.last = total, time.perf_counter(), False, 0
        self.enabled = sys.stderr.isatty() if enabled is None else bool(enabled)

    def fraction(self, done: float) -> None:
        """Show that the fraction ``done`` (0…1) of the run is done."""
        self.update(int(round(done * self.total)))

    def update(self, done: int) -> None:
        """Show that ``done`` of the cycles are done (once the run has taken ~2 s)."""
        if not self.enabled or (self.shown and done < self.last):
            return
        self.last = done
        elapsed = time.perf_counter() - self.start
        if elapsed < 2.0 and done < self.total:
            return
        frac = done / self.total
        bar = "#" * int(30 * frac)
        eta = elapsed / frac - elapsed if frac > 0 else float("nan")
        sys.stderr.write(f"\rsimulating [{bar:<30}] {done}/{self.total} cycles, {elapsed:5.1f} s, ~{eta:4.0f} s left")
        sys.stderr.flush()
        self.shown = True

    def close(self) -> None:
        """End the bar's line, if it was shown."""
        if self.shown:
            sys.stderr.write("\n")
            sys.stderr.flush()


def _known(x, default):
    """``x`` as a number, or ``default`` while tracing (jax.grad / jax.vmap over a run)."""
    c = concrete(x)
    return default if c is None else c.item()


def _warn_runaway(train, scales, fr, rpm):
    """Warn where nothing resists the engine: no load, no governor and a mean engine
    torque above friction at the start speed (the run accelerates)."""
    if any(isinstance(x, jax.core.Tracer) for x in (rpm, scales, fr, train.values)):
        return  # under jit/grad/vmap: no values to judge
    vals, s0, (fa, fb, fc) = np.asarray(train.values), np.asarray(scales)[0], np.asarray(fr, dtype=np.float64)
    engine_Nm = float(np.mean(vals[:, COL_MOTORED]) + np.sum(s0 * np.mean(vals[:, COL_COMBUSTION:], axis=0)))
    w = float(rpm) / RPM_PER_RAD_S
    friction_Nm = float(fa + fb * w + fc * w**2)
    if engine_Nm - friction_Nm > 1e-3 * max(abs(engine_Nm), 1.0):
        warnings.warn(
            f"simulate: no load and no governor, and the mean engine torque ({engine_Nm:.1f} N·m) exceeds friction "
            f"({friction_Nm:.1f} N·m) at {float(rpm):g} rpm: the engine will accelerate and δ will not be that of an "
            "operating point; give a load (e.g. rotor.ConstantLoad(rotor.steady_state(engine, rpm).load_torque_Nm), "
            "the one that balances it) or a governor",
            stacklevel=3,
        )


def _check_scales(combustion, cycles, n):
    if combustion is None:
        return np.ones((cycles, n))
    c = combustion
    if not isinstance(c, jax.Array) or concrete(c) is not None:
        c = np.asarray(c, dtype=np.float64)
        if c.shape != (cycles, n):
            raise EngineError(
                f"combustion has shape {c.shape}: needs one scale per cycle and cylinder, ({cycles}, {n}); "
                "build it with rotor.combustion_pattern"
            )
        if not np.all(np.isfinite(c)) or np.any(c < 0):
            raise EngineError("combustion scales must be finite and not negative")
    return jnp.asarray(c, dtype=jnp.float64)


def simulate(
    engine: Engine,
    rpm: ArrayLike | None = None,
    cycles: int = 10,
    load: Load | None = None,
    *,
    method: str = "auto",
    fidelity: str = "variable",
    rtol: ArrayLike | None = None,
    friction: Friction | Literal[False] | None = None,
    governor: Governor | None = None,
    combustion: ArrayLike | None = None,
    step_deg: float = 1.0,
    grid_deg: float = 0.25,
    steps_per_cycle: int | None = None,
    stop_at_stall: bool = True,
    max_time_s: float | None = None,
    progress: bool | None = None,
) -> SpeedResult:
    """Run the engine for ``cycles`` cycles from crank angle 0 at speed ``rpm``.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``rpm``: the starting speed [rpm] (0: from rest); default ``[operating] rpm``.
    - ``cycles``: number of cycles to run.
    - ``load``: a load (:mod:`rotor.dynamics.loads`) or None.
    - ``method``: ``"auto"`` (default), ``"closed"``, ``"grid"``, ``"angle"`` or ``"time"``.
    - ``fidelity``: ``"variable"`` (default), ``"series"`` (λ-series kinematics),
      ``"coefficients"`` or ``"constant"`` (see :mod:`rotor.dynamics.crank_train`).
    - ``rtol``: relative tolerance of the adaptive methods (default 1e-9).
    - ``friction``: a :class:`rotor.Friction`, None (the engine file's) or False (none).
    - ``governor``: a :class:`rotor.Governor` scaling the fuelling, or None.
    - ``combustion``: combustion scale per cycle and cylinder, (cycles, cylinders), from
      :func:`rotor.combustion_pattern` (misfires, IMEP spread, cycle-to-cycle variation).
    - ``step_deg``: spacing of the saved samples [deg]; must be a multiple of ``grid_deg``.
    - ``steps_per_cycle``: RK4 steps per cycle of ``method="grid"`` (default two per
      degree, 1440 four-stroke: a 1° pressure rise costs 1.6e-7 in ω there, and 2.5e-6
      at one step per degree).
    - ``grid_deg``: node spacing of the angle tables [deg].
    - ``stop_at_stall``: end the run where ω reaches zero (else it runs on in the time
      domain, friction and load acting against the motion).
    - ``max_time_s``: longest time the time domain may run [s].
    - ``progress``: show a progress bar on stderr (default: when stderr is a terminal and
      the run takes longer than about two seconds).

    **Returns:** a :class:`rotor.SpeedResult` (``kind="transient"``).
    """
    wall = time.perf_counter()
    if method not in METHODS:
        raise EngineError(f"method = {method!r}: must be one of {', '.join(map(repr, METHODS))}")
    if not (isinstance(cycles, (int, np.integer)) and cycles >= 1):
        raise EngineError(f"cycles = {cycles!r}: must be a whole number, 1 or more")
    rpm = engine.operating.rpm if rpm is None else rpm
    r = concrete(rpm)
    if r is not None and not (r.ndim == 0 and np.isfinite(r) and r >= 0):
        raise EngineError(f"rpm = {rpm!r}: the starting speed must be zero or a positive, finite speed in rpm")
    rtol = DEFAULT_RTOL if rtol is None else rtol
    rt = concrete(rtol)
    if rt is not None and not (1e-14 <= rt <= 1e-2):
        raise EngineError(f"rtol = {rtol!r}: must lie between 1e-14 and 1e-2")
    load, governor = arrays_only(load), arrays_only(governor)
    train = crank_train(engine, fidelity, grid_deg)
    P = int(round(train.cycle_rad / np.deg2rad(step_deg)))
    if P < 8 or train.points % P:
        raise EngineError(
            f"step_deg = {step_deg!r}: must be a multiple of grid_deg ({grid_deg:g}°) that divides the cycle"
        )
    stride = train.points // P
    scales = _check_scales(combustion, cycles, engine.cylinders)
    fr = friction_coefficients(engine, friction)
    scene = Scene(train, scales, fr, load, governor)
    at_rest = r is not None and r == 0
    lin = linear_losses(load, fr) if governor is None else None
    if method == "auto":
        method = "time" if at_rest else ("closed" if lin is not None else "grid")
    if method == "closed" and lin is None:
        raise EngineError(
            "method='closed' needs losses a + c·ω² that do not change in time and no governor; "
            "use method='angle' (or 'auto')"
        )
    if method in ("closed", "grid", "angle") and at_rest:
        raise EngineError(
            f"method={method!r} works in the crank-angle domain and needs a start speed above 0; "
            "a start from rest needs method='time' (or 'auto')"
        )
    rtol_a = jnp.asarray(rtol, dtype=jnp.float64)
    if load is None and governor is None:
        _warn_runaway(train, scales, fr, rpm)
    # the progress bar hears from inside the one compiled run (a host callback), so showing it
    # compiles the same kernels once, never per chunk
    bar = Progress(cycles, progress)
    PROGRESS["report"] = bar.fraction if bar.enabled else None
    try:
        return _run(
            engine,
            train,
            scene,
            cycles,
            method,
            fidelity,
            P,
            stride,
            rpm,
            rtol_a,
            at_rest,
            lin,
            governor,
            steps_per_cycle,
            step_deg,
            grid_deg,
            stop_at_stall,
            max_time_s,
            bar,
            wall,
        )
    finally:
        PROGRESS["report"] = None
        bar.close()


def _run(
    engine,
    train,
    scene,
    cycles,
    method,
    fidelity,
    P,
    stride,
    rpm,
    rtol_a,
    at_rest,
    lin,
    governor,
    steps_per_cycle,
    step_deg,
    grid_deg,
    stop_at_stall,
    max_time_s,
    bar,
    wall,
):
    """The run of :func:`simulate` once its arguments are checked."""
    omega0, E0, e_switch = _start(train, rpm)
    theta_step = train.cycle_rad / P
    pieces: list[tuple[Any, ...]] = []  # (theta, t, E or None, omega or None, z, rows kept or None)
    done, t_now, E_now, z_now = 0, jnp.asarray(0.0), E0, jnp.asarray(0.0)
    handover = None  # (theta, t, omega, z) where the time domain takes over
    extras: dict[str, Any] = {}  # typed fields of the result: steps_per_cycle, solver_steps, incomplete
    if method == "closed":
        assert lin is not None  # checked above
        a, c = lin
        for size in (cycles,):
            E, t, E_end, t_end, stalled_at = closed_run(scene, a, c, E_now, t_now, done, size, stride, bar.enabled)
            k = int(_known(stalled_at, size))
            pieces.append((_theta_grid(done, k, P, train.cycle_rad), t, E, None, None, k))
            done += k
            E_now, t_now = E_end, t_end
            bar.update(done)
            if k == size and done == cycles:
                pieces.append((np.array([done * train.cycle_rad]), t_end, E_end, None, None, None))
            if k < size:
                handover = (done * train.cycle_rad, t_end, _omega_at(train, done * train.cycle_rad, E_end), 0.0)
                break
    elif method == "grid":
        if steps_per_cycle is None:  # two per degree, or one per saved sample if those are finer
            spc = max(int(round(2 * np.rad2deg(train.cycle_rad))), P)
        else:
            spc = int(steps_per_cycle)
        if spc < 8 or spc % P:
            raise EngineError(
                f"steps_per_cycle = {steps_per_cycle!r}: needs a whole multiple of the {P} saved points per cycle "
                f"(step_deg = {step_deg:g}); raise step_deg or steps_per_cycle"
            )
        for size in (cycles,):
            th0 = done * train.cycle_rad
            (E, t, z), y_end, stalled_at = grid_run(
                scene, jnp.asarray(th0), (E_now, t_now, z_now), size, spc, spc // P, e_switch, bar.enabled
            )
            k = int(_known(stalled_at, size))
            pieces.append((_theta_grid(done, k, P, train.cycle_rad), t, E, None, z, k))
            done += k
            E_now, t_now, z_now = y_end
            bar.update(done)
            if k == size and done == cycles:
                pieces.append((np.array([done * train.cycle_rad]), t_now, E_now, None, z_now, None))
            if k < size:
                th_h = done * train.cycle_rad
                handover = (th_h, t_now, _omega_at(train, th_h, E_now), z_now)
                break
        extras["steps_per_cycle"] = spc
    elif method == "angle":
        steps = 0
        for size in (cycles,):
            theta_out = done * train.cycle_rad + np.arange(1, size * P + 1) * theta_step
            th0 = done * train.cycle_rad
            (E, t, z), end, stopped, ok, n_steps = angle_run(
                scene, th0, (E_now, t_now, z_now), theta_out, rtol_a, e_switch, 4000 * size + 10000, bar.enabled
            )
            steps += int(_known(n_steps, 0))
            stopped = bool(_known(stopped, False))
            if not _known(ok, True) and not stopped:
                raise EngineError(
                    f"the angle-domain solver could not reach the end of cycle {done + size} "
                    f"(stopped at crank angle {float(np.rad2deg(end[0])):.1f}°); try a looser rtol or method='time'"
                )
            # samples at θ_out[i] hold the state after step i; prepend the chunk's start
            th = np.concatenate([[th0], theta_out[:-1]])
            Es, ts, zs = _prepend((E_now, t_now, z_now), (E, t, z))
            if stopped:
                reached = int(np.sum(np.isfinite(np.asarray(E))))  # samples saved before the hand-over
                whole = reached // P
                keep = whole * P
                pieces.append((th, ts, Es, None, zs, keep))
                done += whole
                # hand over at the start of the incomplete cycle
                if keep > 0:
                    E_h, t_h, z_h = E[keep - 1], t[keep - 1], z[keep - 1]
                else:
                    E_h, t_h, z_h = E_now, t_now, z_now
                th_h = done * train.cycle_rad
                handover = (th_h, t_h, _omega_at(train, th_h, E_h), z_h)
                break
            pieces.append((th, ts, Es, None, zs, None))
            E_now, t_now, z_now = _last((E, t, z))
            done += size
            bar.update(done)
            if done == cycles:
                pieces.append((theta_out[-1:], t_now, E_now, None, z_now, None))
        extras["solver_steps"] = steps
    else:
        handover = (0.0, 0.0, omega0, 0.0)

    stalled = False
    stall_t = stall_th = None
    time_domain = None
    if handover is not None:
        th_h, t_h, w_h, z_h = handover
        theta_end = cycles * train.cycle_rad
        w_ref = omega0 if not at_rest else engine.operating.omega
        if governor is not None and at_rest:
            w_ref = governor.omega
        if max_time_s is None:
            t_max = float(t_h) + 20.0 * (theta_end - float(th_h)) / float(w_ref) + 10.0
        else:
            t_max = float(t_h) + float(max_time_s)
        ts, (th, w, z), mask, ok, sol = time_run(
            scene,
            jnp.asarray(t_h, dtype=jnp.float64),
            (
                jnp.asarray(th_h, dtype=jnp.float64),
                jnp.asarray(w_h, dtype=jnp.float64),
                jnp.asarray(z_h, dtype=jnp.float64),
            ),
            jnp.asarray(theta_end),
            jnp.asarray(t_max),
            rtol_a,
            jnp.asarray(w_ref, dtype=jnp.float64),
            stop_at_stall,
            TIME_DOMAIN_STEPS,
        )
        keep = np.isfinite(np.asarray(ts))
        ts, th, w, z = ts[keep], th[keep], w[keep], z[keep]
        if stop_at_stall and bool(mask[1]):
            stalled = True
            stall_t, stall_th = float(ts[-1]), float(th[-1])
        elif not bool(mask[0]):
            extras["incomplete"] = (
                f"the time-domain run ended at t = {float(ts[-1]):.3f} s, crank angle "
                f"{float(np.rad2deg(th[-1])):.1f}°, before reaching the end of cycle {cycles}"
                + ("" if bool(ok) else " (step limit)")
            )
        time_domain = (th, ts, w, z, sol, w_ref)
        if method == "time":
            method = "time"
        else:
            method = f"{method}+time"
    return _assemble(
        engine, train, scene, pieces, time_domain, method, fidelity, P, stalled, stall_t, stall_th, wall, extras
    )


@eqx.filter_jit
def _samples(scene, theta, t, E, omega, z):
    """ω (from E where given), engine and load torque, dω/dt and fuel at the samples."""
    count_trace()
    val, der, s = scene.terms(theta)
    inertia, dinertia = val[:, 0], der[:, 0]
    if E is not None:
        omega = jnp.sqrt(2 * jnp.maximum(E, 0.0) / inertia)
    m_eng = scene.engine_torque(val, s, omega, z)
    m_loss = scene.loss(omega, t)
    accel = (m_eng - m_loss - 0.5 * dinertia * omega**2) / inertia
    return omega, m_eng, m_loss, accel, scene.fuel(omega, z)


def _theta_grid(first_cycle, cycles, P, cycle_rad):
    """Crank angles [rad] of the saved samples of ``cycles`` whole cycles, shape (cycles, P)."""
    k = np.arange(first_cycle, first_cycle + cycles)[:, None]
    return k * cycle_rad + np.arange(P)[None, :] * (cycle_rad / P)


@eqx.filter_jit
def _start(train, rpm):
    """ω0 [rad/s] and kinetic energy [J] at the start, θ = 0, and the energy [J] below
    which the angle domain hands over to the time domain."""
    omega0 = jnp.asarray(rpm, dtype=jnp.float64) / RPM_PER_RAD_S
    inertia0 = train.at(0.0)[0][0]
    return omega0, 0.5 * inertia0 * omega0**2, 0.5 * train.mean_inertia * (STALL_HANDOVER * omega0) ** 2


@jax.jit
def _prepend(first, rest):
    """Each array of ``rest`` shifted one place on, its first place taken by ``first``."""
    return tuple(jnp.concatenate([jnp.reshape(a, (1,)), b[:-1]]) for a, b in zip(first, rest))


@jax.jit
def _last(arrays):
    return tuple(a[-1] for a in arrays)


@eqx.filter_jit
def _omega_at(train, theta, E):
    return jnp.sqrt(2 * jnp.maximum(E, 0.0) / train.at(theta)[0][0])


@eqx.filter_jit
def _gather(scene, pieces):
    """All pieces (θ, t, E or None, ω or None, z or None, rows kept or None) as the flat
    sample arrays (θ, t, ω, engine torque, load torque, dω/dt, fuel), in one compiled call."""

    def flat(a, keep):
        a = jnp.asarray(a, dtype=jnp.float64)
        return jnp.reshape(a if keep is None else a[:keep], (-1,))

    parts = []
    for th, t, E, w, z, keep in pieces:
        th, t = flat(th, keep), flat(t, keep)
        E, w = (None if a is None else flat(a, keep) for a in (E, w))
        z = jnp.zeros_like(th) if z is None else flat(z, keep)
        parts.append((th, t) + _samples(scene, th, t, E, w, z))
    return tuple(jnp.concatenate(a) for a in zip(*parts))


def _assemble(engine, train, scene, pieces, time_domain, method, fidelity, P, stalled, stall_t, stall_th, wall, extras):
    pieces = [p for p in pieces if np.shape(p[0])[0] > 0 and p[5] != 0]
    # the whole cycles of P samples (a single end sample adds none); ``keep`` counts the
    # rows kept of a (cycles, P) piece or the samples kept of a flat one
    uniform = sum((np.shape(p[0])[0] if p[5] is None else p[5]) * (P if np.ndim(p[0]) == 2 else 1) // P for p in pieces)
    if time_domain is not None:
        for th, t, w, z, whole in _resample(scene, time_domain, P):
            pieces.append((th, t, None, w, z, None))
            uniform += whole
    theta, t, omega, m_eng, m_loss, accel, fuel = _gather(scene, tuple(pieces))
    imep = _imep(train, scene.scales)
    return SpeedResult(
        t=t,
        theta=theta,
        omega=omega,
        accel=accel,
        torque=m_eng,
        load_torque=m_loss,
        imep_pa=imep,
        method=method,
        fidelity=fidelity,
        kind="transient",
        strokes=engine.strokes,
        cycle_rad=train.cycle_rad,
        points_per_cycle=P,
        uniform_cycles=uniform,
        stalled=stalled,
        stall_time_s=stall_t,
        stall_angle_rad=stall_th,
        engine_name=engine.name,
        wall_s=time.perf_counter() - wall,
        fuel=None if scene.governor is None else fuel,
        **extras,
    )


@eqx.filter_jit
def _imep(train, scales):
    """IMEP [Pa] per cycle and cylinder."""
    return train.imep_motored_pa + scales * train.imep_combustion_pa


def _resample(scene, time_domain, P):
    """The time-domain steps as (uniformly sampled whole cycles, raw tail).

    While ω > 0, θ(t) is monotone: the time of each crank angle of the uniform grid is
    found by Newton's method on the solver's dense output, from a linear first guess.
    """
    th, t, w, z = (np.asarray(a) for a in time_domain[:4])
    sol, w_ref = time_domain[4:]
    train = scene.train
    cycle = train.cycle_rad
    start = th[0]
    k0 = start / cycle
    whole = 0
    if np.isclose(k0, round(k0)) and th.size > 2 and np.all(np.diff(th) > 0) and np.all(w[1:] > 0):
        whole = int(np.floor((th[-1] - start) / cycle + 1e-9))
    if whole == 0:
        return [(jnp.asarray(th), jnp.asarray(t), jnp.asarray(w), jnp.asarray(z), 0)]
    # a run that ends on a cycle boundary (it reached the end) gets that boundary as its
    # last sample, like the angle-domain methods, and no raw tail
    ends_whole = abs(th[-1] - start - whole * cycle) <= 1e-9 * max(1.0, abs(th[-1]))
    tq = start + np.arange(whole * P + int(ends_whole)) * (cycle / P)
    j = np.clip(np.searchsorted(th, tq, side="right") - 1, 0, th.size - 2)
    u = (tq - th[j]) / (th[j + 1] - th[j])
    t_q, w_q, z_q = (f[j] + u * (f[j + 1] - f[j]) for f in (t, w, z))  # linear between steps
    # where the crank turns: Newton on θ(t) = θ_q with the solver's own dense output; at a
    # start from rest (ω = 0 at the step's start) the linear values stay
    moving = w[j] > 0
    t_n, w_n, z_n = (
        np.asarray(a)
        for a in dense_at_angles(sol, jnp.asarray(t_q), jnp.asarray(tq), jnp.asarray(w_ref, dtype=jnp.float64))
    )
    t_q, w_q, z_q = (np.where(moving, a, b) for a, b in ((t_n, t_q), (w_n, w_q), (z_n, z_q)))
    tail = (th > tq[-1] + 1e-12) & (not ends_whole)
    return [
        (jnp.asarray(tq), jnp.asarray(t_q), jnp.asarray(w_q), jnp.asarray(z_q), whole),
        (jnp.asarray(th[tail]), jnp.asarray(t[tail]), jnp.asarray(w[tail]), jnp.asarray(z[tail]), 0),
    ]
