"""Transient runs: the crank speed over many cycles from a given start.

:func:`simulate` starts at crank angle 0 with speed ``rpm`` (0: from rest) and runs
``cycles`` cycles, or until the crankshaft stops (a stall: ``result.stalled``, with the
time and angle). See :mod:`rotor.dynamics.equation` for the formulations ``"closed"``,
``"grid"``, ``"angle"`` and ``"time"``; ``method="auto"`` picks the cheapest valid one:
``"time"`` from rest, ``"closed"`` where the losses are a + c·ω² and nothing changes in
time, ``"grid"`` otherwise.
"""

from __future__ import annotations

import dataclasses
import functools
import time
import warnings
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..cache import padded_size
from ..checks import (
    TRACED,
    arrays_only,
    called_from_outside,
    check_size,
    concrete,
    guard,
    guard_number,
    is_tracer,
    tracing,
)
from ..cycles import array_module, cycle_delta, cycle_slopes
from ..engine.friction import Friction
from ..engine.model import Engine, guard_engine, require_engine
from ..engine.plausible import PLAUSIBLE, guard_fields, what_it_is
from ..errors import EngineError
from ..programs import kept_program
from ..progress import Progress
from ..units import RPM_PER_RAD_S
from .adaptive import angle_run, dense_at_angles, time_run
from .crank_train import COL_COMBUSTION, COL_I, COL_K, COL_MOTORED, CrankTrain, crank_train
from .equation import (
    Scene,
    closed_run,
    friction_coefficients,
    grid_run,
    linear_losses,
    node_offsets,
)
from .invariants import check_speed_result
from .loads import Governor, Load, guard_governor, guard_load
from .operating import given_operating_point
from .prepared import PreparedEngine, resolve_engine
from .result import CycleSummary, SpeedResult, cycle_extremes

__all__ = ["simulate", "METHODS", "RunPlan", "chunk_cycles", "plan_run", "run_plan"]

METHODS = ("auto", "closed", "grid", "angle", "time")
DEFAULT_RTOL = 1e-9  # the cheapest that meets 1e-6 in ω on every scene (benchmarks/defaults.py)
STALL_HANDOVER = 0.02  # the angle domain hands over to the time domain below 2 % of the start speed
TIME_DOMAIN_STEPS = 200_000
# a run goes in chunks of cycles, one compiled call each, every one well under a second on
# 4chn15 (benchmarks/long_run.py), so that Ctrl-C, which Python hears between calls, stops
# a run within about a second, and the samples of a long run need not all be held at once
CHUNK_GRID_STEPS = 72_000  # RK4 steps per chunk of method="grid": 50 cycles at 1440 steps, ~0.25 s
CHUNK_CLOSED_NODES = 1_440_000  # table nodes per chunk of method="closed": 500 cycles at 0.25°, ~0.25 s
CHUNK_ANGLE_CYCLES = 20  # cycles per chunk of method="angle" (Dopri8 at rtol 1e-9), ~0.2 s
SAMPLE_BYTES = 16 * 8  # memory per kept sample: 7 result arrays, the states and the copies joining them [bytes]
CYCLE_BYTES = 12 * 8  # memory per cycle of the per-cycle figures [bytes], plus 16 per cylinder


def chunk_cycles(method: str, cycles: int, steps_per_cycle: int = 0, nodes_per_cycle: int = 0) -> int:
    """Cycles per compiled call of a run of ``cycles`` cycles by ``method`` (``"closed"``,
    ``"grid"`` or ``"angle"``): a fixed chunk that takes well under a second, or for a
    shorter run ``cycles`` itself (``"angle"``: an adaptive solve steps to the run's end) or
    the standard size that holds it (:func:`rotor.cache.padded_size`; ``"closed"`` and
    ``"grid"``, whose fixed steps past the end change nothing before it), so that runs of
    other lengths reuse the compiled program. ``steps_per_cycle``: RK4 steps per cycle
    (``"grid"``); ``nodes_per_cycle``: table nodes per cycle (``"closed"``)."""
    if method == "grid":
        per = CHUNK_GRID_STEPS // max(int(steps_per_cycle), 1)
    elif method == "closed":
        per = CHUNK_CLOSED_NODES // max(int(nodes_per_cycle), 1)
    else:
        return int(min(max(CHUNK_ANGLE_CYCLES, 1), cycles))
    return int(min(max(per, 1), padded_size(cycles)))


def _kind(value) -> str:
    """The NumPy dtype kind of ``value`` (``"f"``, ``"i"``, …), ``"?"`` where it is none."""
    if isinstance(value, (str, bytes)):
        return "U"
    try:
        return np.asarray(value).dtype.kind
    except (TypeError, ValueError):
        return "?"


