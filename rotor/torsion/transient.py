"""Torsional transients in time: the whole chain integrated by diffrax from a given start.

The equations are those of :mod:`rotor.torsion.response` (each throw mass with its
cylinders' I_c(θ_j), I_c′(θ_j) and gas torque at its own angle; damping on the vibratory
speeds θ̇ − ω̄ about the run's nominal speed ω̄), integrated in time with the state
(θ_ref, the n − 1 twists θ_i − θ_{i+1}, the n speeds): the twists are states of their own
so that a stiff shaft's torque k·(θ_i − θ_{i+1}) never comes from the difference of two
angles that have grown to thousands of radians.

**Solver.** The chain is *stiff* when its stiffest mode is far faster than what the engine
makes it do: an explicit Runge–Kutta step must stay below about 3/ω_max for stability
(ω_max the highest natural frequency [rad/s]), whatever accuracy asks. ``solver="auto"``
takes diffrax's implicit, L-stable ``Kvaerno5`` (ESDIRK, 5th order) where that stability
limit alone would force more than 2000 steps per engine cycle (ω_max·T_cycle/3 > 2000,
T_cycle the cycle's period at the nominal speed: e.g. the MWM six's chain with 10⁴-times
stiffer shafts, 300 kHz modes against a 55 ms cycle); otherwise, and for a free chain,
the explicit ``Dopri8`` (8th order, 7th-order dense output), which at tight tolerances takes
about as many steps as the gas torque's shape needs anyway (the MWM chain's 3 kHz top mode
at 2200 rpm: ω_max·T/3 ≈ 340). Both with a PID step-size controller at ``rtol``.

**Samples.** An engine run is sampled, like a trigger wheel, at uniform angles of the
reference mass (the load mass, usually the flywheel): the times where θ_ref passes each
node are found by Newton's method on the solver's dense output, and every mass's angle
and speed are taken there; the run ends when the reference has turned ``cycles`` whole
cycles (an event). A free chain (no engine) is sampled at uniform times.

**Energy.** Without damping, load and gas torque (a free chain, or zero pressure),
½·Σ A_j(θ_j)·θ̇_j² + ½·Σ k_i·(θ_i − θ_{i+1})² is conserved (``energy_J``): the test
of the integrator: Dopri8 at rtol 1e-13 keeps it to 2e-10 over 1000 periods of a two-mass
chain (rtol 1e-12: 1.5e-9; 1e-14: 3e-11; the error grows with the number of steps). One
cycle of the MWM chain at 1500 rpm takes about 600 Dopri8 steps at rtol 1e-8 (1.2 s after
compile, about 10 s the first time) and 1800 at rtol 1e-11.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, ArrayLike

from ..checks import check_size
from ..dynamics.loads import ConstantLoad, Load
from ..engine.friction import Friction
from ..engine.model import Engine
from ..engine.plausible import PLAUSIBLE, require_number, require_whole, what_it_is
from ..errors import EngineError, SolverError
from ..results import Result, json_safe
from ..units import RPM_PER_RAD_S
from .driven import DrivenChain, driven_chain, mass_index, section_names
from .model import TorsionalChain
from .modes import natural_frequencies
from .response import TorsionalResponse

__all__ = ["TorsionalRun", "torsional_simulate", "SOLVERS", "STIFF_STEPS"]

SOLVERS = ("auto", "kvaerno5", "dopri8")
#: explicit steps per cycle that stability alone would force, above which ``solver="auto"``
#: takes the implicit Kvaerno5
STIFF_STEPS = 2000
#: memory per sample and mass kept [bytes] (angles, speeds, twists, torques, the search)
SAMPLE_BYTES = 8 * 12


class _Scene(eqx.Module):
    """What the vector field needs: the driven chain, the load, the nominal speed and the
    state's scales (the solver sees every state of order one)."""

    dc: DrivenChain
    load: Load
    omega_ref: Array  # ω̄ [rad/s]: the damping's reference
    angle_scale: Array  # [rad]
    twist_scale: Array  # [rad]
    speed_scale: Array  # [rad/s]
    time_scale: Array  # [s]

    def unscale(self, y):
        a, d, w = y
        return a * self.angle_scale, d * self.twist_scale, w * self.speed_scale

    def angles(self, theta_ref: Array, twist: Array) -> Array:
        """Every mass's angle from the reference's and the twists θ_i − θ_{i+1}."""
        ref = self.dc.reference_mass
        # θ_j − θ_ref = Σ_{i=j}^{ref−1} d_i (j < ref), −Σ_{i=ref}^{j−1} d_i (j > ref)
        c = jnp.concatenate([jnp.zeros(1), jnp.cumsum(twist)])  # c_j = θ_0 − θ_j
        return theta_ref + c[ref] - c

    def field(self, s, y, args):
        dc = self.dc
        t = s * self.time_scale
        theta_ref, twist, omega = self.unscale(y)
        theta = self.angles(theta_ref, twist)
        A, dA = dc.inertias(theta)
        torque = dc.gas_torques(theta) - dc.friction_torques(omega) - dc.damping_torques(omega, self.omega_ref)
        torque = torque.at[dc.load_mass].add(-self.load.torque(omega[dc.load_mass], t))
        shaft = dc.stiffnesses * twist  # the shafts' springs (their damping is in dc.damping)
        torque = torque.at[:-1].add(-shaft).at[1:].add(shaft)
        accel = (torque - 0.5 * dA * omega**2) / A
        T = self.time_scale
        return (
            omega[dc.reference_mass] * T / self.angle_scale,
            (omega[:-1] - omega[1:]) * T / self.twist_scale,
            accel * T / self.speed_scale,
        )


