"""The forced response of a torsional chain: its periodic steady state at an operating point.

The model, the chain with its engine's mechanisms on its masses, is
:mod:`rotor.torsion.driven`'s.

**The method: harmonic balance in the load mass's crank angle** (trigonometric
collocation). The independent variable is the reference mass's angle φ (the load mass,
usually the flywheel that carries the trigger wheel) on the same uniform cycle grid as the
rigid steady state (``grid_deg``, 0.25° by default). The unknowns are periodic: the time
t(φ) = φ/ω̄ + s(φ) and each other mass's angle θ_j = φ + q_j(φ), as trigonometric
polynomials through the grid's nodes, plus the balancing load torque (or fuel scale). The
equations are collocated at every node (derivatives by FFT, spectrally exact), and the
system is solved by Newton's method (:class:`optimistix.Newton`) whose linear steps are
GMRES (:class:`lineax.GMRES`), preconditioned by the chain's *constant-coefficient*
operator, −(kΩ)²·M̄ + i·kΩ·C + K, which is diagonal in the harmonics k (an n×n solve per
harmonic): it takes the shafts' stiffness and the resonances exactly, so the iterations
see only the crank-angle variation of the inertias and torques (4 or 5 Newton steps).
The time-mean speed is exactly ω̄ by construction.

*Why harmonic balance, not shooting:* shooting integrates one cycle per Newton step with a
fixed step that a stiff chain forces to be tiny (an explicit step must stay below 2.8/ω_max:
for a six-cylinder chain with 3 kHz modes at 600 rpm that is already 1/1300 of the cycle,
and 10⁴ times stiffer shafts need 10⁵ steps a cycle), or with an implicit scheme whose
per-step nonlinear solves cost as much; harmonic balance does not care how stiff the
shafts are (a stiff chain converges in fewer steps), puts the result on the rigid model's
own grid (the flywheel's ω(φ) compares node by node with :func:`rotor.steady_state`, and
a trigger wheel samples the speed by angle too), and vmaps over speeds with a fixed
problem size.

**Accuracy** (``tests/torsion/test_torsion_response.py``; MWM six at 1500 and 2200 rpm, 0.25°
grid): its chain with 10⁶ times stiffer shafts and no damping gives the rigid steady state's
δ to 4e-9, the load torque to 1e-14 and, at the flywheel, ω(θ) to 3e-9 and every speed
order to 1e-9 of the mean speed (at the damper, the other end, 4e-8 and 1e-8: the shafts'
remaining compliance). The real chain's response agrees with a time-domain run started on
it (Dopri8, rtol 1e-11) to 1.4e-7 of the mean speed at the throws, 2e-9 at the flywheel, and
to 3e-7 of the largest shaft torque: the collocation's aliasing of the gas torque's
harmonics above the grid's Nyquist order (the same order as the rigid model's own grid
error).

**Derivatives.** :func:`torsional_response` is traceable in ``imep_scale`` and in the chain's
numbers (a :class:`rotor.TorsionalChain` whose arrays are traced, e.g. by ``eqx.tree_at``; not
in ``rpm`` or the grid): under ``jax.grad``, ``jax.jacfwd``, ``jit`` or ``vmap`` its arrays stay
JAX's and a failed solve shows as ``converged`` False instead of an exception. The
derivatives of the periodic state come from the implicit function theorem
(``optimistix.ImplicitAdjoint``), a GMRES solve with the Newton iteration's operator
(its transpose in reverse mode) on the right-hand side scaled to unit size (``ADJOINT_SOLVER``).
The flywheel's mean-square speed fluctuation differentiated by ``jax.grad`` with respect to the
six combustion scales and the eight stiffnesses agrees with central differences to 1e-10 of
the largest derivative (``tests/torsion/test_torsion_response.py``).

**Cost** (2-core CPU, after compile; the first call compiles for about 20 s, the cylinder
tables included): one response of the nine-mass MWM chain in about 1–2 s on the 0.25° grid
and 0.15–0.3 s on the 1° grid (4 Newton steps; more near an undamped resonance);
:func:`torsional_sweep` of 100 speeds on the 1° grid in 15–35 s (the range: the same run on a
quiet and a busy machine). It runs the speeds in ``jax.vmap`` batches one batch after
another (``jax.lax.map``), which bounds memory at about 2 kB per node and mass for each
speed of a batch (50 MB for the MWM chain on the 0.25° grid).
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx
from jaxtyping import Array, ArrayLike

from ..checks import check_size, concrete
from ..dynamics.crank_train import grid_points
from ..dynamics.loads import ConstantLoad, Load
from ..dynamics.result import Orders, SpeedResult, periodic_extremes
from ..engine.friction import Friction
from ..engine.model import Engine
from ..engine.plausible import PLAUSIBLE, check_speed_rpm, require_number, require_whole, what_it_is
from ..errors import EngineError, NoSteadyStateError
from ..results import Result, json_safe
from ..units import RPM_PER_RAD_S
from .driven import DrivenChain, chain_for, driven_chain, mass_index, section_names
from .model import TorsionalChain
from .modes import natural_frequencies

__all__ = [
    "TorsionalResponse",
    "TorsionalSweep",
    "torsional_response",
    "torsional_sweep",
    "periodic_range",
]

#: the Newton iteration's tolerance on the unknowns (rad, and relative for the balance)
NEWTON_TOL = 1e-11
#: the preconditioned residual (the Newton correction still left: radians of twist and phase,
#: and the relative balance) below which a response counts as found
RESIDUAL_TOL = 1e-9
#: bytes per unknown (mass × node) while a response is solved: the GMRES basis (restart
#: vectors), the linearisation and the tables
BYTES_PER_UNKNOWN = 8 * 260
#: seconds of one response of a 40-mass chain on 2880 nodes, after compiling (2-core CPU)
RESPONSE_SECONDS_40 = 15.0
#: the longest a single response may take unless ROTOR_TIME_LIMIT_S says otherwise [s]
MAX_RESPONSE_SECONDS = 120.0


# ----------------------------------------------------------------------------- harmonic balance
def _pack(z: Array, P: int) -> Array:
    """(n, P/2 + 1) complex harmonics → (n, P) reals: the real parts, then the imaginary
    parts of the harmonics 1 … P/2 − 1 (those of 0 and P/2 are zero for real data)."""
    return jnp.concatenate([z.real, z.imag[:, 1 : P // 2]], axis=1)


def _unpack(u: Array, P: int) -> Array:
    zero = jnp.zeros((u.shape[0], 1))
    return u[:, : P // 2 + 1] + 1j * jnp.concatenate([zero, u[:, P // 2 + 1 :], zero], axis=1)


class _Balance(eqx.Module):
    """What balances the engine: the constant load torque (``load`` None) or the fuelling
    that carries ``load`` (a speed-dependent :class:`rotor.Load`)."""

    load: Load | None
    scale: Array  # the unknown's scale: N·m for a load torque, 1 for a fuel scale

    def torques(self, dc: DrivenChain, x: Array, theta: Array, omega: Array) -> Array:
        """Gas torques minus friction minus the load on each mass [N·m], (n, P)."""
        fuel = 1.0 if self.load is None else x
        out = dc.gas_torques(theta.T, fuel).T - dc.friction_torques(omega.T).T
        m_load = x if self.load is None else self.load.torque(omega[dc.load_mass], 0.0)
        return out.at[dc.load_mass].add(-m_load)


def _fields(u, P, dk, omega_m, ref, x_scale):
    """(x, t, θ, θ̇, θ̈) on the nodes from the packed unknowns ``u``: harmonics of
    v_j = q_j − ω̄·s (v_ref = −ω̄·s) with the balance x in the slot of v_ref's mean."""
    z = _unpack(u, P)
    x = z[ref, 0].real * x_scale
    z = z.at[ref, 0].set(0.0)
    v = jnp.fft.irfft(z, n=P, axis=1) * P
    v1 = jnp.fft.irfft(z * dk, n=P, axis=1) * P
    v2 = jnp.fft.irfft(z * dk**2, n=P, axis=1) * P
    s, s1, s2 = -v[ref] / omega_m, -v1[ref] / omega_m, -v2[ref] / omega_m
    q, q1, q2 = v - v[ref], v1 - v1[ref], v2 - v2[ref]
    t_prime = 1.0 / omega_m + s1  # dt/dφ
    omega = (1.0 + q1) / t_prime
    accel = (q2 * t_prime - (1.0 + q1) * s2) / t_prime**3
    return x, s, q, omega, accel