def _whole(name, value):
    """``value`` as a Python int of 1 or more, or a TypeError / EngineError naming ``name``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} = {value!r}: takes a whole number (an int such as 10), not a {type(value).__name__}")
    if value < 1:
        raise EngineError(f"{name} = {value!r}: must be a whole number, 1 or more")
    return int(value)


def _sample(x, *index: int):
    """The element of ``x`` at ``index``: a NumPy number where ``x`` is concrete (no JAX
    operation to dispatch, or to compile in a new process), else the traced element."""
    return array_module(x).asarray(x)[index]


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
            stacklevel=4,
        )


def _check_scales(combustion, cycles, n, guarded=False):
    """The combustion scales (cycles, cylinders) [-]: concrete ones checked at once, traced
    ones (where ``guarded``) when the program runs: finite and not negative."""
    if combustion is None:
        return np.ones((cycles, n))
    c = combustion
    if is_tracer(c):
        if c.shape != (cycles, n):
            raise EngineError(
                f"combustion has shape {c.shape}: needs one scale per cycle and cylinder, ({cycles}, {n}); "
                "build it with rotor.combustion_pattern"
            )
        return guard_number(c, "combustion", 0.0, expected="combustion scales [-]") if guarded else c
    if isinstance(c, (str, bytes)) or np.asarray(c).dtype.kind not in "iuf":
        raise TypeError(f"combustion: expected real combustion scales [-], got {what_it_is(c)}")
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


@dataclasses.dataclass(frozen=True)
class RunPlan:
    """A run of :func:`simulate`, its arguments checked: what :func:`run_plan` carries out.

    **Fields:** ``engine`` (:class:`rotor.Engine`); ``train``: its tables
    (:class:`rotor.dynamics.crank_train.CrankTrain`); ``scene``: the numbers of the equation
    of motion (:class:`rotor.dynamics.equation.Scene`); ``cycles``; ``method``:
    ``"closed"``, ``"grid"``, ``"angle"`` or ``"time"`` (``"auto"`` resolved);
    ``fidelity``; ``points_per_cycle``: samples kept per cycle; ``stride``: table nodes per
    sample; ``rpm``: the start speed [rpm]; ``rtol``: the adaptive methods' tolerance (a
    float64 array); ``at_rest``: whether the run starts from rest; ``losses``: (a, c) of
    losses a + c·ω² constant in time, or None; ``governor``; ``steps_per_cycle``: as given
    (None: the default of ``"grid"``); ``step_deg`` and ``grid_deg`` [deg];
    ``stop_at_stall``; ``max_time_s`` [s] or None; ``keep_cycles`` or None; ``started``:
    ``time.perf_counter()`` when the call began [s].
    """

    engine: Engine
    train: CrankTrain
    scene: Scene
    cycles: int
    method: str
    fidelity: str
    points_per_cycle: int
    stride: int
    rpm: Any
    rtol: Any
    at_rest: bool
    losses: tuple[Any, Any] | None
    governor: Governor | None
    steps_per_cycle: int | None
    step_deg: float
    grid_deg: float
    stop_at_stall: bool
    max_time_s: float | None
    keep_cycles: int | None
    started: float


def simulate(
    engine: Engine | PreparedEngine,
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
    keep_cycles: int | None = None,
) -> SpeedResult:
    """Run the engine for ``cycles`` cycles from crank angle 0 at speed ``rpm``.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`, or a :class:`rotor.PreparedEngine` (its tables reused at the same fidelity and grid).
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
    - ``keep_cycles``: keep the samples of the last ``keep_cycles`` complete cycles only
      (None, the default: every sample). The per-cycle figures of every cycle are kept
      (:class:`rotor.dynamics.result.CycleSummary`), so that δ, the speeds and the range
      are those of the whole run; orders, plots and tables cover the kept cycles. A long run
      goes in chunks (:func:`chunk_cycles`) and needs memory for the kept samples only; a
      run whose samples would not fit is refused before it starts. Not under
      ``jax.grad``/``jax.vmap`` (keep every sample there).

    Every number may be traced (``jax.jit``, ``jax.vmap``, ``jax.grad``; a start from rest
    needs ``rpm=0`` known): a traced value is checked when the program runs
    (``eqx.error_if``), as a concrete one is at once, and a NaN, infinite or implausible
    speed, tolerance, engine field, load, governor or combustion scale raises a one-line
    error naming it.

    **Returns:** a :class:`rotor.SpeedResult` (``kind="transient"``).

    **Raises:** :class:`rotor.EngineError` for values out of range, a :class:`TypeError`
    for arguments of the wrong type, each naming the argument.
    """
    started = time.perf_counter()
    guarded = called_from_outside() and tracing()  # a caller's traced values: checked when they run
    if not isinstance(engine, PreparedEngine):
        require_engine(engine, "simulate(engine)")
    engine = resolve_engine(engine)  # a prepared engine: its tables are reused
    for name, value, kind in (("load", load, Load), ("governor", governor, Governor)):
        if value is not None and not isinstance(value, kind):
            raise TypeError(f"simulate({name}): expected a rotor.{kind.__name__} or None, got {what_it_is(value)}")
    if friction is not None and friction is not False and not isinstance(friction, Friction):
        raise TypeError(f"simulate(friction): expected a rotor.Friction, None or False, got {what_it_is(friction)}")
    if guarded:
        engine, load, governor = guard_engine(engine), guard_load(load), guard_governor(governor)
        friction = guard_fields(friction) if isinstance(friction, Friction) else friction
    plan = plan_run(
        engine,
        rpm,
        cycles,
        load,
        method=method,
        fidelity=fidelity,
        rtol=rtol,
        friction=friction,
        governor=governor,
        combustion=combustion,
        step_deg=step_deg,
        grid_deg=grid_deg,
        steps_per_cycle=steps_per_cycle,
        stop_at_stall=stop_at_stall,
        max_time_s=max_time_s,
        keep_cycles=keep_cycles,
        started=started,
        guarded=guarded,
    )
    # the progress bar hears from inside each compiled chunk (a host callback: the same
    # kernels, compiled once) and between chunks
    bar = Progress(plan.cycles, progress)
    try:
        result = run_plan(plan, bar)
    except KeyboardInterrupt:
        # Ctrl-C between two chunks: let the chunk already sent to XLA finish (well under a
        # second; none is left where the user switched JAX's asynchronous CPU dispatch off)
        # before the interpreter goes down, which it would otherwise do under it
        for x in jax.live_arrays():
            x.block_until_ready()
        raise
    finally:
        bar.close()
    check_speed_result(result)  # time increases, speeds finite, min ≤ mean ≤ max: else a SolverError
    return result


def _check_sizes(engine, cycles, keep_cycles, step_deg, grid_deg):
    """Refuse angles that are not positive numbers of degrees, and a run whose tables,
    per-cycle figures or kept samples would not fit in memory, before any work."""
    for name, value in (("step_deg", step_deg), ("grid_deg", grid_deg)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise TypeError(f"{name} = {value!r}: takes a number of degrees, not a {type(value).__name__}")
        if not (np.isfinite(value) and 0 < value <= 90):
            raise EngineError(f"{name} = {value!r}: must be a positive, finite angle in degrees (at most 90)")
    cycle_deg = 180.0 * engine.strokes
    n_cyl = int(engine.cylinders)
    check_size(
        (cycle_deg / grid_deg) * (8 + 4 * n_cyl) * 8 * 4,
        f"grid_deg = {grid_deg!r} ({cycle_deg / grid_deg:.3g} table nodes per cycle)",
        "give a coarser grid_deg (0.25° is the default)",
    )
    check_size(
        cycles * (CYCLE_BYTES + 16 * n_cyl),
        f"cycles = {cycles} (the per-cycle figures and combustion scales alone)",
        "run fewer cycles, or several runs one after another, each starting from the last one's speed",
    )
    P_est = cycle_deg / step_deg
    kept = cycles if keep_cycles is None else min(keep_cycles, cycles)
    check_size(
        kept * P_est * SAMPLE_BYTES,
        f"{'cycles' if keep_cycles is None else 'keep_cycles'} = {kept} with every sample kept "
        f"({P_est:.0f} per cycle at step_deg = {step_deg:g})",
        "keep only the last cycles' samples with keep_cycles=, or save fewer samples per cycle with a larger step_deg",
    )


def _pick_method(method, at_rest, losses):
    """The method of a run: ``method``, or for ``"auto"`` the cheapest valid one; an
    :class:`rotor.EngineError` for one that cannot run this scene."""
    if method == "auto":
        method = "time" if at_rest else ("closed" if losses is not None else "grid")
    if method == "closed" and losses is None:
        raise EngineError(
            "method='closed' needs losses a + c·ω² that do not change in time and no governor; "
            "use method='angle' (or 'auto')"
        )
    if method in ("closed", "grid", "angle") and at_rest:
        raise EngineError(
            f"method={method!r} works in the crank-angle domain and needs a start speed above 0; "
            "a start from rest needs method='time' (or 'auto')"
        )
    return method


def plan_run(
    engine: Engine,
    rpm: ArrayLike | None,
    cycles: int,
    load: Load | None,
    *,
    method: str,
    fidelity: str,
    rtol: ArrayLike | None,
    friction: Friction | Literal[False] | None,
    governor: Governor | None,
    combustion: ArrayLike | None,
    step_deg: float,
    grid_deg: float,
    steps_per_cycle: int | None,
    stop_at_stall: bool,
    max_time_s: float | None,
    keep_cycles: int | None,
    started: float,
    guarded: bool = False,
) -> RunPlan:
    """The arguments of :func:`simulate` checked (an :class:`rotor.EngineError` or a
    :class:`TypeError` naming the argument) and the engine's tables found: the
    :class:`RunPlan` of the run. ``guarded``: traced values (of a caller outside rotor)
    are checked when the program runs (``eqx.error_if``)."""
    if method not in METHODS:
        raise EngineError(f"method = {method!r}: must be one of {', '.join(map(repr, METHODS))}")
    cycles = _whole("cycles", cycles)
    if keep_cycles is not None:
        keep_cycles = _whole("keep_cycles", keep_cycles)
    _check_sizes(engine, cycles, keep_cycles, step_deg, grid_deg)
    rpm = engine.operating.rpm if rpm is None else rpm
    hi = PLAUSIBLE[("operating", "rpm")][1]
    for name, value in (("rpm", rpm), ("rtol", rtol)):
        if value is not None and not is_tracer(value) and _kind(value) not in "iuf":
            raise TypeError(f"{name}: expected a real number, got {what_it_is(value)}")
    r = concrete(rpm)
    if r is not None and not (r.ndim == 0 and np.isfinite(r) and 0 <= r <= hi):
        raise EngineError(
            f"rpm = {rpm!r}: the starting speed must be zero or a positive, finite speed in rpm, at most {hi:g}"
        )
    if guarded:  # a traced start speed: the run was planned in the angle domain, so above 0
        rpm = guard_number(rpm, "rpm", 0.0, hi, above=True, unit="rpm", expected="a start from rest is rpm=0, known")
    rtol = DEFAULT_RTOL if rtol is None else rtol
    rt = concrete(rtol)
    if rt is not None and not (rt.ndim == 0 and 1e-14 <= rt <= 1e-2):
        raise EngineError(f"rtol = {rtol!r}: must lie between 1e-14 and 1e-2")
    if guarded and is_tracer(rtol):  # checked with the start speed, which every method uses
        rt_traced = jnp.asarray(rtol)
        bad = ~((rt_traced >= 1e-14) & (rt_traced <= 1e-2))
        rpm, rtol = guard((jnp.asarray(rpm), rtol), bad, f"rtol: must lie between 1e-14 and 1e-2; {TRACED}")
    load, governor = arrays_only(load), arrays_only(governor)
    if keep_cycles is not None and keep_cycles < cycles:
        leaves = jax.tree_util.tree_leaves((rpm, rtol, load, governor, combustion, engine))
        if any(isinstance(x, jax.core.Tracer) for x in leaves):
            raise EngineError(
                "keep_cycles: a run that drops samples cannot be traced (jax.grad, jax.vmap, jax.jit); "
                "keep every sample there (keep_cycles=None)"
            )
    train = crank_train(engine, fidelity, grid_deg)
    P = int(round(train.cycle_rad / np.deg2rad(step_deg)))
    if P < 8 or train.points % P:
        raise EngineError(
            f"step_deg = {step_deg!r}: must be a multiple of grid_deg ({grid_deg:g}°) that divides the cycle"
        )
    scales = _check_scales(combustion, cycles, engine.cylinders, guarded)
    fr = friction_coefficients(engine, friction)
    at_rest = r is not None and r == 0
    losses = linear_losses(load, fr) if governor is None else None
    method = _pick_method(method, at_rest, losses)
    rtol_a = _f64(rtol)
    if load is None and governor is None:
        _warn_runaway(train, scales, fr, rpm)
    return RunPlan(
        engine=engine,
        train=train,
        scene=Scene(train, scales, fr, load, governor),
        cycles=cycles,
        method=method,
        fidelity=fidelity,
        points_per_cycle=P,
        stride=train.points // P,
        rpm=rpm,
        rtol=rtol_a,
        at_rest=at_rest,
        losses=losses,
        governor=governor,
        steps_per_cycle=steps_per_cycle,
        step_deg=step_deg,
        grid_deg=grid_deg,
        stop_at_stall=stop_at_stall,
        max_time_s=max_time_s,
        keep_cycles=keep_cycles,
        started=started,
    )


def _f64(x):
    """``x`` as a float64 array of strong type (one trace for every chunk): a NumPy array
    where it is concrete (no JAX operation to dispatch, or to compile in a new process)."""
    xp = array_module(x)
    return xp.asarray(x, dtype=xp.float64)


def _grid_steps(plan: RunPlan) -> int:
    """RK4 steps per cycle of ``method="grid"``: as given, or two per degree (one per saved
    sample if those are finer); an :class:`rotor.EngineError` for a count that does not fit."""
    P, steps_per_cycle = plan.points_per_cycle, plan.steps_per_cycle
    if steps_per_cycle is None:
        spc = max(int(round(2 * np.rad2deg(plan.train.cycle_rad))), P)
    else:
        spc = int(steps_per_cycle)
    if spc < 8 or spc % P:
        raise EngineError(
            f"steps_per_cycle = {steps_per_cycle!r}: needs a whole multiple of the {P} saved points per cycle "
            f"(step_deg = {plan.step_deg:g}); raise step_deg or steps_per_cycle"
        )
    check_size(
        spc * 3 * 8 * 4.0,
        f"steps_per_cycle = {spc}",
        "give fewer steps per cycle (the default is two per degree)",
    )
    return spc


@dataclasses.dataclass
class _Chunks:
    """A run's angle-domain part in chunks of ``size`` cycles, one compiled call each (the
    last padded past the end and cut); ``meter``: the progress bar's key for the kernels
    (an int32 array), or None."""

    plan: RunPlan
    size: int
    sink: Any
    bar: Progress
    meter: Any

    def part(self, done: int):
        """The scene of the chunk from cycle ``done`` and the chunk's start angle and first
        cycle in it: for a chunked run, the combustion scales of cycles done − 1 … done +
        size (clipped to the run) with the chunk starting one cycle in, so that the kernels
        see the same shapes in every chunk of every run and compile once (a short closed-form
        or grid run too: one chunk of the standard size, :func:`chunk_cycles`); else (a short
        adaptive run) the whole run's. Tells the progress bar which cycles the chunk covers."""
        plan, cyc = self.plan, self.plan.train.cycle_rad
        self.bar.within(done, self.size)
        if self.size >= plan.cycles and plan.method == "angle":
            return plan.scene, done * cyc, done
        rows = np.clip(np.arange(done - 1, done + self.size + 1), 0, plan.cycles - 1)
        scales = plan.scene.scales
        picked = scales[rows] if self._host_scales is None else jax.device_put(self._host_scales[rows])
        return eqx.tree_at(lambda s: s.scales, plan.scene, picked), cyc, 1

    @functools.cached_property
    def _host_scales(self) -> np.ndarray | None:
        """The run's combustion scales on the host (picked there for each chunk: no program
        per run length), or None while tracing."""
        scales = self.plan.scene.scales
        return None if is_tracer(scales) else np.asarray(scales)

    def valid(self, done: int) -> int:
        """The cycles of the chunk from cycle ``done`` that lie in the run."""
        return min(self.size, self.plan.cycles - done)


def _run_closed(chunks: _Chunks, E_now, t_now):
    """``method="closed"``: the run in closed form, chunk by chunk. Returns the hand-over
    to the time domain (θ, t, ω, z) after a stall, or None."""
    plan, P, cyc = chunks.plan, chunks.plan.points_per_cycle, chunks.plan.train.cycle_rad
    assert plan.losses is not None  # checked by plan_run
    a, c = plan.losses
    done = 0
    while done < plan.cycles:
        valid = chunks.valid(done)
        sc, _, first = chunks.part(done)
        E, t, E_end, t_end, stalled_at = closed_run(
            sc, a, c, E_now, t_now, jnp.asarray(first, dtype=jnp.int32), chunks.size, plan.stride, chunks.meter
        )
        k = min(int(_known(stalled_at, chunks.size)), valid)  # a stall in the padding is past the end
        if k == valid < chunks.size:  # the padding's first node is the state at the end of the run
            E_end, t_end = _sample(E, valid, 0), _sample(t, valid, 0)
        if k:
            chunks.sink.add_cycles(done, _theta_grid(done, k, P, cyc), *_first(k, t, E), None, None)
        done += k
        E_now, t_now = E_end, t_end
        chunks.bar.update(done)
        if k < valid:
            return (done * cyc, t_end, _omega_at(plan.train, done * cyc, E_end), 0.0)
    chunks.sink.add_extra(np.array([done * cyc]), t_now, E_now, None, None)
    return None


def _run_grid(chunks: _Chunks, spc: int, e_switch, E_now, t_now, z_now):
    """``method="grid"``: RK4 on the table grid, ``spc`` steps per cycle, chunk by chunk.
    Returns the hand-over to the time domain (θ, t, ω, z) after a stall, or None."""
    plan, P, cyc = chunks.plan, chunks.plan.points_per_cycle, chunks.plan.train.cycle_rad
    done = 0
    while done < plan.cycles:
        valid = chunks.valid(done)
        sc, th_start, _ = chunks.part(done)
        (E, t, z), y_end, stalled_at = grid_run(
            sc, _f64(th_start), (E_now, t_now, z_now), chunks.size, spc, spc // P, e_switch, chunks.meter
        )
        k = min(int(_known(stalled_at, chunks.size)), valid)
        if k == valid < chunks.size:  # the padding's first state is the state at the end of the run
            y_end = (_sample(E, valid, 0), _sample(t, valid, 0), _sample(z, valid, 0))
        if k:
            t_k, E_k, z_k = _first(k, t, E, z)
            chunks.sink.add_cycles(done, _theta_grid(done, k, P, cyc), t_k, E_k, None, z_k)
        done += k
        E_now, t_now, z_now = y_end[0], y_end[1], y_end[2]
        chunks.bar.update(done)
        if k < valid:
            return (done * cyc, t_now, _omega_at(plan.train, done * cyc, E_now), z_now)
    chunks.sink.add_extra(np.array([done * cyc]), t_now, E_now, None, z_now)
    return None


def _angle_chunk(chunks: _Chunks, done: int, e_switch, y_now):
    """One chunk of ``method="angle"`` from cycle ``done`` and state ``y_now`` = (E, t, z):
    the adaptive solve's samples with the chunk's start prepended (θ, t, E, z), its raw
    samples (E, t, z), the samples that lie in the run, the samples saved before a stall
    hand-over (or None), and the solver's steps. A failure to reach the chunk's end is an
    :class:`rotor.EngineError`."""
    plan, P, cyc = chunks.plan, chunks.plan.points_per_cycle, chunks.plan.train.cycle_rad
    theta_step = cyc / P
    valid = chunks.valid(done)
    need = valid * P
    th0 = done * cyc
    theta_out = th0 + np.arange(1, chunks.size * P + 1) * theta_step
    sc, th_start, _ = chunks.part(done)
    (E, t, z), end, stopped, ok, n_steps = angle_run(
        sc,
        _f64(th_start),
        y_now,
        th_start + np.arange(1, chunks.size * P + 1) * theta_step,
        plan.rtol,
        e_switch,
        4000 * chunks.size + 10000,
        chunks.meter,
    )
    stopped = bool(_known(stopped, False))
    ok = bool(_known(ok, True))
    reached = need
    if stopped or not ok:
        reached = int(np.sum(np.isfinite(np.asarray(E))))  # samples saved before the end
        if reached >= need:  # the hand-over or the failure fell in the padding past the run's end
            stopped, ok = False, True
    if not ok and not stopped:
        raise EngineError(
            f"the angle-domain solver could not reach the end of cycle {done + valid} "
            f"(stopped at crank angle {float(np.rad2deg(end[0] - th_start + th0)):.1f}°); "
            "try a looser rtol or method='time'"
        )
    # samples at θ_out[i] hold the state after step i; prepend the chunk's start
    th = np.concatenate([[th0], theta_out[:-1]])
    Es, ts, zs = _prepend(y_now, (E, t, z))
    return (th, ts, Es, zs), (E, t, z), theta_out, need, (reached if stopped else None), int(_known(n_steps, 0))


def _run_angle(chunks: _Chunks, e_switch, E_now, t_now, z_now):
    """``method="angle"``: the adaptive angle-domain solve, chunk by chunk. Returns the
    hand-over to the time domain (θ, t, ω, z) after a stall, or None, and the solver's
    steps."""
    plan, P, cyc = chunks.plan, chunks.plan.points_per_cycle, chunks.plan.train.cycle_rad
    steps = done = need = 0
    theta_out = np.zeros(1)
    while done < plan.cycles:
        valid = chunks.valid(done)
        (th, ts, Es, zs), (E, t, z), theta_out, need, reached, n_steps = _angle_chunk(
            chunks, done, e_switch, (E_now, t_now, z_now)
        )
        steps += n_steps
        if reached is not None:  # a stall: hand over at the start of the incomplete cycle
            whole = min(reached // P, valid)
            keep = whole * P
            if keep:
                th_k, ts_k, Es_k, zs_k = _first(keep, th, ts, Es, zs)
                chunks.sink.add_cycles(done, th_k, ts_k, Es_k, None, zs_k)
            done += whole
            if keep > 0:
                E_h, t_h, z_h = (_sample(a, keep - 1) for a in (E, t, z))
            else:
                E_h, t_h, z_h = E_now, t_now, z_now
            th_h = done * cyc
            return (th_h, t_h, _omega_at(plan.train, th_h, E_h), z_h), steps
        th_k, ts_k, Es_k, zs_k = _first(need, th, ts, Es, zs)
        chunks.sink.add_cycles(done, th_k, ts_k, Es_k, None, zs_k)
        E_now, t_now, z_now = (_sample(a, need - 1) for a in (E, t, z))
        done += valid
        chunks.bar.update(done)
    chunks.sink.add_extra(theta_out[need - 1 : need], t_now, E_now, None, z_now)
    return None, steps


def _run_time_domain(plan: RunPlan, handover, omega0, extras: dict[str, Any]):
    """The time domain from the hand-over (θ, t, ω, z) to the end of the run, or to a
    stall. Returns its steps (θ, t, ω, z, the solution, the reference speed), whether it
    stalled, and the stall's time [s] and angle [rad] (or None); a run that ends short of
    the end says so in ``extras["incomplete"]``."""
    th_h, t_h, w_h, z_h = handover
    theta_end = plan.cycles * plan.train.cycle_rad
    w_ref = omega0 if not plan.at_rest else plan.engine.operating.omega
    if plan.governor is not None and plan.at_rest:
        w_ref = plan.governor.omega
    if plan.max_time_s is None:
        t_max = float(t_h) + 20.0 * (theta_end - float(th_h)) / float(w_ref) + 10.0
    else:
        t_max = float(t_h) + float(plan.max_time_s)
    ts, (th, w, z), mask, ok, sol = time_run(
        plan.scene,
        _f64(t_h),
        (_f64(th_h), _f64(w_h), _f64(z_h)),
        jnp.asarray(theta_end),
        jnp.asarray(t_max),
        plan.rtol,
        _f64(w_ref),
        plan.stop_at_stall,
        TIME_DOMAIN_STEPS,
    )
    ts_np = np.asarray(ts)
    keep = np.isfinite(ts_np)
    # an event on the last step saves that step's end twice: keep the later (located) state
    keep[:-1] &= ~(ts_np[:-1] == ts_np[1:])
    ts, th, w, z = (np.asarray(a)[keep] for a in (ts, th, w, z))  # on the host: no program per length
    stalled, stall_t, stall_th = False, None, None
    if plan.stop_at_stall and bool(mask[1]):
        stalled = True
        stall_t, stall_th = float(ts[-1]), float(th[-1])
    elif not bool(mask[0]):
        extras["incomplete"] = (
            f"the time-domain run ended at t = {float(ts[-1]):.3f} s, crank angle "
            f"{float(np.rad2deg(th[-1])):.1f}°, before reaching the end of cycle {plan.cycles}"
            + ("" if bool(ok) else " (step limit)")
        )
    return (th, ts, w, z, sol, w_ref), stalled, stall_t, stall_th


def run_plan(plan: RunPlan, bar: Progress) -> SpeedResult:
    """Carry out ``plan`` (:func:`plan_run`), reporting to the progress bar ``bar``: the
    angle-domain methods in chunks of :func:`chunk_cycles` cycles (one compiled call each;
    the last padded past the end and cut), each chunk's samples handed to a sink that keeps
    them all or only the last ``keep_cycles`` cycles' with per-cycle summaries of every
    cycle; after a stall, or for ``method="time"``, the time domain."""
    train, P, cycles, method = plan.train, plan.points_per_cycle, plan.cycles, plan.method
    # the speed as an array: a Python float would be a constant of the compiled program, one per speed
    omega0, E0, e_switch = _start(train, _f64(plan.rpm))
    streaming = plan.keep_cycles is not None and plan.keep_cycles < cycles
    sink: _AllSamples | _LastCycles = (
        _LastCycles(plan.scene, P, train.cycle_rad, plan.keep_cycles, cycles)
        if streaming
        else _AllSamples(plan.scene, P)
    )
    extras: dict[str, Any] = {}  # typed fields of the result: steps_per_cycle, solver_steps, incomplete
    spc = _grid_steps(plan) if method == "grid" else 0
    size = chunk_cycles(method, cycles, spc, train.points) if method != "time" else cycles
    # the progress bar: from inside each chunk (a host callback with the bar's key), and between chunks
    meter = jnp.asarray(bar.key, dtype=jnp.int32) if bar.enabled else None
    chunks = _Chunks(plan, size, sink, bar, meter)
    E_now, t_now, z_now = _f64(E0), _f64(0.0), _f64(0.0)
    if method == "closed":
        handover = _run_closed(chunks, E_now, t_now)
    elif method == "grid":
        handover = _run_grid(chunks, spc, e_switch, E_now, t_now, z_now)
        extras["steps_per_cycle"] = spc
    elif method == "angle":
        handover, extras["solver_steps"] = _run_angle(chunks, e_switch, E_now, t_now, z_now)
    else:
        handover = (0.0, 0.0, omega0, 0.0)
    stalled, stall_t, stall_th, time_domain = False, None, None, None
    if handover is not None:
        time_domain, stalled, stall_t, stall_th = _run_time_domain(plan, handover, omega0, extras)
        method = "time" if method == "time" else f"{method}+time"
    return _assemble(
        plan.engine,
        train,
        plan.scene,
        sink,
        time_domain,
        method,
        plan.fidelity,
        P,
        stalled,
        stall_t,
        stall_th,
        plan.started,
        extras,
    )


@kept_program()
@eqx.filter_jit
def _samples(scene, theta, t, E, omega, z):
    """ω (from E where given), engine and load torque, dω/dt and fuel at the samples."""
    return _samples_at(scene, theta, t, E, omega, z)


def _samples_at(scene, theta, t, E, omega, z):
    """:func:`_samples`, not compiled on its own (inside another compiled call)."""
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


@kept_program()
@eqx.filter_jit
def _start(train, rpm):
    """ω0 [rad/s] and kinetic energy [J] at the start, θ = 0, and the energy [J] below
    which the angle domain hands over to the time domain."""
    omega0 = jnp.asarray(rpm, dtype=jnp.float64) / RPM_PER_RAD_S
    inertia0 = train.at(0.0)[0][0]
    return omega0, 0.5 * inertia0 * omega0**2, 0.5 * train.mean_inertia * (STALL_HANDOVER * omega0) ** 2


@kept_program()
@jax.jit
def _prepend(first, rest):
    """Each array of ``rest`` shifted one place on, its first place taken by ``first``."""
    return tuple(jnp.concatenate([jnp.reshape(a, (1,)), b[:-1]]) for a, b in zip(first, rest))


@eqx.filter_jit
def _omega_at(train, theta, E):
    return jnp.sqrt(2 * jnp.maximum(E, 0.0) / train.at(theta)[0][0])


def _cycle_samples(scene, first, t, E, omega, z, P: int):
    """:func:`_samples` for whole cycles saved on the table nodes (θ = k·Θ + p·Θ/P, cycle
    k from ``first``; t, E or ω, z flat, P per cycle): the tables' own node values, no
    interpolation, and each cylinder's combustion scale by its firing window at the node
    (as :func:`rotor.dynamics.equation.closed_run` uses it) as three small matrix products,
    no per-sample gather."""
    train = scene.train
    stride = train.points // P
    k = t.shape[0] // P
    val, der = train.values[::stride], train.slopes[::stride]  # (P, columns)
    off = node_offsets(train)[:-1:stride]  # (P, cylinders): -1, 0 or 1 cycles from the sample's
    rows = first + jnp.arange(k)
    last = scene.scales.shape[0] - 1
    comb = sum(
        scene.scales[jnp.clip(rows + o, 0, last)] @ jnp.where(off == o, val[:, COL_COMBUSTION:], 0.0).T
        for o in (-1, 0, 1)
    )  # (k, P): Σ_c s·ΔM_c
    t = t.reshape(k, P)
    z = jnp.zeros_like(t) if z is None else z.reshape(k, P)
    inertia, dinertia = val[:, COL_I], der[:, COL_I]
    if E is not None:
        omega = jnp.sqrt(2 * jnp.maximum(E.reshape(k, P), 0.0) / inertia)
    else:
        omega = omega.reshape(k, P)
    fuel = scene.fuel(omega, z)
    m_eng = val[:, COL_MOTORED] + fuel * comb + val[:, COL_K] * omega**2
    m_loss = scene.loss(omega, t)
    accel = (m_eng - m_loss - 0.5 * dinertia * omega**2) / inertia
    return tuple(jnp.reshape(a, (-1,)) for a in (omega, m_eng, m_loss, accel, fuel))


@kept_program(static_argnames=("P",))
@eqx.filter_jit
def _gather(scene, pieces, P: int):
    """All pieces (first cycle or None, θ, t, E or None, ω or None, z or None), flat, as the
    flat sample arrays (θ, t, ω, engine torque, load torque, dω/dt, fuel), in one compiled
    call. A piece with a first cycle holds whole cycles on the table nodes (:func:`_cycle_samples`)."""
    parts = []
    for first, th, t, E, w, z in pieces:
        if first is not None:
            parts.append((th, t) + _cycle_samples(scene, first, t, E, w, z, P))
        else:
            z = jnp.zeros_like(th) if z is None else z
            parts.append((th, t) + _samples_at(scene, th, t, E, w, z))
    if len(parts) == 1:
        return parts[0]
    return tuple(jnp.concatenate(a) for a in zip(*parts))


def _first(n: int, *arrays: Any) -> tuple[Any, ...]:
    """The first ``n`` rows of each array: cut on the host for concrete values (a cut of a
    JAX array compiles a program for every ``n``)."""
    return tuple(a[:n] if is_tracer(a) else np.asarray(a)[:n] for a in arrays)


def _flat(a):
    """``a`` flat in float64: on the host for concrete values (no program per length)."""
    if a is None:
        return None
    if is_tracer(a):
        return jnp.reshape(jnp.asarray(a, dtype=jnp.float64), (-1,))
    return np.asarray(a, dtype=np.float64).reshape(-1)


def _padded_piece(piece: tuple[Any, ...], P: int) -> tuple[tuple[Any, ...], int]:
    """A concrete piece of the samples (:func:`_gather`) padded to a standard length
    (:func:`rotor.cache.padded_size`: whole cycles for a piece of them, samples else) by
    repeating its last cycle or sample, so that a run of another length reuses the compiled
    gather; and its length before."""
    n = piece[1].shape[0]
    per = P if piece[0] is not None else 1
    units = n // per
    extra = (padded_size(max(units, 1)) - units) * per
    if not extra:
        return piece, n

    def pad(a):
        if a is None:
            return None
        tail = a[n - per :]
        return np.concatenate([a, np.tile(tail, extra // per)])

    return (piece[0],) + tuple(pad(a) for a in piece[1:]), n


@kept_program(static_argnames=("P",))
@eqx.filter_jit
def _chunk_figures(scene, first, th, t, E, w, P: int, z=None):
    """The samples of whole cycles from cycle ``first`` (:func:`_cycle_samples`, flat) and
    per cycle: its start time, mean engine torque and highest and lowest speed, in one
    compiled call."""
    arrays = (th, t) + _cycle_samples(scene, first, t, E, w, z, P)
    k = th.shape[0] // P
    omega, torque = arrays[2].reshape(k, P), arrays[3].reshape(k, P)
    return arrays, t.reshape(k, P)[:, 0], jnp.mean(torque, axis=1), jnp.max(omega, axis=1), jnp.min(omega, axis=1)


class _AllSamples:
    """Keeps every sample of a run (``keep_cycles=None``): the pieces, computed into the
    result's arrays at the end in one compiled call."""

    def __init__(self, scene, P):
        self.scene, self.P = scene, P
        self.parts: list[tuple[Any, ...]] = []
        self.uniform = 0

    def add_cycles(self, first, th, t, E, w, z):
        """Samples of whole cycles from cycle ``first`` on the table nodes (θ, t, E or ω,
        z or None; any shape, P per cycle)."""
        part = (int(first),) + tuple(_flat(a) for a in (th, t, E, w, z))
        self.parts.append(part)
        self.uniform += part[1].shape[0] // self.P

    def add_extra(self, th, t, E, w, z):
        """Samples after the last whole cycle (the run's end, a time-domain tail)."""
        part = (None,) + tuple(_flat(a) for a in (th, t, E, w, z))
        if part[1].shape[0]:
            self.parts.append(part)

    def finish(self):
        """(θ, t, ω, engine torque, load torque, dω/dt, fuel), whole cycles, first kept cycle, summary."""
        # consecutive pieces of one kind joined (whole cycles: consecutive ones): a compiled
        # call over a few pieces, not one per chunk
        groups: list[list[tuple[Any, ...]]] = []
        for p in self.parts:
            kind = tuple(a is None for a in p)
            if groups and tuple(a is None for a in groups[-1][0]) == kind:
                g = groups[-1]
                if p[0] is None or p[0] == g[-1][0] + g[-1][1].shape[0] // self.P:
                    g.append(p)
                    continue
            groups.append([p])
        pieces = tuple(
            g[0]
            if len(g) == 1
            else (g[0][0],)
            + tuple(
                None if g[0][i] is None else array_module(*(p[i] for p in g)).concatenate([p[i] for p in g])
                for i in range(1, 6)
            )
            for g in groups
        )
        concrete_pieces = not any(is_tracer(a) for p in pieces for a in p[1:])
        lengths = None
        if concrete_pieces:  # each piece padded to a standard length, cut back on the host
            padded = [_padded_piece(p, self.P) for p in pieces]
            pieces, lengths = tuple(q for q, _ in padded), [n for _, n in padded]
        # the first cycle as an array: a new first cycle compiles nothing
        pieces = tuple((None if p[0] is None else np.asarray(p[0], dtype=np.int32),) + p[1:] for p in pieces)
        scene = self.scene
        if concrete_pieces and not is_tracer(scene.scales):
            # the scales of each cycle likewise: the rows past the run copies of its last
            scales = np.asarray(scene.scales)
            rows = padded_size(max(scales.shape[0], 1)) - scales.shape[0]
            if rows:
                scene = eqx.tree_at(
                    lambda s: s.scales, scene, np.concatenate([scales, np.repeat(scales[-1:], rows, 0)])
                )
        arrays = _gather(scene, pieces, self.P)
        if lengths is not None:
            starts = np.cumsum([0] + [p[1].shape[0] for p in pieces])
            keep = np.concatenate([np.arange(a, a + n) for a, n in zip(starts[:-1], lengths)])
            arrays = tuple(jax.device_put(np.asarray(a)[keep]) for a in arrays)
        return arrays, self.uniform, 0, None


class _LastCycles:
    """Keeps the samples of the last ``keep`` whole cycles (and those after them) and the
    per-cycle figures of every cycle (:class:`rotor.dynamics.result.CycleSummary`): a long
    run in bounded memory.

    A cycle's δ needs its trend, from its neighbours' mean speeds (:mod:`rotor.cycles`),
    and the samples next to its first and last; it is computed once the next cycle's mean
    is known, over a window of rows with one row of context on each side, so that every
    figure equals that of a run that keeps every sample."""

    def __init__(self, scene, P, cycle_rad, keep, cycles):
        self.scene, self.P, self.cycle_rad, self.keep = scene, P, cycle_rad, keep
        n = cycles + 1
        self.t_start, self.t_end, self.mean, self.mean_torque = (np.zeros(n) for _ in range(4))
        self.max, self.min, self.delta, self.rmax, self.rmin = (np.zeros(n) for _ in range(5))
        self.done = 0  # whole cycles received
        self.final = 0  # cycles whose δ and refined extremes are known
        self.rows: tuple[Any, ...] | None = None  # (θ, t, ω, M_eng, M_loss, dω/dt, fuel), each (rows, P)
        self.first_row = 0  # the cycle of rows[.][0]
        self.extra: list[tuple[Any, ...]] = []
        self.hi, self.lo = -np.inf, np.inf
        self.first: tuple[float, float] | None = None

    def _extremes_of(self, arrays):
        w = arrays[2]
        if w.size:
            self.hi, self.lo = max(self.hi, float(np.max(w))), min(self.lo, float(np.min(w)))
        if self.first is None and w.size:
            self.first = (float(arrays[0][0]), float(arrays[1][0]))

    def add_cycles(self, first, th, t, E, w, z):
        """Samples of whole cycles from cycle ``first`` on the table nodes (θ, t, E or ω,
        z or None; any shape, P per cycle)."""
        k = int(np.size(th)) // self.P
        if k == 0:
            return
        th, t, E, w, z = (_flat(a) for a in (th, t, E, w, z))
        arrays, t_start, mean_torque, w_max, w_min = _chunk_figures(
            self.scene, jnp.asarray(first, dtype=jnp.int32), th, t, E, w, self.P, z
        )
        rows = tuple(np.asarray(a).reshape(k, self.P) for a in arrays)  # numpy from here: no compiling per shape
        self._extremes_of(tuple(a.reshape(-1) for a in rows))
        d = self.done
        ts = np.asarray(t_start)
        self.t_start[d : d + k] = ts
        if d > 0:
            self.t_end[d - 1] = ts[0]
        self.t_end[d : d + k - 1] = ts[1:]
        self.mean[max(d - 1, 0) : d + k - 1] = self.cycle_rad / (
            self.t_end[max(d - 1, 0) : d + k - 1] - self.t_start[max(d - 1, 0) : d + k - 1]
        )
        self.mean_torque[d : d + k] = np.asarray(mean_torque)
        self.max[d : d + k] = np.asarray(w_max)
        self.min[d : d + k] = np.asarray(w_min)
        self.rows = rows if self.rows is None else tuple(np.concatenate([a, b]) for a, b in zip(self.rows, rows))
        self.done += k
        self._finalize(at_end=False)
        # keep one row of context before the pending ones, and the last ``keep`` rows
        new_first = max(0, min(self.final - 1, self.done - self.keep))
        if new_first > self.first_row:
            cut = new_first - self.first_row
            self.rows = tuple(a[cut:] for a in self.rows)
            self.first_row = new_first

    def add_extra(self, th, t, E, w, z):
        """Samples after the last whole cycle (the run's end, a time-domain tail)."""
        th, t, E, w, z = (_flat(a) for a in (th, t, E, w, z))
        if th.shape[0]:
            z = jnp.zeros_like(th) if z is None else z
            arrays = tuple(np.asarray(a) for a in (th, t) + tuple(_samples(self.scene, th, t, E, w, z)))
            self._extremes_of(arrays)
            self.extra.append(arrays)

    def _finalize(self, at_end: bool) -> None:
        D, f = self.done, self.final
        if at_end:  # every mean known; the last row has no neighbour after it
            last, known = D - 1, D
            a = max(min(f - 1, D - 3), 0)
        else:  # means known below D − 1; row D − 2 is context after the last finished row
            last, known = D - 3, D - 1
            a = max(f - 1, 0)
            if known - a < 3:
                return
        if last < f:
            return
        slopes = cycle_slopes(jnp.asarray(self.mean[a:known]), self.cycle_rad)  # rows a … known − 1
        lo = max(f - 1, 0)
        hi = D if at_end else D - 1  # rows lo … hi − 1 go in
        assert self.rows is not None and lo >= self.first_row
        x = self.rows[2][lo - self.first_row : hi - self.first_row]
        dmax, dmin, rmax, rmin = cycle_extremes(x, slopes[lo - a : hi - a], self.cycle_rad)
        sel = slice(f - lo, last + 1 - lo)
        self.delta[f : last + 1] = np.asarray(cycle_delta(dmax[sel], dmin[sel], jnp.asarray(self.mean[f : last + 1])))
        self.rmax[f : last + 1] = np.asarray(rmax[sel])
        self.rmin[f : last + 1] = np.asarray(rmin[sel])
        self.final = last + 1

    def finish(self):
        """(θ, t, ω, engine torque, load torque, dω/dt, fuel), whole cycles, first kept cycle, summary."""
        D = self.done
        extra = [tuple(a) for a in self.extra]
        if D > 0:
            assert self.rows is not None
            if extra:
                self.t_end[D - 1] = float(extra[0][1][0])
            else:  # no sample after the last cycle: its end from the last sample's speed
                self.t_end[D - 1] = float(self.rows[1][-1, -1] + (self.cycle_rad / self.P) / self.rows[2][-1, -1])
            self.mean[D - 1] = self.cycle_rad / (self.t_end[D - 1] - self.t_start[D - 1])
            self._finalize(at_end=True)
        kept = min(self.keep, D)
        first_kept = D - kept
        parts = []
        if kept:
            assert self.rows is not None
            parts.append(tuple(a[first_kept - self.first_row :].reshape(-1) for a in self.rows))
        parts += extra
        arrays = tuple(jnp.asarray(np.concatenate([p[i] for p in parts])) for i in range(7))
        summary = None
        if first_kept > 0:
            assert self.first is not None
            summary = CycleSummary(
                t_start_s=self.t_start[:D].copy(),
                t_end_s=self.t_end[:D].copy(),
                mean_omega=self.mean[:D].copy(),
                mean_torque_Nm=self.mean_torque[:D].copy(),
                max_omega=self.max[:D].copy(),
                min_omega=self.min[:D].copy(),
                delta=self.delta[:D].copy(),
                range_max=self.rmax[:D].copy(),
                range_min=self.rmin[:D].copy(),
                omega_max_all=self.hi,
                omega_min_all=self.lo,
                theta_first_rad=self.first[0],
                t_first_s=self.first[1],
            )
        return arrays, D, first_kept, summary


def _assemble(engine, train, scene, sink, time_domain, method, fidelity, P, stalled, stall_t, stall_th, wall, extras):
    if time_domain is not None:
        for th, t, w, z, whole in _resample(scene, time_domain, P):
            n = whole * P
            if n:  # whole cycles start on a cycle boundary (:func:`_resample`)
                sink.add_cycles(int(round(float(th[0]) / train.cycle_rad)), th[:n], t[:n], None, w[:n], z[:n])
            if th.shape[0] > n:
                sink.add_extra(th[n:], t[n:], None, w[n:], z[n:])
    (theta, t, omega, m_eng, m_loss, accel, fuel), uniform, first_kept, summary = sink.finish()
    imep = _imep(train, scene.scales)
    given_load, given_fuel = given_operating_point(scene.load, scene.scales, scene.governor is not None)
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
        first_kept_cycle_index=first_kept,
        cycle_summary=summary,
        load_torque_Nm=given_load,
        fuel_scale=given_fuel,
        **extras,
    )


@kept_program()
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
