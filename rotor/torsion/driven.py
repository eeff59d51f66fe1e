"""The driven chain: a torsional chain with its engine's mechanisms, gas torques and
friction on its masses, the model that the forced response
(:func:`rotor.torsional_response`, :mod:`rotor.torsion.response`) and the transient
(:func:`rotor.torsional_simulate`, :mod:`rotor.torsion.transient`) solve.

**The model.** The chain's masses turn at their own angles θ_j; mass j carries its
constant inertia J_j (the ``[torsion]`` table's; for a given chain its cycle-mean inertia
less its mechanisms' mean) and the mechanisms of the cylinders on its crank throw, whose
reduced inertia I_c and gas torque M_c are evaluated at *that mass's own angle*
(:func:`rotor.cylinder_inertia`, :func:`rotor.cylinder_gas_torques`). Lagrange's
equations of T = ½·Σ A_j(θ_j)·θ̇_j², A_j = J_j + Σ_{c on j} I_c, V = ½·θᵀKθ give, for
every mass,

    A_j(θ_j)·θ̈_j + ½·A_j′(θ_j)·θ̇_j² + (K·θ)_j + (C·θ̇)_j = Σ_{c on j} M_c(θ_j) − F_j(θ̇_j) − δ_{jL}·M_load,

C the chain's damping (absolute, relative and modal, :func:`rotor.torsion.modes.modal_damping_matrix`)
acting on the vibratory speeds θ̇ − ω̄ (the linear theory's: uniform rotation at the mean
speed ω̄ meets no damping; its losses are the engine's friction),
F_j the engine's friction a + b·ω + c·ω² shared equally by the cylinders (each share on
its throw's mass, at that mass's speed), and the load at the chain's load mass L. As in
:func:`rotor.steady_state` the balance is either the load torque that keeps the mean speed
(``load=None``: a constant torque, ``load_torque_Nm``) or a given speed-dependent load,
carried by scaling the fuelling (``fuel_scale``). With very stiff shafts every mass turns
with one angle and the sum of the equations is the rigid model,
I(θ)·θ̈ + ½·I′(θ)·θ̇² = M(θ) − losses, with I = [crankshaft] inertia + Σ I_c.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from ..checks import arrays_only, concrete
from ..dynamics.crank_train import grid_points
from ..dynamics.equation import friction_coefficients
from ..engine.forces import cylinder_gas_torques
from ..engine.friction import Friction
from ..engine.inertia import cylinder_inertia
from ..engine.model import Engine, engine_jit
from ..engine.plausible import what_it_is
from ..errors import EngineError
from .model import TorsionalChain, torsional_chain
from .modes import modal_damping_matrix

__all__ = ["DrivenChain", "chain_for", "driven_chain", "mass_index", "section_names"]


class DrivenChain(eqx.Module):
    """A torsional chain with its engine's mechanisms and gas torques on its throw masses:
    what the forced response (:func:`torsional_response`) and the transient
    (:func:`rotor.torsional_simulate`) integrate.

    **Fields:** ``values``, ``slopes``: per cylinder, on a uniform grid over the cycle, the
    mechanism's reduced inertia I_c [kg·m²], its motored gas torque and its combustion
    torque (fired minus motored) [N·m], and their θ-derivatives, shape (N, cylinders, 3),
    or None for a chain without an engine; ``onto``: (cylinders, n), 1 where cylinder c's
    throw lies on mass j; ``constant_inertias``: J_j [kg·m²], (n,); ``mean_inertias``: the
    cycle-mean inertia of each mass, mechanisms included [kg·m²], (n,) (the chain's);
    ``stiffnesses``: k_i [N·m/rad], (n − 1,); ``section_damping``: the shafts' relative
    damping d_i [N·m·s/rad], (n − 1,); ``damping``: the whole damping matrix C
    [N·m·s/rad], (n, n); ``friction``: the engine's friction (a, b, c) [N·m, N·m·s/rad,
    N·m·s²/rad²]; ``friction_share``: the share of it on each mass [-], (n,);
    ``imep_scale``: combustion scale per cylinder [-]; ``cycle_rad`` [rad], ``strokes``,
    ``load_mass``, ``reference_mass`` (0-based; static).
    """

    values: Array | None
    slopes: Array | None
    onto: Array | None
    constant_inertias: Array
    mean_inertias: Array
    stiffnesses: Array
    section_damping: Array
    damping: Array
    friction: Array
    friction_share: Array
    imep_scale: Array
    cycle_rad: float = eqx.field(static=True)
    strokes: int = eqx.field(static=True)
    load_mass: int = eqx.field(static=True)
    reference_mass: int = eqx.field(static=True)

    @property
    def size(self) -> int:
        """The number of masses n."""
        return int(self.constant_inertias.shape[0])

    @property
    def has_engine(self) -> bool:
        """Whether the chain carries an engine's mechanisms and gas torques."""
        return self.values is not None

    @property
    def stiffness_matrix(self) -> Array:
        """K [N·m/rad], (n, n)."""
        k, n = self.stiffnesses, self.size
        diag = jnp.zeros(n).at[:-1].add(k).at[1:].add(k)
        return jnp.diag(diag) - jnp.diag(k, 1) - jnp.diag(k, -1)

    def _cylinders_at(self, theta: Array) -> tuple[Array, Array]:
        """Hermite-interpolated table (values, slopes) of each cylinder at its mass's angle:
        ``theta`` (..., n) [rad] → two arrays (..., cylinders, 3)."""
        assert self.values is not None and self.slopes is not None and self.onto is not None
        th = theta @ self.onto.T  # each cylinder at its throw mass's angle (one-hot: exact)
        N = self.values.shape[0]
        h = self.cycle_rad / N
        u = th / h
        j = jnp.floor(u)
        tau = (u - j)[..., None]
        j0 = jnp.mod(j, N).astype(jnp.int32)
        j1 = jnp.mod(j0 + 1, N)
        c = jnp.arange(self.values.shape[1])
        f0, f1 = self.values[j0, c], self.values[j1, c]
        d0, d1 = self.slopes[j0, c] * h, self.slopes[j1, c] * h
        t2, t3 = tau * tau, tau * tau * tau
        val = (2 * t3 - 3 * t2 + 1) * f0 + (t3 - 2 * t2 + tau) * d0 + (3 * t2 - 2 * t3) * f1 + (t3 - t2) * d1
        der = ((6 * t2 - 6 * tau) * (f0 - f1) + (3 * t2 - 4 * tau + 1) * d0 + (3 * t2 - 2 * tau) * d1) / h
        return val, der

    def inertias(self, theta: ArrayLike) -> tuple[Array, Array]:
        """Each mass's whole inertia A_j(θ_j) [kg·m²] and its derivative A_j′ [kg·m²/rad] at
        the masses' angles ``theta`` [rad], shape (..., n) each."""
        theta = jnp.asarray(theta, dtype=jnp.float64)
        if not self.has_engine:
            return jnp.broadcast_to(self.constant_inertias, theta.shape), jnp.zeros_like(theta)
        assert self.onto is not None
        val, der = self._cylinders_at(theta)
        return self.constant_inertias + val[..., 0] @ self.onto, der[..., 0] @ self.onto

    def gas_torques(self, theta: ArrayLike, fuel: ArrayLike = 1.0) -> Array:
        """The gas torque on each mass [N·m] at the masses' angles ``theta`` [rad], (..., n):
        each cylinder's motored torque plus ``fuel`` [-] × ``imep_scale`` × its combustion
        torque."""
        theta = jnp.asarray(theta, dtype=jnp.float64)
        if not self.has_engine:
            return jnp.zeros_like(theta)
        assert self.onto is not None
        val, _ = self._cylinders_at(theta)
        return (val[..., 1] + fuel * self.imep_scale * val[..., 2]) @ self.onto

    def friction_torques(self, omega: ArrayLike) -> Array:
        """The engine's friction on each mass [N·m] at the masses' speeds ``omega`` [rad/s], (..., n)."""
        omega = jnp.asarray(omega, dtype=jnp.float64)
        a, b, c = self.friction
        return self.friction_share * (a + b * omega + c * omega**2)

    def damping_torques(self, omega: ArrayLike, omega_ref: ArrayLike) -> Array:
        """The damping torque on each mass [N·m], C·(θ̇ − ω̄): the masses' speeds ``omega``
        [rad/s], (..., n), relative to the uniform rotation ``omega_ref`` [rad/s] about which
        the torsional model is written (the linear theory's vibratory velocity; relative and
        modal damping see only the differences, absolute damping also the rigid body's
        speed fluctuation, not the mean speed, whose losses are the engine's friction)."""
        return (jnp.asarray(omega) - omega_ref) @ self.damping.T

    def section_torques(self, twist: ArrayLike, twist_rate: ArrayLike) -> Array:
        """The torque each shaft section carries from the front mass to the rear one [N·m],
        k_i·(θ_i − θ_{i+1}) + d_i·(θ̇_i − θ̇_{i+1}), from its ``twist`` θ_i − θ_{i+1} [rad]
        and ``twist_rate`` [rad/s], (..., n − 1)."""
        return self.stiffnesses * jnp.asarray(twist) + self.section_damping * jnp.asarray(twist_rate)

    def energy(self, theta: ArrayLike, omega: ArrayLike) -> Array:
        """Kinetic plus elastic energy ½·Σ A_j(θ_j)·θ̇_j² + ½·Σ k_i·(θ_i − θ_{i+1})² [J] at
        the angles ``theta`` [rad] and speeds ``omega`` [rad/s], (..., n) → (...)."""
        theta = jnp.asarray(theta, dtype=jnp.float64)
        A, _ = self.inertias(theta)
        twist = theta[..., :-1] - theta[..., 1:]
        return 0.5 * jnp.sum(A * jnp.asarray(omega) ** 2, axis=-1) + 0.5 * jnp.sum(self.stiffnesses * twist**2, axis=-1)

    def mean_gas_torque(self, fuel: ArrayLike = 1.0) -> Array:
        """The cycle mean of the whole engine's gas torque [N·m] at fuel scale ``fuel`` [-]."""
        if not self.has_engine:
            return jnp.asarray(0.0)
        assert self.values is not None
        return jnp.sum(jnp.mean(self.values[:, :, 1] + fuel * self.imep_scale * self.values[:, :, 2], axis=0))

    def mean_combustion_torque(self) -> Array:
        """The cycle mean of the combustion torque on each mass at ``imep_scale`` [N·m], (n,)."""
        if not self.has_engine:
            return jnp.zeros(self.size)
        assert self.values is not None and self.onto is not None
        return (self.imep_scale * jnp.mean(self.values[:, :, 2], axis=0)) @ self.onto