def _x_column(dc: DrivenChain, balance: _Balance) -> Array:
    """∂(residual)/∂x averaged over the cycle, (n,): the load torque's column, or the mean
    combustion torque's (a fuel scale)."""
    if balance.load is None:
        return jnp.zeros(dc.size).at[dc.load_mass].set(1.0)
    return -dc.mean_combustion_torque()


def _hb_system(dc: DrivenChain, omega_m: Array, balance: _Balance, P: int):
    """The harmonic-balance system at mean speed ω̄ on P nodes: ``(residual, u0, dk)``,
    ``residual(u, args) -> (preconditioned residual, raw residual [N·m])``, the start u0 and
    the spectral derivative dk of each harmonic."""
    n, ref, L = dc.size, dc.reference_mass, dc.load_mass
    cycle = dc.cycle_rad
    nodes = jnp.arange(P) * (cycle / P)
    K = dc.stiffness_matrix
    k = jnp.arange(P // 2 + 1)
    dk = 1j * k * (2 * np.pi / cycle)  # d/dφ of harmonic k
    wk = k * (2 * np.pi / cycle) * omega_m  # its frequency [rad/s] at the mean speed
    # the preconditioner: the chain at uniform rotation, mean inertias, damping plus the
    # losses' speed derivative; harmonic 0 has the balance's column instead of v_ref's mean
    a, b, c = dc.friction
    C = dc.damping + jnp.diag(dc.friction_share * (b + 2 * c * omega_m))
    if balance.load is not None:
        dload = jax.grad(lambda w: balance.load.torque(w, 0.0))(omega_m)  # type: ignore[union-attr]
        C = C.at[L, L].add(dload)
    M = jnp.diag(dc.mean_inertias)
    Z = -(wk**2)[:, None, None] * M[None] + 1j * wk[:, None, None] * C[None] + K[None]
    Z0 = K.at[:, ref].set(_x_column(dc, balance) * balance.scale)
    Zinv = jnp.linalg.inv(Z.at[0].set(Z0.astype(Z.dtype)))

    def residual(u, _):
        x, s, q, omega, accel = _fields(u, P, dk, omega_m, ref, balance.scale)
        theta = nodes[None] + q
        A, dA = dc.inertias(theta.T)
        R = A.T * accel + 0.5 * dA.T * omega**2 + K @ q + dc.damping @ (omega - omega_m)
        R = R - balance.torques(dc, x, theta, omega)
        Rh = jnp.fft.rfft(R, axis=1) / P
        return _pack(jnp.einsum("kij,jk->ik", Zinv, Rh), P), R

    x0 = (0.0 if balance.load is None else 1.0) / balance.scale
    u0 = jnp.zeros((n, P)).at[ref, 0].set(x0)
    return residual, u0, dk


#: GMRES for the Newton steps (on the preconditioned system, whose operator is near identity)
GMRES = lx.GMRES(rtol=1e-9, atol=1e-13, restart=40, stagnation_iters=40, max_steps=600)


class _ScaledGMRES(lx.GMRES):
    """GMRES on the right-hand side divided by its largest entry (and the solution scaled
    back; a zero right-hand side gives zero). lineax tests convergence entry by entry,
    |r_i| < atol + rtol·|b_i|, so with a fixed atol the test depends on the right-hand side's
    units: a reverse-mode cotangent of ~1e3 whose other entries are near zero asks for a
    residual of 1e-13 against 1e3 there, which rounding never reaches, and the solve ended
    in a false "stagnation" (jax.grad of a response failed)."""

    def compute(self, state: Any, vector: Any, options: dict[str, Any]) -> Any:
        scale = jnp.max(jnp.abs(vector))
        scale = jnp.where(scale > 0, scale, 1.0)
        y, result, stats = super().compute(state, vector / scale, options)
        return y * scale, result, stats


#: the linear solves of the derivatives (implicit function theorem: J·du = −∂F·dp forward,
#: Jᵀ·λ = ū in reverse, J the preconditioned system's Jacobian at the solution), on the
#: normalised right-hand side: to 1e-12 of its largest entry in every entry
ADJOINT_SOLVER = _ScaledGMRES(rtol=1e-9, atol=1e-12, restart=40, stagnation_iters=40, max_steps=600)


@eqx.filter_jit
def _hb_kernel(dc: DrivenChain, omega_m: Array, balance: _Balance, P: int):
    """The periodic steady state at mean speed ω̄ on P nodes of the reference mass's angle."""
    residual, u0, dk = _hb_system(dc, omega_m, balance, P)
    ref = dc.reference_mass
    nodes = jnp.arange(P) * (dc.cycle_rad / P)

    def precond(u, args):
        return residual(u, args)[0]

    sol: Any = optx.root_find(
        precond,
        optx.Newton(rtol=NEWTON_TOL, atol=NEWTON_TOL, linear_solver=GMRES),
        u0,
        max_steps=40,
        adjoint=optx.ImplicitAdjoint(linear_solver=ADJOINT_SOLVER),
        throw=False,
    )
    x, s, q, omega, accel = _fields(sol.value, P, dk, omega_m, ref, balance.scale)
    F, _ = residual(sol.value, None)
    resid = jax.lax.stop_gradient(jnp.max(jnp.abs(F)))
    t = nodes / omega_m + s - s[0]
    ok = (sol.result == optx.RESULTS.successful) & (resid < RESIDUAL_TOL) & jnp.all(omega[ref] > 0)
    ok = ok & jnp.all(jnp.isfinite(omega))
    return x, t, nodes[None] + q, omega, accel, ok, sol.stats["num_steps"], resid


@eqx.filter_jit
def _response_kernel(dc: DrivenChain, omega_m: Array, balance: _Balance, P: int):
    """:func:`_hb_kernel` and what the result shows: the sections' torques, the whole
    chain's gas torque and its losses (friction and load) at the nodes [N·m]."""
    x, t, theta, omega, accel, ok, steps, resid = _hb_kernel(dc, omega_m, balance, P)
    torque = dc.section_torques((theta[:-1] - theta[1:]).T, (omega[:-1] - omega[1:]).T).T
    fuel = 1.0 if balance.load is None else x
    gas = jnp.sum(dc.gas_torques(theta.T, fuel), axis=-1)
    loss = jnp.sum(dc.friction_torques(omega.T), axis=-1)
    if balance.load is None:
        loss = loss + x
    else:
        loss = loss + balance.load.torque(omega[dc.load_mass], 0.0)
    return x, t, theta, omega, accel, ok, steps, resid, torque, gas, loss


def _check_load(load: Any, call: str) -> Load | None:
    if load is None:
        return None
    if isinstance(load, (int, float)) and not isinstance(load, bool):
        load = ConstantLoad(jnp.asarray(float(load)))
    if not isinstance(load, Load):
        raise TypeError(f"{call}(load): expected None, a number [N·m] or a rotor.Load, got {what_it_is(load)}")
    if load.time_dependent:
        raise EngineError(
            "a torsional steady state needs a load that does not change in time; use rotor.torsional_simulate for a "
            "load step"
        )
    return load


def _balance_for(dc: DrivenChain, load: Load | None, omega_m: Any, call: str) -> _Balance:
    if load is None:
        scale = jnp.maximum(jnp.abs(dc.mean_gas_torque()), 1.0)
        return _Balance(None, jax.lax.stop_gradient(scale))
    work = concrete(jnp.sum(dc.mean_combustion_torque()))
    if work is not None and not work > 0:
        raise EngineError(
            f"{call}: a given load needs a firing engine: the fuelling is scaled to carry it, but this engine's "
            "pressure has no combustion; give no load (load=None) to balance the mean engine torque instead"
        )
    return _Balance(load, jnp.asarray(1.0))


def response_seconds(n_masses: int, nodes: int) -> float:
    """The time one response of a chain of ``n_masses`` masses on ``nodes`` nodes a cycle
    takes after compiling [s], about: :data:`RESPONSE_SECONDS_40` for 40 masses on 2880
    nodes, growing as masses^2.6 (the GMRES steps' n × n products per harmonic, and their
    number) and linearly with the nodes."""
    return RESPONSE_SECONDS_40 * (n_masses / 40.0) ** 2.6 * (nodes / 2880.0)


def time_limit_s() -> float:
    """The longest a single torsional response may take [s]: ``ROTOR_TIME_LIMIT_S`` if set,
    else :data:`MAX_RESPONSE_SECONDS`."""
    env = os.environ.get("ROTOR_TIME_LIMIT_S")
    if not env:
        return MAX_RESPONSE_SECONDS
    try:
        limit = float(env)
    except ValueError:
        raise EngineError(f"ROTOR_TIME_LIMIT_S = {env!r}: must be a number of seconds, e.g. 600") from None
    if not (math.isfinite(limit) and limit > 0):
        raise EngineError(f"ROTOR_TIME_LIMIT_S = {env!r}: must be a positive number of seconds")
    return limit


def _check_grid(grid_deg: Any, engine: Engine, call: str, n_masses: int, speeds: int = 1) -> int:
    grid_deg = require_number(grid_deg, f"{call}(grid_deg)", "deg")
    P = grid_points(engine.strokes, grid_deg, engine.cylinders)
    if P % 2:
        raise EngineError(
            f"grid_deg = {grid_deg!r}: the harmonic balance needs an even number of nodes per cycle, this gives {P}"
        )
    check_size(
        float(P) * n_masses * speeds * BYTES_PER_UNKNOWN + 16.0 * (P // 2 + 1) * n_masses**2 * speeds,
        f"{call} with grid_deg = {grid_deg:g}° ({P} nodes) × {n_masses} masses of the [torsion] table"
        + (f" × {speeds} speeds at once" if speeds > 1 else ""),
        "give the [torsion] table fewer masses, or use a larger grid_deg"
        + (" or a smaller batch" if speeds > 1 else ""),
    )
    seconds, limit = response_seconds(n_masses, P), time_limit_s()
    if seconds > limit:
        most = int(40 * (limit / (RESPONSE_SECONDS_40 * P / 2880.0)) ** (1 / 2.6))
        raise EngineError(
            f"{call}: the [torsion] table's chain of {n_masses} masses on {P} nodes (grid_deg = {grid_deg:g}°) "
            f"would take about {seconds / 60:.0f} minutes per speed, over the {limit:g} s allowed "
            f"(ROTOR_TIME_LIMIT_S); lump the chain into at most {most} masses, or use a larger grid_deg"
        )
    return P


# ----------------------------------------------------------------------------- results
@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class TorsionalResponse(Result):
    """The periodic steady state of a torsional chain at one operating point
    (:func:`torsional_response`).

    **Samples** over one cycle on the uniform grid of the *reference mass's* crank angle
    (the load mass, usually the flywheel that carries the trigger wheel), P nodes:
    ``theta`` [rad] (the reference's angle, from 0), ``t`` [s]; per mass (n, P):
    ``angle_rad`` (each mass's own angle [rad]), ``omega`` [rad/s], ``accel`` [rad/s²];
    per shaft section (n − 1, P): ``twist_rad`` (θ_i − θ_{i+1}, the front mass leading:
    positive) and ``torque_Nm`` (k_i·twist + the relative damping's torque: what the
    section carries rearwards); over the whole chain (P,): ``gas_torque_Nm`` (every
    cylinder's gas torque) and ``loss_torque_Nm`` (friction and the load) [N·m];
    ``imep_pa``: each cylinder's IMEP at the response's fuelling [Pa], (cylinders,).

    **Figures:** ``rpm`` (time-mean speed) [rpm]; ``period_s`` [s]; ``load_torque_Nm``
    (the load that keeps the mean speed, ``load=None``) [N·m] or ``fuel_scale`` (that
    carries the given load) [-]; ``converged`` (a bool, a JAX bool under ``jit``/``vmap``);
    ``newton_steps``; ``residual`` (the Newton correction still left: the preconditioned
    residual, [rad] of phase and twist).

    **About:** ``mass_names``, ``reference_mass``, ``load_mass`` (0-based);
    ``stiffnesses_Nm_per_rad``; ``natural_frequencies_hz`` (of the chain, for context);
    ``engine_name``; ``strokes``; ``cycle_rad``; ``wall_s``.
    """

    theta: ArrayLike
    t: ArrayLike
    angle_rad: ArrayLike
    omega: ArrayLike
    accel: ArrayLike
    twist_rad: ArrayLike
    torque_Nm: ArrayLike
    gas_torque_Nm: ArrayLike
    loss_torque_Nm: ArrayLike
    imep_pa: ArrayLike
    rpm: float
    period_s: Any
    load_torque_Nm: Any
    fuel_scale: Any
    converged: Any
    newton_steps: Any
    residual: Any
    mass_names: tuple[str, ...]
    reference_mass: int
    load_mass: int
    stiffnesses_Nm_per_rad: Any
    natural_frequencies_hz: Any
    engine_name: str
    strokes: int
    cycle_rad: float
    wall_s: float = float("nan")

    # ------------------------------------------------------------------ figures
    @property
    def points_per_cycle(self) -> int:
        """Nodes over the cycle."""
        return int(np.shape(self.theta)[-1])

    @property
    def section_names(self) -> tuple[str, ...]:
        """The shaft sections, ``"front mass–rear mass"``."""
        return section_names(self.mass_names)

    @property
    def mean_omega(self) -> Array:
        """Time-mean speed [rad/s] (the same at every mass)."""
        return jnp.asarray(self.rpm) / RPM_PER_RAD_S

    def speed_result(self, mass: int | str | None = None) -> SpeedResult:
        """One mass's speed over the cycle as a :class:`rotor.SpeedResult` (``kind="steady"``),
        so that its δ, orders and plots are those of the rigid model's steady state.

        **Arguments:** ``mass``: index (0-based) or name; default the reference mass (whose
        angle the grid is). Another mass's speed is sampled at the reference's angles (its
        own angle differs by the twist, a few milliradians).

        The result's ``torque`` is the gas torque on the whole chain, ``load_torque`` the
        load at the load mass plus all friction [N·m].
        """
        j = self.mass_index(mass)
        omega = jnp.asarray(self.omega)[j]
        accel = jnp.asarray(self.accel)[j]
        return SpeedResult(
            t=jnp.asarray(self.t),
            theta=jnp.asarray(self.theta),
            omega=omega,
            accel=accel,
            torque=jnp.asarray(self.gas_torque_Nm),
            load_torque=jnp.asarray(self.loss_torque_Nm),
            imep_pa=jnp.asarray(self.imep_pa)[None, :],
            method="harmonic balance",
            fidelity="variable",
            kind="steady",
            strokes=self.strokes,
            cycle_rad=self.cycle_rad,
            points_per_cycle=self.points_per_cycle,
            uniform_cycles=1,
            engine_name=f"{self.engine_name} ({self.mass_names[j]})",
            wall_s=self.wall_s,
            period_s=self.period_s,
            load_torque_Nm=self.load_torque_Nm,
            fuel_scale=self.fuel_scale,
            converged=self.converged,
        )

    def mass_index(self, mass: int | str | None) -> int:
        """The 0-based index of ``mass`` (an index, a name, or None: the reference mass)."""
        return mass_index(self.mass_names, self.reference_mass, mass)

    @property
    def delta(self) -> np.ndarray:
        """Each mass's speed irregularity (ω_max − ω_min)/ω̄ over the cycle [-], (n,), the
        extremes refined between the nodes by a parabola, as :attr:`rotor.SpeedResult.delta`."""
        return periodic_range(np.asarray(self.omega)) / float(self.mean_omega)

    @property
    def twist_pp_rad(self) -> np.ndarray:
        """Peak-to-peak twist of each section over the cycle [rad], (n − 1,)."""
        tw = np.asarray(self.twist_rad)
        return tw.max(axis=1) - tw.min(axis=1)

    @property
    def torque_mean_Nm(self) -> np.ndarray:
        """Cycle mean of each section's torque [N·m], (n − 1,) (over the reference angle)."""
        return np.asarray(self.torque_Nm).mean(axis=1)

    @property
    def vibratory_torque_Nm(self) -> np.ndarray:
        """Each section's torque less its cycle mean [N·m], (n − 1, P)."""
        tq = np.asarray(self.torque_Nm)
        return tq - tq.mean(axis=1, keepdims=True)

    @property
    def torque_pp_Nm(self) -> np.ndarray:
        """Peak-to-peak torque of each section over the cycle [N·m], (n − 1,): the vibratory
        torque's range."""
        tq = np.asarray(self.torque_Nm)
        return tq.max(axis=1) - tq.min(axis=1)

    def orders(self, mass: int | str | None = None, max_order: float = 12.0) -> Orders:
        """The speed harmonics of ``mass`` (default the reference mass) by engine order
        (:meth:`rotor.SpeedResult.orders`), up to ``max_order`` [per revolution]."""
        return self.speed_result(mass).orders(max_order=max_order)

    def torque_orders(self, max_order: float = 12.0) -> tuple[np.ndarray, np.ndarray]:
        """Amplitude of each section's vibratory torque by engine order: ``(order, amplitude)``,
        (m,) [per revolution] and (n − 1, m) [N·m], up to ``max_order``."""
        return _orders_of(np.asarray(self.torque_Nm), self.strokes, max_order)

    # ------------------------------------------------------------------ protocol
    def _balance_text(self) -> str:
        if self.fuel_scale is not None:
            return f"the given load carried at fuel scale {float(self.fuel_scale):.4f}"
        return f"load torque {float(self.load_torque_Nm):.2f} N·m balances the mean engine torque"

    def summary(self) -> str:
        """The operating point, each mass's speed and δ, each section's twist and torque."""
        ok = bool(np.all(np.asarray(self.converged)))
        fn = np.asarray(self.natural_frequencies_hz)
        lines = [
            f"{self.engine_name}: torsional steady state at {self.rpm:g} rpm ({len(self.mass_names)} masses; "
            f"{self._balance_text()})",
            f"  harmonic balance on {self.points_per_cycle} nodes of {self.mass_names[self.reference_mass]}'s angle: "
            + (f"converged in {int(self.newton_steps)} Newton steps" if ok else "NOT converged (check `converged`)"),
            "  natural frequencies [Hz]: " + ", ".join(f"{f:.1f}" for f in fn[:8]) + (" …" if fn.size > 8 else ""),
            "",
            f"  {'mass':<16} {'min rpm':>10} {'max rpm':>10} {'δ':>10}",
        ]
        w = np.asarray(self.omega) * RPM_PER_RAD_S
        d = self.delta
        for j, name in enumerate(self.mass_names):
            mark = "  (reference)" if j == self.reference_mass else ""
            lines.append(f"  {name:<16} {w[j].min():10.2f} {w[j].max():10.2f} {d[j]:10.5f}{mark}")
        lines += ["", f"  {'section':<28} {'twist p-p [mrad]':>16} {'mean [N·m]':>11} {'p-p [N·m]':>11}"]
        pp, mean, tw = self.torque_pp_Nm, self.torque_mean_Nm, self.twist_pp_rad
        for i, name in enumerate(self.section_names):
            lines.append(f"  {name:<28} {tw[i] * 1e3:16.4f} {mean[i]:11.1f} {pp[i]:11.1f}")
        worst = int(np.argmax(pp))
        lines.append(f"  largest vibratory torque: {pp[worst]:.1f} N·m peak to peak in {self.section_names[worst]}")
        return "\n".join(lines[:60]) + "\n"

    def to_pandas(self) -> Any:
        """One row per node and mass or section (tidy): ``crank_angle_deg`` (the reference
        mass's), ``t_s``, ``element`` (``"mass"``/``"section"``), ``name``, and
        ``omega_rad_s``, ``rpm`` (masses) or ``twist_rad``, ``torque_Nm`` (sections); the
        other columns are empty (NaN) in each row."""
        import pandas as pd

        deg = np.rad2deg(np.asarray(self.theta))
        t = np.asarray(self.t)
        frames = []
        w = np.asarray(self.omega)
        for j, name in enumerate(self.mass_names):
            frames.append(
                pd.DataFrame(
                    {
                        "crank_angle_deg": deg,
                        "t_s": t,
                        "element": "mass",
                        "name": name,
                        "omega_rad_s": w[j],
                        "rpm": w[j] * RPM_PER_RAD_S,
                    }
                )
            )
        tw, tq = np.asarray(self.twist_rad), np.asarray(self.torque_Nm)
        for i, name in enumerate(self.section_names):
            frames.append(
                pd.DataFrame(
                    {
                        "crank_angle_deg": deg,
                        "t_s": t,
                        "element": "section",
                        "name": name,
                        "twist_rad": tw[i],
                        "torque_Nm": tq[i],
                    }
                )
            )
        return pd.concat(frames, ignore_index=True)

    def to_json_dict(self) -> dict:
        """What ``rotor torsion --json`` prints: the operating point, the balance, whether it
        converged, the natural frequencies [Hz], per mass its speed range [rpm] and δ, per
        section its stiffness, twist peak to peak [rad] and torque mean, min, max and peak to
        peak [N·m]."""
        w = np.asarray(self.omega) * RPM_PER_RAD_S
        d = self.delta
        tq = np.asarray(self.torque_Nm)
        k = np.asarray(self.stiffnesses_Nm_per_rad)
        return json_safe(
            {
                "engine": self.engine_name,
                "rpm": self.rpm,
                "period_s": self.period_s,
                "load_torque_Nm": self.load_torque_Nm,
                "fuel_scale": self.fuel_scale,
                "converged": bool(np.all(np.asarray(self.converged))),
                "method": "harmonic balance",
                "points_per_cycle": self.points_per_cycle,
                "reference_mass": self.mass_names[self.reference_mass],
                "load_mass": self.mass_names[self.load_mass],
                "natural_frequencies_hz": np.asarray(self.natural_frequencies_hz),
                "masses": [
                    {"name": name, "min_rpm": w[j].min(), "max_rpm": w[j].max(), "delta": d[j]}
                    for j, name in enumerate(self.mass_names)
                ],
                "sections": [
                    {
                        "name": name,
                        "stiffness_Nm_per_rad": k[i],
                        "twist_pp_rad": self.twist_pp_rad[i],
                        "torque_mean_Nm": tq[i].mean(),
                        "torque_min_Nm": tq[i].min(),
                        "torque_max_Nm": tq[i].max(),
                        "torque_pp_Nm": self.torque_pp_Nm[i],
                    }
                    for i, name in enumerate(self.section_names)
                ],
            }
        )

    def plot(self, ax: Any = None, front: int | str = 0) -> Any:
        """Three panels over the cycle (against the reference mass's crank angle): the speed
        of the reference mass (flywheel) and of the ``front`` mass (default the first: the
        pulley or damper) [rpm]; every section's twist [mrad]; every section's vibratory
        torque [N·m]. ``ax``: three Axes or None (a new figure). Returns the Axes."""
        from ..plotting.torsion_response import plot_torsional_response

        j = self.mass_index(front)
        w = np.asarray(self.omega) * RPM_PER_RAD_S
        return plot_torsional_response(
            np.rad2deg(np.asarray(self.theta)),
            w[self.reference_mass],
            w[j],
            (self.mass_names[self.reference_mass], self.mass_names[j]),
            np.asarray(self.twist_rad),
            self.vibratory_torque_Nm,
            self.section_names,
            f"{self.engine_name} at {self.rpm:g} rpm",
            ax=ax,
        )


def periodic_range(x: ArrayLike) -> np.ndarray:
    """max − min of each row of ``x`` (samples of one period, uniform), each extreme refined
    by the parabola through it and its two (periodic) neighbours
    (:func:`rotor.dynamics.result.periodic_extremes`): shape ``x.shape[:-1]``."""
    high, low, _, _ = periodic_extremes(np, np.asarray(x, dtype=np.float64))
    return high - low


def _orders_of(x: np.ndarray, strokes: int, max_order: float) -> tuple[np.ndarray, np.ndarray]:
    """Amplitudes by engine order of rows ``x`` sampled uniformly over one cycle."""
    P = x.shape[-1]
    spec = np.abs(np.fft.rfft(x, axis=-1)) * (2.0 / P)
    order = np.arange(spec.shape[-1]) / (strokes / 2)
    keep = (order > 0) & (order <= max_order + 1e-9)
    return order[keep], spec[..., keep]


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class TorsionalSweep(Result):
    """The forced response over a range of speeds (:func:`torsional_sweep`): the resonance
    curves.

    **Per speed** (S speeds): ``rpm`` [rpm]; ``converged`` (bool); ``load_torque_Nm`` [N·m]
    or ``fuel_scale`` [-] (one of them, the other None); ``delta`` (S, n) each mass's δ
    (sampled extremes) [-]; ``torque_pp_Nm`` (S, n − 1) each section's vibratory torque
    peak to peak [N·m]; ``twist_pp_rad`` (S, n − 1) [rad]; ``torque_order_Nm`` (S, n − 1, m)
    each section's vibratory torque by engine order [N·m] at the orders ``order`` (m,) [per
    revolution].

    **About:** ``mass_names``, ``natural_frequencies_hz``, ``engine_name``, ``strokes``,
    ``points_per_cycle``, ``wall_s``.
    """

    rpm: np.ndarray
    converged: np.ndarray
    load_torque_Nm: np.ndarray | None
    fuel_scale: np.ndarray | None
    delta: np.ndarray
    torque_pp_Nm: np.ndarray
    twist_pp_rad: np.ndarray
    order: np.ndarray
    torque_order_Nm: np.ndarray
    mass_names: tuple[str, ...]
    natural_frequencies_hz: np.ndarray
    engine_name: str
    strokes: int
    points_per_cycle: int
    wall_s: float = float("nan")

    @property
    def section_names(self) -> tuple[str, ...]:
        """The shaft sections, ``"front mass–rear mass"``."""
        return section_names(self.mass_names)

    def critical_speeds(self, orders: ArrayLike | None = None) -> list[dict]:
        """Where each elastic mode meets an engine order inside the swept range: dicts with
        ``mode`` (from 1), ``order`` [per revolution], ``rpm`` = 60·f/order [rpm]; ``orders``
        default: the orders of the sweep's torque harmonics."""
        orders = self.order if orders is None else np.asarray(orders, dtype=np.float64)
        lo, hi = float(np.min(self.rpm)), float(np.max(self.rpm))
        out = []
        for m, f in enumerate(np.asarray(self.natural_frequencies_hz)):
            for o in orders:
                r = 60.0 * f / o
                if lo <= r <= hi:
                    out.append({"mode": m + 1, "order": float(o), "rpm": float(r)})
        return sorted(out, key=lambda d: d["rpm"])

    def summary(self) -> str:
        """The swept range, the largest vibratory torque of each section and where it is."""
        ok = np.asarray(self.converged)
        lines = [
            f"{self.engine_name}: torsional forced response at {len(self.rpm)} speeds, "
            f"{np.min(self.rpm):g}…{np.max(self.rpm):g} rpm ({self.points_per_cycle} nodes a cycle); "
            + ("all converged" if ok.all() else f"{int((~ok).sum())} NOT converged"),
            "",
            f"  {'section':<28} {'largest p-p [N·m]':>18} {'at rpm':>8}",
        ]
        tq = np.where(ok[:, None], self.torque_pp_Nm, np.nan)
        for i, name in enumerate(self.section_names):
            col = tq[:, i]
            if np.all(np.isnan(col)):
                lines.append(f"  {name:<28} {'—':>18}")
                continue
            s = int(np.nanargmax(col))
            lines.append(f"  {name:<28} {col[s]:18.1f} {self.rpm[s]:8.0f}")
        crit = self.critical_speeds(_major_orders(self))
        if crit:
            lines += [
                "",
                "  critical speeds of the strong orders (mode, order: rpm): "
                + "; ".join(f"{c['mode']}, {c['order']:g}: {c['rpm']:.0f}" for c in crit[:12])
                + (" …" if len(crit) > 12 else ""),
            ]
        return "\n".join(lines[:60]) + "\n"

    def to_pandas(self) -> Any:
        """One row per speed and section (tidy): ``rpm``, ``section``, ``torque_pp_Nm``,
        ``twist_pp_rad``, ``converged``."""
        import pandas as pd

        S, m = self.torque_pp_Nm.shape
        return pd.DataFrame(
            {
                "rpm": np.repeat(self.rpm, m),
                "section": np.tile(np.array(self.section_names, dtype=object), S),
                "torque_pp_Nm": self.torque_pp_Nm.ravel(),
                "twist_pp_rad": self.twist_pp_rad.ravel(),
                "converged": np.repeat(self.converged, m),
            }
        )

    def to_json_dict(self) -> dict:
        """The speeds and, per speed, convergence, balance, δ of each mass and each section's
        vibratory torque peak to peak [N·m] (null where a speed did not converge)."""
        ok = np.asarray(self.converged)

        def masked(a):
            a = np.asarray(a, dtype=np.float64)
            return np.where(ok.reshape((-1,) + (1,) * (a.ndim - 1)), a, np.nan)

        return json_safe(
            {
                "engine": self.engine_name,
                "rpm": self.rpm,
                "converged": ok,
                "load_torque_Nm": None if self.load_torque_Nm is None else masked(self.load_torque_Nm),
                "fuel_scale": None if self.fuel_scale is None else masked(self.fuel_scale),
                "masses": list(self.mass_names),
                "sections": list(self.section_names),
                "delta": masked(self.delta),
                "torque_pp_Nm": masked(self.torque_pp_Nm),
                "natural_frequencies_hz": self.natural_frequencies_hz,
                "critical_speeds": self.critical_speeds(_major_orders(self)),
            }
        )

    def plot(self, ax: Any = None, sections: Any = None) -> Any:
        """Each section's vibratory torque peak to peak against speed [N·m] (``sections``:
        indices to draw, default all), with the critical speeds of the strong orders (those whose vibratory torque reaches a tenth of the largest) marked.
        ``ax``: one Axes or None. Returns the Axes."""
        from ..plotting.torsion_response import plot_torsional_sweep

        ok = np.asarray(self.converged)
        idx = range(len(self.section_names)) if sections is None else list(sections)
        return plot_torsional_sweep(
            self.rpm,
            np.where(ok[:, None], self.torque_pp_Nm, np.nan)[:, list(idx)],
            [self.section_names[i] for i in idx],
            [c["rpm"] for c in self.critical_speeds(_major_orders(self))],
            f"{self.engine_name}: vibratory torque against speed",
            ax=ax,
        )


def _major_orders(sweep: TorsionalSweep) -> np.ndarray:
    """The orders whose vibratory torque peaks above a tenth of the largest anywhere."""
    amp = np.nanmax(np.where(np.asarray(sweep.converged)[:, None, None], sweep.torque_order_Nm, np.nan), axis=(0, 1))
    if not np.any(np.isfinite(amp)):
        return np.zeros(0)
    return sweep.order[np.nan_to_num(amp) >= 0.1 * np.nanmax(amp)]


# ----------------------------------------------------------------------------- the functions
def _engine_arg(engine: Any, call: str) -> Engine:
    if not isinstance(engine, Engine):
        hint = " (load it first: rotor.load_engine(...))" if isinstance(engine, (str, bytes)) else ""
        raise TypeError(f"{call}(engine): expected a rotor.Engine{hint}, got {what_it_is(engine)}")
    return engine


def torsional_response(
    engine: Engine,
    rpm: float | None = None,
    *,
    load: Load | float | None = None,
    chain: TorsionalChain | None = None,
    imep_scale: ArrayLike = 1.0,
    friction: Friction | bool | None = None,
    grid_deg: float = 0.25,
) -> TorsionalResponse:
    """The periodic steady state of ``engine``'s torsional chain at mean speed ``rpm``
    (harmonic balance, see :mod:`rotor.torsion.response`).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`; its ``[torsion]`` table gives the chain unless
      ``chain`` is given.
    - ``rpm``: time-mean crank speed [rpm]; default the file's ``[operating] rpm``.
    - ``load``: None (the constant load torque at the load mass that keeps the mean speed:
      ``load_torque_Nm``), a number (a constant load [N·m]: the fuelling is scaled to carry
      it) or a :class:`rotor.Load` that does not change in time (``fuel_scale``).
    - ``chain``: a :class:`rotor.TorsionalChain` with cycle-mean inertias (as
      :func:`rotor.torsional_chain` gives them) and a mass for each crank throw.
    - ``imep_scale``: combustion scale per cylinder [-] (one for all or one per cylinder).
    - ``friction``: a :class:`rotor.Friction`, None (the engine file's) or False.
    - ``grid_deg``: node spacing over the cycle [deg] (default 0.25°, as the rigid steady
      state): the response's samples and the cylinder tables. The collocation's error in
      the speeds, against a time-domain run, is about 1.4e-7 of the mean speed at 0.25°,
      7e-7 at 0.5° and 2e-5 at 2° (the MWM six: it falls as the gas torque's harmonics
      above the grid's Nyquist order).

    **Returns:** a :class:`TorsionalResponse`.

    **Raises:** :class:`rotor.EngineError` for bad input (an engine without ``[torsion]``
    and no chain says how to add one); :class:`rotor.NoSteadyStateError` (a
    :class:`rotor.SolverError`) where Newton's method found no periodic solution, when the
    values are concrete; under ``jax.grad``, ``jit`` or ``vmap`` (``imep_scale`` or the
    chain's numbers traced) the result's ``converged`` is False instead, and its arrays are
    JAX's (differentiable: see the module's *Derivatives*).
    """
    call = "torsional_response"
    start = time.perf_counter()
    engine = _engine_arg(engine, call)
    rpm = check_speed_rpm(engine.operating.rpm if rpm is None else rpm, f"{call}(rpm)")
    load = _check_load(load, call)
    engine.check()
    ch = chain_for(engine, chain, f"{call}(chain)")
    _check_grid(grid_deg, engine, call, ch.size)  # before the tables are built
    dc = driven_chain(engine, ch, imep_scale=imep_scale, friction=friction, grid_deg=grid_deg, call=call)
    P = _check_grid(grid_deg, engine, call, dc.size)
    omega_m = rpm / RPM_PER_RAD_S
    _refuse_undamped_resonance(dc, ch, load, rpm, P)
    balance = _balance_for(dc, load, omega_m, call)
    out = _response_kernel(dc, jnp.asarray(omega_m), balance, P)
    traced = any(isinstance(a, jax.core.Tracer) for a in jax.tree_util.tree_leaves(out))
    if not traced:  # one transfer from the device; under jit, grad or vmap the arrays stay JAX's
        out = jax.device_get(out)
    ok, steps, resid = out[5], out[6], out[7]
    if not traced and not ok:
        raise NoSteadyStateError(
            f"no torsional steady state found at {rpm:g} rpm (Newton's method stopped after {int(steps)} steps with "
            f"a residual of {float(resid):.2g} of the torque scale): the chain may sit on an undamped resonance or the "
            "speed may be too low for the flywheel; give the chain damping or try another speed"
        )
    return _response(engine, dc, ch, load, rpm, out, start)


RESONANCE_GAP = 2e-4
"""How close (relative) an engine order's frequency may come to a natural frequency of a
chain without damping before :func:`torsional_response` says there is no steady state,
without solving: there the response grows as 1/(2·gap) and the harmonic balance finds no
solution (on the MWM six without its damping, at 10⁻⁴ of its first critical speed it
stops after its steps; at 10⁻³ it converges)."""


def _refuse_undamped_resonance(dc: DrivenChain, ch: TorsionalChain, load: Load | None, rpm: float, P: int) -> None:
    """:class:`rotor.NoSteadyStateError` before any solving where nothing damps the chain
    (no absolute, relative or modal damping, no speed term in friction or the load) and an
    engine order that the grid of ``P`` nodes resolves excites a natural frequency at
    ``rpm`` [rpm] within :data:`RESONANCE_GAP`. Traced values are not judged."""
    damping, friction = concrete(dc.damping), concrete(dc.friction)
    if damping is None or friction is None or np.any(damping != 0) or np.any(friction[1:] != 0):
        return
    if load is not None and not isinstance(load, ConstantLoad):
        return
    natural = concrete(natural_frequencies(ch))
    if natural is None:
        return
    revs = dc.strokes / 2  # revolutions a cycle: orders come in steps of 1/revs
    orders = np.arange(1, P // 2) / revs
    excited = orders[None, :] * rpm / 60.0  # [Hz]
    gap = np.abs(excited / np.asarray(natural)[:, None] - 1.0)
    mode, k = np.unravel_index(int(np.argmin(gap)), gap.shape)
    if gap[mode, k] < RESONANCE_GAP:
        critical = float(natural[mode]) * 60.0 / orders[k]
        raise NoSteadyStateError(
            f"no torsional steady state at {rpm:g} rpm: order {orders[k]:g} excites mode {mode + 1} "
            f"({float(natural[mode]):.1f} Hz, critical at {critical:.2f} rpm) of a chain with no damping, whose "
            "response there has no finite amplitude; give the chain damping ([torsion] absolute_damping_Nms_per_rad, "
            f"relative_damping_Nms_per_rad or modal_damping_ratio) or a speed more than {100 * RESONANCE_GAP:g} % "
            "away (rotor.campbell lists the critical speeds)"
        )


def _response(engine, dc, ch, load, rpm, out, start) -> TorsionalResponse:
    x, t, theta, omega, accel, ok, steps, resid, torque, gas, loss = out
    traced = any(isinstance(a, jax.core.Tracer) for a in jax.tree_util.tree_leaves((out, ch)))
    host = (lambda a: a) if traced else np.asarray  # numpy where concrete, JAX's arrays under a transformation
    num = (lambda a: a) if traced else float
    twist = theta[:-1] - theta[1:]
    fuel = 1.0 if load is None else x
    v = dc.values  # the per-cylinder tables: mean torque × cycle / swept volume
    imep = (v[:, :, 1].mean(axis=0) + fuel * dc.imep_scale * v[:, :, 2].mean(axis=0)) * engine.cycle_rad
    imep = host(imep / engine.geometry.displacement_m3)
    nodes = np.arange(theta.shape[1]) * (engine.cycle_rad / theta.shape[1])
    return TorsionalResponse(
        theta=nodes,
        t=t,
        angle_rad=theta,
        omega=omega,
        accel=accel,
        twist_rad=twist,
        torque_Nm=torque,
        gas_torque_Nm=gas,
        loss_torque_Nm=loss,
        imep_pa=imep,
        rpm=float(rpm),
        period_s=engine.cycle_rad / (rpm / RPM_PER_RAD_S),
        load_torque_Nm=num(x) if load is None else None,
        fuel_scale=num(x) if load is not None else None,
        converged=ok if traced else bool(ok),
        newton_steps=steps if traced else int(steps),
        residual=num(resid),
        mass_names=tuple(ch.names),
        reference_mass=dc.reference_mass,
        load_mass=dc.load_mass,
        stiffnesses_Nm_per_rad=host(ch.stiffnesses_Nm_per_rad),
        natural_frequencies_hz=host(natural_frequencies(ch)),
        engine_name=engine.name,
        strokes=engine.strokes,
        cycle_rad=engine.cycle_rad,
        wall_s=time.perf_counter() - start,
    )


@eqx.filter_jit
def _sweep_kernel(dc: DrivenChain, omegas: Array, balance: _Balance, P: int, batch: int, max_order: float):
    """Per speed: x, ok, δ per mass (sampled), section torque and twist p-p, torque orders."""
    revs = dc.strokes / 2
    keep = np.nonzero((np.arange(P // 2 + 1) > 0) & (np.arange(P // 2 + 1) / revs <= max_order + 1e-9))[0]

    def one(omega_m):
        x, t, theta, omega, accel, ok, steps, resid = _hb_kernel(dc, omega_m, balance, P)
        twist = theta[:-1] - theta[1:]
        torque = dc.section_torques(twist.T, (omega[:-1] - omega[1:]).T).T
        delta = (jnp.max(omega, axis=1) - jnp.min(omega, axis=1)) / omega_m
        spec = jnp.abs(jnp.fft.rfft(torque, axis=1)) * (2.0 / P)
        pp = jnp.max(torque, axis=1) - jnp.min(torque, axis=1)
        tw = jnp.max(twist, axis=1) - jnp.min(twist, axis=1)
        return x, ok, delta, pp, tw, spec[:, keep]

    return jax.lax.map(one, omegas, batch_size=batch)


def torsional_sweep(
    engine: Engine,
    rpm: ArrayLike,
    *,
    load: Load | float | None = None,
    chain: TorsionalChain | None = None,
    imep_scale: ArrayLike = 1.0,
    friction: Friction | bool | None = None,
    grid_deg: float = 1.0,
    batch: int | None = None,
    max_order: float = 12.0,
) -> TorsionalSweep:
    """The forced response (:func:`torsional_response`) at every speed of ``rpm``: the
    resonance curves, each section's vibratory torque against speed.

    **Arguments:**
    - ``engine``, ``load``, ``chain``, ``imep_scale``, ``friction``: as
      :func:`torsional_response` (the same load and fuelling at every speed).
    - ``rpm``: the speeds [rpm], a 1-D array (e.g. ``np.linspace(800, 2400, 100)``).
    - ``grid_deg``: node spacing [deg] (default 1°: orders up to 180 resolved, a quarter of
      the 0.25° grid's cost).
    - ``batch``: speeds solved at once (``jax.vmap``); batches run one after another
      (``jax.lax.map``), so memory stays at ``batch`` responses. Default 1 on a CPU (where
      a vmapped Newton iteration runs every member to the slowest one's steps and gains
      nothing: 16 speeds took 2.9 s one by one, 4.1 s four at a time) and 16 on an
      accelerator.
    - ``max_order``: the highest engine order of the torque harmonics kept [per revolution].

    **Returns:** a :class:`TorsionalSweep`; a speed without a solution has
    ``converged`` False (its figures are not used in the summary or plot).
    """
    call = "torsional_sweep"
    start = time.perf_counter()
    engine = _engine_arg(engine, call)
    speeds = np.atleast_1d(np.asarray(rpm, dtype=np.float64))
    if speeds.ndim != 1 or speeds.size == 0:
        raise EngineError(f"{call}(rpm): give a 1-D array of speeds [rpm], got shape {speeds.shape}")
    lo, hi, _, _ = PLAUSIBLE[("operating", "rpm")]
    bad = ~(np.isfinite(speeds) & (speeds >= lo) & (speeds <= hi))
    if np.any(bad):
        raise EngineError(f"{call}(rpm): {speeds[bad][0]!r} is not a speed between {lo:g} and {hi:g} rpm")
    if batch is None:
        batch = 1 if jax.default_backend() == "cpu" else 16
    batch = require_whole(batch, f"{call}(batch)")
    max_order = require_number(max_order, f"{call}(max_order)", "per revolution")
    if not (math.isfinite(max_order) and max_order > 0):
        raise EngineError(f"{call}(max_order) = {max_order!r}: must be a positive order")
    load = _check_load(load, call)
    size = chain_for(engine, chain, f"{call}(chain)").size
    _check_grid(grid_deg, engine, call, size, speeds=min(batch, speeds.size))  # before the tables are built
    dc = driven_chain(engine, chain, imep_scale=imep_scale, friction=friction, grid_deg=grid_deg, call=call)
    P = _check_grid(grid_deg, engine, call, dc.size, speeds=min(batch, speeds.size))
    balance = _balance_for(dc, load, speeds[0] / RPM_PER_RAD_S, call)
    out = _sweep_kernel(dc, jnp.asarray(speeds / RPM_PER_RAD_S), balance, P, min(batch, speeds.size), max_order)
    x, ok, delta, pp, tw, spec = (np.asarray(a) for a in jax.device_get(out))
    order = np.arange(P // 2 + 1) / (engine.strokes / 2)
    order = order[(order > 0) & (order <= max_order + 1e-9)]
    ch = chain_for(engine, chain, f"{call}(chain)")
    return TorsionalSweep(
        rpm=speeds,
        converged=ok.astype(bool),
        load_torque_Nm=x if load is None else None,
        fuel_scale=x if load is not None else None,
        delta=delta,
        torque_pp_Nm=pp,
        twist_pp_rad=tw,
        order=order,
        torque_order_Nm=spec,
        mass_names=tuple(ch.names),
        natural_frequencies_hz=np.asarray(natural_frequencies(ch)),
        engine_name=engine.name,
        strokes=engine.strokes,
        points_per_cycle=P,
        wall_s=time.perf_counter() - start,
    )
