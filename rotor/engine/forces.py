"""Forces and torques of the crank mechanism (the textbook dynamic calculation of Shishkov,
"Dinamika dvigatelei" [Engine dynamics: guide to the course project], South Ural State
University, 2014, §3.2.2, after Kolchin & Demidov; signs as there).

Per cylinder, at crank speed ω (the textbook calculation holds ω constant):

- gas force P_g = (p − p_crankcase)·A_p, positive towards the crank axis;
- reciprocating inertia force P_j = −m_rec·j, j = ω²·d²s/dθ²;
- total P_Σ = P_g + P_j;
- side force on the liner N = P_Σ·tan β; force along the rod K = P_Σ / cos β;
- radial force on the throw Z = K·cos(θ + β); tangential force T = K·sin(θ + β);
- torque M = T·R (= P_Σ·ds/dθ by virtual work, which also holds for slave rods).

Equation-of-motion fidelity: the *textbook* (``"constant"``) model adds the inertia
torque of the reciprocating masses, −m_rec·ω²·s″·s′, to the gas torque; the
*variable-inertia* model must not, because there that torque is −½·I′(θ)·ω² and comes
out of I(θ). :func:`gas_torque` is the gas torque alone; :func:`reciprocating_inertia_torque`
the textbook inertia torque.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from ..checks import called_from_outside, check_size, tracing
from ..errors import EngineError
from .kinematics import piston_motion, rod_motion
from .mechanism import engine_piston_motion
from .model import engine_jit, guard_engine, require_engine
from .plausible import checked_angle, require_number, require_whole

if TYPE_CHECKING:
    from .model import Engine

__all__ = [
    "cylinder_pressure",
    "cylinder_gas_torques",
    "gas_torque",
    "reciprocating_inertia_torque",
    "total_torque",
    "crank_forces",
    "imep_pa",
    "mean_gas_torque",
    "indicated_power_w",
]


@engine_jit  # one compiled call per shape, not hundreds of eager operations
def cylinder_pressure(engine: Engine, theta: ArrayLike) -> Array:
    """Absolute pressure in every cylinder [Pa], shape ``theta.shape + (cylinders,)``.

    **Arguments:** ``engine``: a :class:`rotor.Engine`; ``theta``: engine crank angle [rad].
    """
    require_engine(engine, "cylinder_pressure(engine)")
    phi = engine.cycle_angles(theta)
    return engine.pressure(phi, engine.geometry, engine.strokes)


@engine_jit  # one compiled call per shape, not hundreds of eager operations
def cylinder_gas_torques(engine: Engine, theta: ArrayLike, model: str = "exact") -> Array:
    """Gas torque of each cylinder, (p − p_cc)·A·ds/dθ [N·m], shape ``theta.shape + (cylinders,)``.

    **Arguments:** ``engine``; ``theta``: engine crank angle [rad]; ``model``: piston
    kinematics, ``"exact"`` or ``"series"``.
    """
    require_engine(engine, "cylinder_gas_torques(engine)")
    ds = engine_piston_motion(engine, theta, model).ds
    force = (cylinder_pressure(engine, theta) - engine.pressure.crankcase_pa) * engine.geometry.piston_area_m2
    return force * ds


@engine_jit  # one compiled call per shape, not hundreds of eager operations
def gas_torque(engine: Engine, theta: ArrayLike, model: str = "exact") -> Array:
    """Total gas torque of the engine on the crankshaft [N·m], shape of ``theta``.

    **Arguments:** ``engine``; ``theta``: engine crank angle [rad]; ``model``: ``"exact"``/``"series"``.
    """
    require_engine(engine, "gas_torque(engine)")
    return jnp.sum(cylinder_gas_torques(engine, theta, model), axis=-1)


@engine_jit  # one compiled call per shape, not dozens of eager operations
def reciprocating_inertia_torque(engine: Engine, theta: ArrayLike, omega: ArrayLike, model: str = "exact") -> Array:
    """Textbook inertia torque of the reciprocating masses at constant speed [N·m].

    Σ −m_rec·ω²·(d²s/dθ²)·(ds/dθ) = −½·I′_rec(θ)·ω²; its mean over a revolution is zero.
    Use it only with a constant inertia (the textbook model), never with I(θ).

    **Arguments:** ``engine``; ``theta``: engine crank angle [rad]; ``omega``: crank speed
    [rad/s]; ``model``: ``"exact"``/``"series"``.
    """
    require_engine(engine, "reciprocating_inertia_torque(engine)")
    pm = engine_piston_motion(engine, theta, model)
    m_rec, _ = engine.masses.two_mass_split(engine.geometry.rod_length_m)
    return jnp.sum(-m_rec * omega**2 * pm.d2s * pm.ds, axis=-1)


@engine_jit  # one compiled call per shape, not dozens of eager operations
def total_torque(engine: Engine, theta: ArrayLike, omega: ArrayLike, model: str = "exact") -> Array:
    """Textbook total torque of the engine at constant speed [N·m]: gas torque plus the
    reciprocating inertia torque, summed over the cylinders at their phases (Shishkov
    (2014) §3.2.3 and §3.2.11; the total tangential force is this divided by R).

    **Arguments:** ``engine``; ``theta``: engine crank angle [rad]; ``omega``: crank speed
    [rad/s]; ``model``: piston kinematics, ``"exact"`` or ``"series"``.
    """
    require_engine(engine, "total_torque(engine)")
    return gas_torque(engine, theta, model) + reciprocating_inertia_torque(engine, theta, omega, model)


def crank_forces(
    engine: Engine, theta: ArrayLike, omega: ArrayLike, cylinder: int = 1, model: str = "exact"
) -> dict[str, Array]:
    """The textbook forces of one cylinder at constant crank speed (Shishkov (2014) §3.2.2).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``theta``: engine crank angle [rad] (array).
    - ``omega``: crank speed [rad/s].
    - ``cylinder``: cylinder number, 1…n (not a slave of an articulated rod).
    - ``model``: piston kinematics, ``"exact"`` or ``"series"``.

    **Returns:** a dict of arrays: ``s_m``, ``v_m_s``, ``j_m_s2``, ``pg_N``, ``pj_N``,
    ``psum_N``, ``n_N``, ``k_N``, ``z_N``, ``t_N``, ``m_Nm`` (SI units as named).

    **Raises:** :class:`rotor.EngineError` for a cylinder the engine does not have or one a
    slave rod drives; ``TypeError`` for a cylinder that is not a whole number.
    """
    engine = require_engine(engine, "crank_forces(engine)")
    if called_from_outside():
        engine = guard_engine(engine) if tracing() else engine
        theta = checked_angle("crank_forces", "theta", theta)
        omega = checked_angle("crank_forces", "omega", omega, "rad/s")
    return cylinder_forces(engine, theta, omega, cylinder_index(engine, cylinder), model)


def cylinder_index(engine: Engine, cylinder: int) -> np.ndarray:
    """The index (0…n−1) of ``cylinder`` (1…n) as an array, so that one program serves every
    cylinder; :class:`rotor.EngineError` where the engine has no such cylinder or a slave
    rod drives it (the textbook table is for ordinary rods), or where it is not a whole
    number."""
    cylinder = require_whole(cylinder, "cylinder")
    if not 1 <= cylinder <= engine.cylinders:
        raise EngineError(f"cylinder {cylinder} does not exist: the engine has cylinders 1…{engine.cylinders}")
    if cylinder - 1 in engine.slave_index():
        raise EngineError(f"cylinder {cylinder} is driven by a slave rod: the textbook table is for ordinary rods")
    return np.asarray(cylinder - 1)


@engine_jit  # one compiled call per shape, not dozens of eager operations
def cylinder_forces(engine: Engine, theta: ArrayLike, omega: ArrayLike, i: ArrayLike, model: str) -> dict[str, Array]:
    """:func:`crank_forces` of the cylinder of index ``i`` (0…n−1, an integer array from
    :func:`cylinder_index`, which checks it), compiled once for every cylinder."""
    g = engine.geometry
    theta = jnp.asarray(theta, dtype=jnp.float64)
    alpha = engine.mechanical_angles(theta)[..., i]
    pm = engine_piston_motion(engine, theta, model)
    s, ds, d2s = pm.s[..., i], pm.ds[..., i], pm.d2s[..., i]
    beta = rod_motion(alpha, g.crank_radius_m, g.rod_length_m, g.pin_offset_m).beta
    m_rec, _ = engine.masses.two_mass_split(g.rod_length_m)
    v = ds * omega
    j = d2s * omega**2
    pg = (cylinder_pressure(engine, theta)[..., i] - engine.pressure.crankcase_pa) * g.piston_area_m2
    pj = -m_rec * j
    psum = pg + pj
    k = psum / jnp.cos(beta)
    t = k * jnp.sin(alpha + beta)
    return {
        "s_m": s,
        "v_m_s": v,
        "j_m_s2": j,
        "pg_N": pg,
        "pj_N": pj,
        "psum_N": psum,
        "n_N": psum * jnp.tan(beta),
        "k_N": k,
        "z_N": k * jnp.cos(alpha + beta),
        "t_N": t,
        "m_Nm": t * g.crank_radius_m,
    }


def _cycle_grid(engine, points_per_rev: int = 1440):
    n = int(points_per_rev * engine.strokes / 2)
    return jnp.linspace(0.0, engine.cycle_rad, n, endpoint=False)


@engine_jit  # one compiled call instead of dozens of eagerly compiled operations
def imep_pa(engine: Engine) -> Array:
    """Indicated mean effective pressure of one cylinder, ∮p·dV / V_h [Pa].

    ∮ p·A·(ds/dφ)·dφ over the cycle on a grid of 0.25° (the tests check it against the
    mean gas torque, the same work reached through the forces).
    """
    require_engine(engine, "imep_pa(engine)")
    phi = _cycle_grid(engine)
    g = engine.geometry
    # one cylinder at its own cycle angle: cycle angle φ is its mechanical angle (TDC at 0)
    ds = piston_motion(phi, g.crank_radius_m, g.rod_length_m, g.pin_offset_m).ds
    p = engine.pressure(phi, g, engine.strokes)
    work = jnp.mean(p * g.piston_area_m2 * ds) * engine.cycle_rad
    return work / g.displacement_m3


@engine_jit
def mean_gas_torque(engine: Engine) -> Array:
    """Cycle mean of the engine's gas torque [N·m] = n·IMEP·V_h / (cycle angle)."""
    require_engine(engine, "mean_gas_torque(engine)")
    theta = _cycle_grid(engine)
    return jnp.mean(gas_torque(engine, theta))