def mass_index(names: tuple[str, ...], reference: int, mass: int | str | None) -> int:
    """The 0-based index of ``mass`` in a chain whose masses are ``names``: an index
    (negative from the end), a name, or None (``reference``)."""
    n = len(names)
    if mass is None:
        return reference
    if isinstance(mass, str):
        if mass not in names:
            raise ValueError(f"mass = {mass!r}: the chain's masses are {', '.join(map(repr, names))}")
        return names.index(mass)
    if isinstance(mass, (bool, np.bool_)) or not isinstance(mass, (int, np.integer)) or not -n <= mass < n:
        raise ValueError(f"mass = {mass!r}: a mass index 0 … {n - 1} or a name")
    return int(mass) % n


def section_names(names: tuple[str, ...]) -> tuple[str, ...]:
    """The name of each shaft section from its masses' ``names``: ``"damper–gear train"``."""
    return tuple(f"{a}–{b}" for a, b in zip(names[:-1], names[1:]))


@engine_jit
def _tables(engine: Engine, points: int):
    """Per cylinder on ``points`` nodes over the cycle: I_c, motored torque, combustion
    torque, and their derivatives (automatic differentiation), (points, cylinders, 3)."""
    theta = jnp.arange(points) * (engine.cycle_rad / points)
    motored = engine.replace(pressure=engine.pressure.motored(engine.strokes))

    def cols(th):
        m_mot = cylinder_gas_torques(motored, th)
        return jnp.stack([cylinder_inertia(engine, th), m_mot, cylinder_gas_torques(engine, th) - m_mot], axis=-1)

    return jax.jvp(cols, (theta,), (jnp.ones_like(theta),))