def _solver(name: str):
    return dfx.Kvaerno5() if name == "kvaerno5" else dfx.Dopri8()


@eqx.filter_jit
def _run_kernel(scene: _Scene, y0, s_end, rtol, solver: str, max_steps: int, theta_end, theta_q, s_q, by_angle: bool):
    """Integrate from y0 (scaled) to s_end (scaled time) or until θ_ref reaches ``theta_end``
    (angle runs); samples at the reference angles ``theta_q`` (``by_angle``) or the
    scaled times ``s_q``. Returns (t, θ, ω) at the samples, whether it finished, steps."""
    event = None
    if by_angle:
        event = dfx.Event(lambda t, y, args, **kw: y[0] * scene.angle_scale - theta_end)
    sol = dfx.diffeqsolve(
        dfx.ODETerm(scene.field),
        _solver(solver),
        0.0,
        s_end,
        None,
        y0,
        saveat=dfx.SaveAt(t1=True, dense=True) if by_angle else dfx.SaveAt(ts=s_q),
        stepsize_controller=dfx.PIDController(rtol=rtol, atol=rtol),
        event=event,
        max_steps=max_steps,
        throw=False,
    )
    ok = sol.result == dfx.RESULTS.successful
    if by_angle:
        ok = (sol.result == dfx.RESULTS.event_occurred) & jnp.any(sol.event_mask)
        assert sol.ts is not None
        s_last = sol.ts[-1]
        w0 = y0[2][scene.dc.reference_mass] * scene.speed_scale * scene.time_scale  # rad per unit scaled time
        a0 = y0[0] * scene.angle_scale

        def find(th_q):
            guess = jnp.clip((th_q - a0) / w0, 0.0, s_last)
            root = optx.root_find(
                lambda s, _: sol.evaluate(jnp.clip(s, 0.0, s_last))[0] * scene.angle_scale - th_q,
                optx.Newton(rtol=1e-14, atol=1e-12),
                guess,
                max_steps=30,
                throw=False,
            )
            s = jnp.clip(root.value, 0.0, s_last)
            return s, sol.evaluate(s)

        s_samples, ys = jax.vmap(find)(theta_q)
    else:
        s_samples, ys = s_q, sol.ys
    theta_ref, twist, omega = jax.vmap(scene.unscale)(ys)
    theta = jax.vmap(scene.angles)(theta_ref, twist)
    return s_samples * scene.time_scale, theta, omega, ok, sol.stats["num_steps"]


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class TorsionalRun(Result):
    """A torsional transient (:func:`torsional_simulate`).

    **Samples** (S of them; ``sampled_by``: ``"angle"``, at uniform angles of the reference
    mass, ``points_per_cycle`` a cycle, for an engine; ``"time"``, at uniform times, for a
    free chain): ``t`` [s]; per mass (S, n): ``angle_rad`` [rad], ``omega`` [rad/s]; per
    section (S, n − 1): ``twist_rad`` (θ_i − θ_{i+1}) [rad], ``torque_Nm`` [N·m];
    ``energy_J`` (S,): kinetic plus elastic energy [J].

    **About:** ``rpm`` (nominal speed) [rpm]; ``load_torque_Nm`` (the constant load, when
    one was given or balanced; else None) [N·m]; ``cycles`` (complete cycles sampled);
    ``solver``; ``rtol``; ``steps`` (accepted solver steps); ``mass_names``;
    ``reference_mass``, ``load_mass`` (0-based); ``engine_name``; ``strokes``;
    ``cycle_rad`` [rad]; ``wall_s``.
    """

    t: ArrayLike
    angle_rad: ArrayLike
    omega: ArrayLike
    twist_rad: ArrayLike
    torque_Nm: ArrayLike
    energy_J: ArrayLike
    sampled_by: str
    points_per_cycle: int
    cycles: int
    rpm: float
    load_torque_Nm: Any
    solver: str
    rtol: float
    steps: int
    mass_names: tuple[str, ...]
    reference_mass: int
    load_mass: int
    engine_name: str
    strokes: int
    cycle_rad: float
    wall_s: float = float("nan")

    @property
    def section_names(self) -> tuple[str, ...]:
        """The shaft sections, ``"front mass–rear mass"``."""
        return section_names(self.mass_names)

    def mass_index(self, mass: int | str | None) -> int:
        """The 0-based index of ``mass`` (an index, a name, or None: the reference mass)."""
        return mass_index(self.mass_names, self.reference_mass, mass)

    def speed_cycles(self, mass: int | str | None = None) -> np.ndarray:
        """The speed of ``mass`` (default the reference mass) at the reference mass's uniform
        crank angles, one row per complete cycle: (cycles, points_per_cycle) [rad/s], what
        :func:`rotor.identify` takes (as a trigger wheel on the reference mass would log it,
        when ``mass`` is the reference)."""
        if self.sampled_by != "angle":
            raise ValueError("speed_cycles: a free chain's run is sampled in time, not by crank angle")
        j = self.mass_index(mass)
        P = self.points_per_cycle
        return np.asarray(self.omega)[: self.cycles * P, j].reshape(self.cycles, P)

    @property
    def energy_drift(self) -> float:
        """max |E − E₀| / E₀ over the run [-] (meaningful for a conservative run)."""
        e = np.asarray(self.energy_J)
        return float(np.max(np.abs(e - e[0])) / abs(e[0])) if e.size and e[0] != 0 else float("nan")

    def summary(self) -> str:
        """The run: length, solver, each mass's speed range and each section's torque range."""
        t = np.asarray(self.t)
        w = np.asarray(self.omega) * RPM_PER_RAD_S
        tq = np.asarray(self.torque_Nm)
        what = f"{self.cycles} cycles" if self.sampled_by == "angle" else f"{t[-1] - t[0]:.4g} s"
        lines = [
            f"{self.engine_name}: torsional transient, {what} from {self.rpm:g} rpm ({len(self.mass_names)} masses; "
            f"{self.solver}, rtol {self.rtol:g}, {self.steps} steps)",
        ]
        if self.load_torque_Nm is not None:
            lines.append(f"  constant load {float(self.load_torque_Nm):.2f} N·m at {self.mass_names[self.load_mass]}")
        lines += ["", f"  {'mass':<16} {'min rpm':>10} {'max rpm':>10}"]
        for j, name in enumerate(self.mass_names):
            lines.append(f"  {name:<16} {w[:, j].min():10.2f} {w[:, j].max():10.2f}")
        lines += ["", f"  {'section':<28} {'min [N·m]':>11} {'max [N·m]':>11}"]
        for i, name in enumerate(self.section_names):
            lines.append(f"  {name:<28} {tq[:, i].min():11.1f} {tq[:, i].max():11.1f}")
        return "\n".join(lines[:60]) + "\n"

    def to_pandas(self) -> Any:
        """One row per sample and mass (tidy): ``t_s``, ``mass``, ``angle_rad``,
        ``omega_rad_s``, ``rpm``."""
        import pandas as pd

        S, n = np.shape(self.omega)
        w = np.asarray(self.omega)
        return pd.DataFrame(
            {
                "t_s": np.repeat(np.asarray(self.t), n),
                "mass": np.tile(np.array(self.mass_names, dtype=object), S),
                "angle_rad": np.asarray(self.angle_rad).ravel(),
                "omega_rad_s": w.ravel(),
                "rpm": w.ravel() * RPM_PER_RAD_S,
            }
        )

    def to_json_dict(self) -> dict:
        """The run's figures: length, solver, per mass the speed range [rpm], per section
        the torque range [N·m], the energy's largest relative change."""
        w = np.asarray(self.omega) * RPM_PER_RAD_S
        tq = np.asarray(self.torque_Nm)
        t = np.asarray(self.t)
        return json_safe(
            {
                "engine": self.engine_name,
                "rpm": self.rpm,
                "duration_s": t[-1] - t[0] if t.size else None,
                "cycles": self.cycles if self.sampled_by == "angle" else None,
                "solver": self.solver,
                "rtol": self.rtol,
                "steps": self.steps,
                "load_torque_Nm": self.load_torque_Nm,
                "masses": [
                    {"name": name, "min_rpm": w[:, j].min(), "max_rpm": w[:, j].max()}
                    for j, name in enumerate(self.mass_names)
                ],
                "sections": [
                    {"name": name, "torque_min_Nm": tq[:, i].min(), "torque_max_Nm": tq[:, i].max()}
                    for i, name in enumerate(self.section_names)
                ],
                "energy_drift": self.energy_drift,
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """Every mass's speed [rpm] and every section's torque [N·m] against time. ``ax``:
        two Axes or None. Returns the Axes."""
        from ..plotting.torsion_response import plot_torsional_run

        return plot_torsional_run(
            np.asarray(self.t),
            np.asarray(self.omega) * RPM_PER_RAD_S,
            self.mass_names,
            np.asarray(self.torque_Nm),
            self.section_names,
            f"{self.engine_name}: torsional transient",
            ax=ax,
        )


def _initial(initial: Any, n: int, omega_ref: float, call: str) -> tuple[np.ndarray, np.ndarray]:
    if initial is None:
        return np.zeros(n), np.full(n, omega_ref)
    if isinstance(initial, TorsionalResponse):
        return np.asarray(initial.angle_rad)[:, 0], np.asarray(initial.omega)[:, 0]
    if isinstance(initial, tuple) and len(initial) == 2:
        a = np.asarray(initial[0], dtype=np.float64)
        w = np.asarray(initial[1], dtype=np.float64)
        if a.shape != (n,) or w.shape != (n,) or not (np.all(np.isfinite(a)) and np.all(np.isfinite(w))):
            raise EngineError(
                f"{call}(initial): (angles, speeds) need {n} finite numbers each [rad, rad/s], got shapes "
                f"{a.shape} and {w.shape}"
            )
        return a, w
    raise TypeError(
        f"{call}(initial): expected None, a rotor.TorsionalResponse or (angles [rad], speeds [rad/s]), got "
        f"{what_it_is(initial)}"
    )


def _engine_or_chain(
    engine: Any, chain: TorsionalChain | None, call: str
) -> tuple[Engine | None, TorsionalChain | None]:
    """(the engine or None, the chain or None) of ``torsional_simulate``'s first argument
    and ``chain``."""
    if isinstance(engine, TorsionalChain):
        if chain is not None:
            raise EngineError(f"{call}: give the chain once, as the first argument or as chain=, not both")
        return None, engine
    if isinstance(engine, Engine):
        return engine, chain
    hint = " (load it first: rotor.load_engine(...))" if isinstance(engine, (str, bytes)) else ""
    raise TypeError(
        f"{call}(engine): expected a rotor.Engine or a rotor.TorsionalChain{hint}, got {what_it_is(engine)}"
    )


def _checked_options(solver: str, rtol: Any, max_steps: Any, rpm: Any, eng: Engine | None, call: str):
    """``rtol``, ``max_steps`` and ``rpm`` (default the engine's, a free chain's 0) checked:
    (rtol, max_steps, rpm) as Python numbers."""
    if solver not in SOLVERS:
        raise EngineError(f"{call}(solver) = {solver!r}: one of {', '.join(map(repr, SOLVERS))}")
    rtol = require_number(rtol, f"{call}(rtol)")
    if not (1e-14 <= rtol <= 1e-2):
        raise EngineError(f"{call}(rtol) = {rtol!r}: must lie between 1e-14 and 1e-2")
    max_steps = require_whole(max_steps, f"{call}(max_steps)")
    lo, hi, _, _ = PLAUSIBLE[("operating", "rpm")]
    if rpm is None:
        rpm = 0.0 if eng is None else float(eng.operating.rpm)
    rpm = require_number(rpm, f"{call}(rpm)", "rpm")
    if eng is not None and not (math.isfinite(rpm) and lo <= rpm <= hi):
        raise EngineError(
            f"{call}(rpm) = {rpm!r}: an engine run needs a positive, finite speed between {lo:g} and {hi:g} rpm"
        )
    if eng is None and not (math.isfinite(rpm) and abs(rpm) <= hi):
        raise EngineError(f"{call}(rpm) = {rpm!r}: must be a finite speed below {hi:g} rpm")
    return rtol, max_steps, rpm


def _load_for(load: Any, dc: DrivenChain, eng: Engine | None, omega_ref: float, call: str) -> tuple[Load, float | None]:
    """The run's load and its constant torque [N·m] (None for a load that varies): by
    default the engine's mean gas torque less friction at ``omega_ref`` (a free chain: 0)."""
    if load is None:
        m0 = float(dc.mean_gas_torque()) - float(jnp.sum(dc.friction_torques(jnp.full(dc.size, omega_ref))))
        return ConstantLoad(jnp.asarray(m0 if eng is not None else 0.0)), (m0 if eng is not None else None)
    if isinstance(load, (int, float)) and not isinstance(load, bool):
        return ConstantLoad(jnp.asarray(float(load))), float(load)
    if isinstance(load, Load):
        return load, (float(load.torque_Nm) if isinstance(load, ConstantLoad) else None)
    raise TypeError(f"{call}(load): expected None, a number [N·m] or a rotor.Load, got {what_it_is(load)}")


@dataclasses.dataclass(frozen=True)
class _Span:
    """A run's length and samples: ``solver``: the solver ``"auto"`` picks; ``points``:
    samples per cycle (an engine run) or 0; ``cycles``; ``period``: the time unit of the
    solver's state [s] (a cycle at the nominal speed, or the free run's length);
    ``t_end`` [s]; ``theta_q``: the reference mass's angles to sample at [rad];
    ``theta_end`` [rad]; ``by_angle``: sampled by angle (an engine run) or in time;
    ``samples``: a free run's samples."""

    solver: str
    points: int
    cycles: int
    period: float
    t_end: float
    theta_q: np.ndarray
    theta_end: float
    by_angle: bool
    samples: int


def _span(dc, eng, cycles, duration_s, samples, omega_ref, omega_max, theta0, call: str) -> _Span:
    """The length and samples of the run (:class:`_Span`): an engine run's ``cycles``
    sampled on the grid of the reference mass's angle, a free chain's ``duration_s``
    sampled in time; a run whose samples would not fit in memory is refused."""
    n = dc.size
    if eng is not None:
        cycles = require_whole(cycles, f"{call}(cycles)")
        period = eng.cycle_rad / omega_ref
        P = dc.values.shape[0] if dc.values is not None else 0
        total = cycles * P
        check_size(total * n * SAMPLE_BYTES, f"{call}: {cycles} cycles × {P} samples", "run fewer cycles")
        th_start = float(theta0[dc.reference_mass])
        return _Span(
            solver="kvaerno5" if omega_max * period / 3 > STIFF_STEPS else "dopri8",
            points=P,
            cycles=cycles,
            period=period,
            t_end=20.0 * cycles * period,  # the event at the last angle ends it long before
            theta_q=th_start + np.arange(total) * (eng.cycle_rad / P),
            theta_end=th_start + cycles * eng.cycle_rad,
            by_angle=True,
            samples=samples,
        )
    if duration_s is None:
        raise EngineError(f"{call}: a free chain's run needs duration_s (its length [s])")
    t_end = require_number(duration_s, f"{call}(duration_s)", "s")
    if not (math.isfinite(t_end) and t_end > 0):
        raise EngineError(f"{call}(duration_s) = {duration_s!r}: must be a positive, finite time [s]")
    samples = require_whole(samples, f"{call}(samples)", 2)
    check_size(samples * n * SAMPLE_BYTES, f"{call}: {samples} samples", "take fewer samples")
    return _Span("dopri8", 0, 0, t_end, t_end, np.zeros(1), 0.0, False, samples)


def _scaled_start(dc, load_obj, omega_ref, theta0, omega0, omega_max, eng, period):
    """The scene the solver sees and its start state, scaled so that the state is of order
    one: (:class:`_Scene`, (reference angle, twists, speeds))."""
    twist0 = theta0[:-1] - theta0[1:]
    k = np.asarray(dc.stiffnesses)
    torque_scale = abs(float(dc.mean_gas_torque())) + abs(float(load_obj.torque(omega_ref, 0.0))) + 1.0
    twist_scale = max(float(np.max(np.abs(twist0))), torque_scale / float(np.min(k)), 1e-12)
    speed_scale = max(abs(omega_ref), float(np.max(np.abs(omega0))), omega_max * twist_scale, 1e-9)
    angle_scale = eng.cycle_rad if eng is not None else 1.0
    scene = _Scene(
        dc,
        load_obj,
        jnp.asarray(omega_ref),
        jnp.asarray(angle_scale),
        jnp.asarray(twist_scale),
        jnp.asarray(speed_scale),
        jnp.asarray(period),
    )
    y0 = (
        jnp.asarray(theta0[dc.reference_mass] / angle_scale),
        jnp.asarray(twist0 / twist_scale),
        jnp.asarray(omega0 / speed_scale),
    )
    return scene, y0


def torsional_simulate(
    engine: Engine | TorsionalChain,
    rpm: float | None = None,
    cycles: int = 4,
    *,
    chain: TorsionalChain | None = None,
    load: Load | float | None = None,
    imep_scale: ArrayLike = 1.0,
    friction: Friction | bool | None = None,
    initial: Any = None,
    duration_s: float | None = None,
    samples: int = 2000,
    solver: str = "auto",
    rtol: float = 1e-8,
    grid_deg: float = 0.25,
    max_steps: int = 400_000,
) -> TorsionalRun:
    """A transient of the torsional chain in time (diffrax; see :mod:`rotor.torsion.transient`).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine` (its ``[torsion]`` chain unless ``chain``), or a
      :class:`rotor.TorsionalChain` alone (free vibration: no mechanisms, no gas torque).
    - ``rpm``: nominal speed [rpm]: every mass's start speed (unless ``initial``) and the
      uniform rotation about which damping acts; default the engine's ``[operating] rpm``
      (a free chain: 0).
    - ``cycles``: engine cycles to run (an engine run ends when the reference mass has
      turned them).
    - ``chain``: a :class:`rotor.TorsionalChain` for the engine (cycle-mean inertias, as
      :func:`rotor.torsional_chain`).
    - ``load``: None (a constant load torque equal to the engine's mean gas torque less
      friction at ``rpm``: the balance at uniform speed), a number (a constant load [N·m]),
      or any :class:`rotor.Load` (a load step included), at the chain's load mass.
    - ``imep_scale``: combustion scale per cylinder [-]; ``friction``: a
      :class:`rotor.Friction`, None (the engine file's) or False.
    - ``initial``: None (every mass at angle 0 and speed ``rpm``: no twist), a
      :class:`rotor.TorsionalResponse` (its state at its first node; its balance is not
      carried over: give ``load=response.load_torque_Nm``, or for a response that carried a
      given load, that load and ``imep_scale`` times its ``fuel_scale``) or a tuple (angles
      [rad], speeds [rad/s]), n each.
    - ``duration_s``: the run's length [s], for a free chain (required there).
    - ``samples``: samples of a free chain's run (uniform in time).
    - ``solver``: ``"auto"`` (Kvaerno5 where the chain is stiff, else Dopri8; see the module
      doc), ``"kvaerno5"`` or ``"dopri8"``.
    - ``rtol``: the step-size controller's tolerance on the scaled state [-].
    - ``grid_deg``: the cylinder tables' node spacing and an engine run's sample spacing in
      the reference mass's angle [deg].
    - ``max_steps``: the most solver steps.

    **Returns:** a :class:`TorsionalRun`.

    **Raises:** :class:`rotor.EngineError` for bad input; :class:`rotor.SolverError` where the
    solver did not reach the end (too many steps, or the reference mass stopped turning).
    """
    call = "torsional_simulate"
    start = time.perf_counter()
    eng, chain = _engine_or_chain(engine, chain, call)
    rtol, max_steps, rpm = _checked_options(solver, rtol, max_steps, rpm, eng, call)
    dc = driven_chain(eng, chain, imep_scale=imep_scale, friction=friction, grid_deg=grid_deg, call=call)
    assert chain is not None or eng is not None
    n = dc.size
    omega_ref = rpm / RPM_PER_RAD_S
    theta0, omega0 = _initial(initial, n, omega_ref, call)
    load_obj, load_value = _load_for(load, dc, eng, omega_ref, call)
    K_hz = np.asarray(natural_frequencies(_mean_chain(dc)))
    omega_max = 2 * np.pi * float(K_hz[-1]) if K_hz.size else 0.0
    span = _span(dc, eng, cycles, duration_s, samples, omega_ref, omega_max, theta0, call)
    name = span.solver if solver == "auto" else solver
    scene, y0 = _scaled_start(dc, load_obj, omega_ref, theta0, omega0, omega_max, eng, span.period)
    s_q = np.linspace(0.0, span.t_end / span.period, span.samples) if not span.by_angle else np.zeros(1)
    t, theta, omega, ok, steps = _run_kernel(
        scene,
        y0,
        jnp.asarray(span.t_end / span.period),
        jnp.asarray(rtol),
        name,
        max_steps,
        jnp.asarray(span.theta_end),
        jnp.asarray(span.theta_q),
        jnp.asarray(s_q),
        span.by_angle,
    )
    t, theta, omega, ok, steps = jax.device_get((t, theta, omega, ok, steps))
    if not ok:
        raise SolverError(
            f"{call}: the {name} solver did not reach the end of the run ({int(steps)} steps"
            + (f" of {max_steps}" if steps >= max_steps else "")
            + "): raise max_steps or rtol, or check that the reference mass keeps turning"
        )
    twist = theta[:, :-1] - theta[:, 1:]
    torque = np.asarray(dc.section_torques(twist, omega[:, :-1] - omega[:, 1:]))
    energy = np.asarray(dc.energy(theta, omega))
    names = tuple(chain.names) if chain is not None else _engine_names(eng)
    return TorsionalRun(
        t=t,
        angle_rad=theta,
        omega=omega,
        twist_rad=twist,
        torque_Nm=torque,
        energy_J=energy,
        sampled_by="angle" if span.by_angle else "time",
        points_per_cycle=span.points,
        cycles=span.cycles,
        rpm=float(rpm),
        load_torque_Nm=load_value,
        solver=name,
        rtol=float(rtol),
        steps=int(steps),
        mass_names=names,
        reference_mass=dc.reference_mass,
        load_mass=dc.load_mass,
        engine_name=eng.name if eng is not None else "free chain",
        strokes=eng.strokes if eng is not None else 0,
        cycle_rad=eng.cycle_rad if eng is not None else 0.0,
        wall_s=time.perf_counter() - start,
    )


def _engine_names(engine: Engine | None) -> tuple[str, ...]:
    from .model import torsional_chain

    assert engine is not None
    return tuple(torsional_chain(engine).names)


def _mean_chain(dc: DrivenChain) -> TorsionalChain:
    """The linear chain (mean inertias, stiffnesses) of ``dc``, for its natural frequencies."""
    return TorsionalChain(inertias_kgm2=dc.mean_inertias, stiffnesses_Nm_per_rad=dc.stiffnesses)