def indicated_power_w(engine: Engine, omega: ArrayLike | None = None) -> Array:
    """Indicated power [W] = mean gas torque × ω.

    **Arguments:** ``omega``: crank speed [rad/s]; default the engine's ``[operating] rpm``.
    """
    engine = require_engine(engine, "indicated_power_w(engine)")
    if called_from_outside():
        engine = guard_engine(engine) if tracing() else engine
        omega = None if omega is None else checked_angle("indicated_power_w", "omega", omega, "rad/s")
    omega = engine.operating.omega if omega is None else omega
    return mean_gas_torque(engine) * omega


TABLE_ROW_BYTES = 4096
"""Memory one row of a crank table takes while it is computed and written as text [bytes]:
its twelve columns, the intermediates of every cylinder, and the text of the row."""


def table_angles_deg(engine: Engine, step_deg: float) -> np.ndarray:
    """Angles 0, step, …, cycle (inclusive, as in the tables of Shishkov (2014)) [deg].

    **Arguments:** ``engine``; ``step_deg``: the angle step [deg], dividing the cycle.
    A step so small that the table would not fit in memory is refused before anything is
    allocated (:func:`rotor.checks.check_size`)."""
    step_deg = require_number(step_deg, "step_deg", "deg")
    cycle = 360.0 * engine.strokes / 2
    if not (np.isfinite(step_deg) and 0 < step_deg <= cycle):
        raise EngineError(f"step must be a positive angle up to {cycle:g} degrees, got {step_deg!r}")
    rows = cycle / step_deg + 1
    check_size(
        rows * TABLE_ROW_BYTES,
        f"a table at a step of {step_deg:g}° ({rows:.3g} rows)",
        "use a larger step, e.g. step_deg=1 or step_deg=10 (degrees)",
    )
    n = int(round(cycle / step_deg))
    if not np.isclose(n * step_deg, cycle):
        raise EngineError(f"step {step_deg:g}° must divide the {cycle:g}° cycle evenly")
    return np.linspace(0.0, cycle, n + 1)
