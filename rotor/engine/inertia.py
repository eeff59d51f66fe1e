"""Reduced moment of inertia of the crank train, I(θ), and its derivative (V. A. Lashko,
"Matrix methods in calculations of torsional vibrations of power plants with ICE", for
articulated rods; V. F. Anisimov, M. P. Yelenich & V. V. Melnyk, "Modelling a piston engine
by the irregularity of crankshaft rotation", for the A·cos²α + B·cosα + C form).

The kinetic energy of the moving parts at crank speed ω is ½·I(θ)·ω², with

    I(θ) = J + Σ_cylinders [ m_rot·R² + m_rec·(ds/dθ)² + rod terms ]

where J is ``[crankshaft] inertia_kgm2``. The rod terms are, for the full rod, its
mass times the squared velocity of its centre of mass per unit ω plus its own inertia
times (dβ/dθ)²; for a slave rod, its knuckle-pin share times the knuckle pin's squared
velocity per unit ω.

Models (``model=``):

- ``"exact"``: the expression above (default).
- ``"coefficients"``: each cylinder's I_cyl(α) replaced by the form of Anisimov
  et al., A·cos²α + B·cosα + C, with A, B, C chosen so that the mean and the first and second
  harmonics of the exact I_cyl are kept (see :func:`inertia_coefficients`). For a
  central two-mass cylinder A ≈ −m_rec·R², B ≈ m_rec·R²·λ/2, C ≈ m_rot·R² + m_rec·R²·(1 + λ²/8);
  it neglects the 3rd and 4th harmonics, of relative size λ/2 and λ²/8 of m_rec·R².
  (The coefficients printed in that paper are the moment of the masses about the crank
  axis, m·x², which contains L²-terms and is not the kinetic-energy inertia; rotor keeps
  the paper's form but fits it to the kinetic energy.)
- ``"mean"``: the cycle mean of I(θ), a constant.

I'(θ) comes from automatic differentiation of the same expression.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .articulated import knuckle_velocity_sq, slave_piston_motion
from .kinematics import piston_motion, rod_motion
from .mechanism import slave_geometry
from .model import engine_jit, require_engine

if TYPE_CHECKING:
    from .model import Engine

__all__ = [
    "cylinder_inertia",
    "reduced_inertia",
    "reduced_inertia_derivative",
    "inertia_coefficients",
    "mean_reduced_inertia",
]

_MODELS = ("exact", "coefficients", "mean")
_FOURIER_POINTS = 256


def ordinary_cylinder_inertia(alpha, geometry, masses):
    R, L, k = geometry.crank_radius_m, geometry.rod_length_m, geometry.pin_offset_m
    ds = piston_motion(alpha, R, L, k).ds
    if not masses.full_rod:
        return masses.rotating_kg * R**2 + masses.reciprocating_kg * ds**2
    beta, dbeta, _ = rod_motion(alpha, R, L, k)
    a = masses.rod_cg_from_big_end_m
    # centre of mass = crank pin + a·(unit vector big end → piston pin)
    vx = -R * jnp.sin(alpha) - a * dbeta * jnp.sin(beta)
    vy = R * jnp.cos(alpha) - a * dbeta * jnp.cos(beta)
    return (
        masses.rotating_kg * R**2
        + masses.reciprocating_kg * ds**2
        + masses.rod_kg * (vx**2 + vy**2)
        + masses.rod_inertia_kgm2 * dbeta**2
    )


@engine_jit  # one compiled call per shape, not dozens of eager operations
def cylinder_inertia(engine: Engine, theta: ArrayLike) -> Float[Array, "... cylinders"]:
    """Each cylinder's contribution to I(θ) [kg·m²], shape ``theta.shape + (cylinders,)``.

    **Arguments:** ``engine``: a :class:`rotor.Engine`; ``theta``: engine crank angle [rad].
    """
    require_engine(engine, "cylinder_inertia(engine)")
    alpha = engine.mechanical_angles(theta)
    out = ordinary_cylinder_inertia(alpha, engine.geometry, engine.masses)
    art = engine.articulated
    for s, m in engine.slave_index().items():
        assert art is not None  # slaves exist only on an articulated engine
        sg = slave_geometry(engine, s, m)
        a_master = alpha[..., s] + sg.bank_rad
        ds = slave_piston_motion(a_master, sg).ds
        i_slave = engine.masses.reciprocating_kg * ds**2 + art.rod_knuckle_kg * knuckle_velocity_sq(a_master, sg)
        out = out.at[..., s].set(i_slave)
    return out


@engine_jit  # one compiled call per shape, not dozens of eager operations
def inertia_coefficients(engine: Engine) -> tuple[Array, Array, Array]:
    """The coefficients of each cylinder in the form of Anisimov, Yelenich & Melnyk:
    I_cyl(α) ≈ A·cos²α + B·cosα + C.

    Chosen so that the form has the same mean and the same first and second cosine
    harmonics as the exact I_cyl(α), α being the cylinder's own crank angle: with
    aₙ = (1/π)∫₀^{2π} I_cyl(α) cos(nα) dα, A = 2a₂, B = a₁ and C = mean − a₂.

    **Returns:** ``(A, B, C)`` [kg·m²], each of shape ``(cylinders,)``.
    """
    require_engine(engine, "inertia_coefficients(engine)")
    theta = jnp.linspace(0.0, 2 * jnp.pi, _FOURIER_POINTS, endpoint=False)
    ci = cylinder_inertia(engine, theta)  # (points, cylinders)
    alpha = engine.mechanical_angles(theta)  # each cylinder's own angle
    mean = jnp.mean(ci, axis=0)
    a1 = 2 * jnp.mean(ci * jnp.cos(alpha), axis=0)
    a2 = 2 * jnp.mean(ci * jnp.cos(2 * alpha), axis=0)
    return 2 * a2, a1, mean - a2


def _check_model(model):
    if model not in _MODELS:
        raise ValueError(f"inertia model must be one of {_MODELS}, got {model!r}")


@engine_jit  # one compiled call per shape, not dozens of eager operations
def reduced_inertia(engine: Engine, theta: ArrayLike, model: str = "exact") -> Array:
    """Reduced moment of inertia of the whole engine I(θ) [kg·m²].

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``theta``: engine crank angle [rad], any shape.
    - ``model``: ``"exact"`` (default), ``"coefficients"`` (the A·cos²α + B·cosα + C
      form of Anisimov et al.) or ``"mean"``.

    **Returns:** I(θ), shape of ``theta`` [kg·m²].
    """
    require_engine(engine, "reduced_inertia(engine)")
    _check_model(model)
    theta = jnp.asarray(theta, dtype=jnp.float64)
    J = engine.crankshaft.inertia_kgm2
    if model == "exact":
        return J + jnp.sum(cylinder_inertia(engine, theta), axis=-1)
    if model == "mean":
        return jnp.broadcast_to(mean_reduced_inertia(engine), theta.shape)
    A, B, C = inertia_coefficients(engine)
    c = jnp.cos(engine.mechanical_angles(theta))
    return J + jnp.sum(A * c**2 + B * c + C, axis=-1)


@engine_jit  # one compiled call per shape, not dozens of eager operations
def reduced_inertia_derivative(engine: Engine, theta: ArrayLike, model: str = "exact") -> Array:
    """dI/dθ [kg·m²/rad] by automatic differentiation of :func:`reduced_inertia`.

    **Arguments:** as :func:`reduced_inertia`.
    """
    theta = jnp.asarray(theta, dtype=jnp.float64)
    return jax.jvp(lambda t: reduced_inertia(engine, t, model), (theta,), (jnp.ones_like(theta),))[1]


@engine_jit  # one compiled call per shape, not dozens of eager operations
def mean_reduced_inertia(engine: Engine) -> Array:
    """Mean of I(θ) over a revolution [kg·m²] (exact, by spectral quadrature).

    For a central two-mass engine this is J + n·(m_rot·R² + m_rec·R²·(½ + λ²/8 + O(λ⁴))).
    """
    require_engine(engine, "mean_reduced_inertia(engine)")
    theta = jnp.linspace(0.0, 2 * jnp.pi, _FOURIER_POINTS, endpoint=False)
    return jnp.mean(reduced_inertia(engine, theta))