def chain_for(engine: Engine | None, chain: TorsionalChain | None, call: str) -> TorsionalChain:
    """``chain``, checked to be a :class:`rotor.TorsionalChain`, or by default ``engine``'s own
    (its ``[torsion]`` table); ``call`` names the argument in the errors."""
    if chain is None:
        if engine is None:
            raise TypeError(f"{call}: give an engine or a chain")
        return torsional_chain(engine)  # EngineError (how to add a [torsion] table) if it has none
    if not isinstance(chain, TorsionalChain):
        raise TypeError(f"{call}: chain must be a rotor.TorsionalChain, got {what_it_is(chain)}")
    return chain


def driven_chain(
    engine: Engine | None,
    chain: TorsionalChain | None = None,
    *,
    imep_scale: ArrayLike = 1.0,
    friction: Friction | bool | None = None,
    grid_deg: float = 0.25,
    call: str = "driven_chain",
) -> DrivenChain:
    """The chain of ``engine`` (or ``chain``) with the engine's mechanisms, gas torques and
    friction on its masses (:class:`DrivenChain`).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`, or None for a chain without an engine (no
      mechanisms, no gas torque).
    - ``chain``: a :class:`rotor.TorsionalChain` whose inertias are *cycle means* with the
      mechanisms included, as :func:`rotor.torsional_chain` gives them; default the
      engine's own (its ``[torsion]`` table). With an engine, its ``throw_masses`` must name
      a mass for each of the engine's crank throws.
    - ``imep_scale``: combustion scale per cylinder [-] (a number or one per cylinder).
    - ``friction``: a :class:`rotor.Friction`, None (the engine file's, if any) or False.
    - ``grid_deg``: node spacing of the cylinder tables [deg]; must divide the cycle.
    - ``call``: the public function's name, for the error messages.

    **Raises:** :class:`rotor.EngineError` for an engine without a ``[torsion]`` table and no
    chain, a chain that does not fit the engine, or a bad argument; ``TypeError`` for a
    wrong type.
    """
    if engine is not None and not isinstance(engine, Engine):
        hint = " (load it first: rotor.load_engine(...))" if isinstance(engine, (str, bytes)) else ""
        raise TypeError(f"{call}(engine): expected a rotor.Engine{hint}, got {what_it_is(engine)}")
    if engine is not None:
        engine.check()
    chain = chain_for(engine, chain, f"{call}(chain)")
    n = chain.size
    K_damp = chain.damping_matrix() + modal_damping_matrix(chain)
    d_rel = chain.relative_damping_Nms_per_rad if chain.relative_damping_Nms_per_rad is not None else jnp.zeros(n - 1)
    if engine is None:
        return DrivenChain(
            None,
            None,
            None,
            chain.inertias_kgm2,
            chain.inertias_kgm2,
            chain.stiffnesses_Nm_per_rad,
            d_rel,
            K_damp,
            jnp.zeros(3),
            jnp.zeros(n),
            jnp.zeros(0),
            2 * np.pi,
            2,
            chain.load_mass,
            chain.load_mass,
        )
    if len(chain.throw_masses) != engine.throw_count:
        raise EngineError(
            f"{call}(chain): throw_masses = {list(chain.throw_masses)} names {len(chain.throw_masses)} crank "
            f"throw{'s' if len(chain.throw_masses) != 1 else ''}, engine {engine.name!r} has {engine.throw_count}: "
            "give the (0-based) mass of each crank throw"
        )
    points = grid_points(engine.strokes, grid_deg, engine.cylinders)
    C = engine.cylinders
    scale = jnp.asarray(imep_scale, dtype=jnp.float64)
    if scale.ndim > 1 or (scale.ndim == 1 and scale.shape[0] not in (1, C)):
        raise EngineError(
            f"imep_scale = {imep_scale!r}: one combustion scale for all cylinders or one per cylinder ({C})"
        )
    sc = concrete(scale)  # the values are checked where they are concrete (not under jit, grad or vmap)
    if sc is not None and not np.all(np.isfinite(sc)):
        raise EngineError(
            f"imep_scale = {imep_scale!r}: one finite combustion scale for all cylinders or one per cylinder ({C})"
        )
    if sc is not None and np.any(sc < 0):
        raise EngineError(f"imep_scale = {imep_scale!r}: a combustion scale must be zero or positive")
    engine = arrays_only(engine)
    values, slopes = _tables(engine, points)
    masses = np.array([chain.throw_masses[k] for k in engine.throw_index])
    onto = np.zeros((C, n))
    onto[np.arange(C), masses] = 1.0
    mean_mech = jnp.mean(values[:, :, 0], axis=0) @ onto
    J_const = chain.inertias_kgm2 - mean_mech
    jc = concrete(J_const)
    if jc is not None and np.any(jc <= 0):
        j = int(np.argmin(jc))
        raise EngineError(
            f"{call}(chain): mass {j} ({chain.names[j]!r}) has {float(chain.inertias_kgm2[j]):g} kg·m², less than the "
            f"mean inertia of the rods and pistons on it ({float(mean_mech[j]):g} kg·m²): a chain's inertias are cycle "
            "means with the mechanisms included (as rotor.torsional_chain gives them)"
        )
    vals = concrete(values)
    if vals is not None and not np.all(np.isfinite(vals)):
        raise EngineError(f"engine {engine.name!r}: a cylinder's inertia or gas torque is not finite; check its units")
    share = jnp.asarray(onto.sum(axis=0) / C)
    return DrivenChain(
        values,
        slopes,
        jnp.asarray(onto),
        J_const,
        chain.inertias_kgm2,
        chain.stiffnesses_Nm_per_rad,
        d_rel,
        K_damp,
        jnp.asarray(friction_coefficients(engine, friction), dtype=jnp.float64),
        share,
        jnp.broadcast_to(scale, (C,)),
        engine.cycle_rad,
        engine.strokes,
        chain.load_mass,
        chain.load_mass,
    )
