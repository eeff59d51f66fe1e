"""Articulated (master and slave) rods: kinematics of a slave piston (V. N. Lukanin (ed.),
"Internal combustion engines, vol. 2: Dynamics and design", 2009; A. I. Yamanin &
A. V. Zharov, "Dynamics of piston engines"; V. A. Lashko, "Matrix methods in calculations of
torsional vibrations of power plants with ICE", for the reduced inertia).

The slave rod hangs on a knuckle pin fixed to the master rod at distance r₁ from the
big-end centre, at an angle γ_k from the master rod's axis. Positions are written in
the plane of the crank (x along the master cylinder axis, y in the direction of
rotation) and differentiated by JAX, so velocities and accelerations are exact.
With r₁ = 0 the slave is an ordinary crank mechanism at its bank angle.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

from ..jaxconfig import jax, jnp
from .kinematics import PistonMotion

__all__ = ["SlaveGeometry", "slave_piston_motion", "knuckle_velocity_sq"]


class SlaveGeometry(NamedTuple):
    """Dimensions of a slave mechanism [m, rad].

    ``crank_radius_m``, ``rod_length_m`` and ``pin_offset_m`` are the master's;
    ``knuckle_radius_m`` r₁, ``knuckle_angle_rad`` γ_k, ``slave_rod_length_m`` l₁, and
    ``bank_rad`` Γ, the slave cylinder axis from the master's (direction of rotation).
    """

    crank_radius_m: jnp.ndarray
    rod_length_m: jnp.ndarray
    pin_offset_m: jnp.ndarray
    knuckle_radius_m: jnp.ndarray
    knuckle_angle_rad: jnp.ndarray
    slave_rod_length_m: jnp.ndarray
    bank_rad: jnp.ndarray


def _knuckle(alpha, g: SlaveGeometry):
    """Knuckle pin position (x, y) [m] at the master's mechanical angle ``alpha`` [rad]."""
    R, L, k = g.crank_radius_m, g.rod_length_m, g.pin_offset_m
    cx, cy = R * jnp.cos(alpha), R * jnp.sin(alpha)
    sin_b = (R * jnp.sin(alpha) - k) / L
    cos_b = jnp.sqrt(1 - sin_b**2)
    ux, uy = cos_b, -sin_b  # unit vector big end -> piston pin
    ca, sa = jnp.cos(g.knuckle_angle_rad), jnp.sin(g.knuckle_angle_rad)
    r1 = g.knuckle_radius_m
    return cx + r1 * (ca * ux - sa * uy), cy + r1 * (sa * ux + ca * uy)


def _slave_pin_distance(alpha, g: SlaveGeometry):
    """Distance of the slave piston pin from the crank centre along its axis [m]."""
    kx, ky = _knuckle(alpha, g)
    cg, sg = jnp.cos(g.bank_rad), jnp.sin(g.bank_rad)
    a = kx * cg + ky * sg
    b = -kx * sg + ky * cg
    return a + jnp.sqrt(g.slave_rod_length_m**2 - b**2)


def _derivs(f, alpha):
    """f, df/dα, d²f/dα² for an elementwise function f, by forward-mode autodiff."""
    ones = jnp.ones_like(alpha)
    df = lambda a: jax.jvp(f, (a,), (ones,))[1]  # noqa: E731
    value, first = jax.jvp(f, (alpha,), (ones,))
    second = jax.jvp(df, (alpha,), (ones,))[1]
    return value, first, second


@jax.jit  # one compiled call per shape, not dozens of eager operations
def slave_piston_motion(alpha_master, g: SlaveGeometry) -> PistonMotion:
    """Slave piston displacement from its TDC and its derivatives, against the master's angle.

    **Arguments:**
    - ``alpha_master``: the master cylinder's mechanical crank angle [rad] (which equals the
      slave's own crank angle plus its bank angle from the master).
    - ``g``: a :class:`SlaveGeometry`.

    **Returns:** a :class:`rotor.engine.kinematics.PistonMotion` [m, m/rad, m/rad²]; the TDC is
    the slave piston's outermost position over a revolution (it differs slightly from
    the master's TDC plus the bank angle, and its stroke from 2R).
    """
    alpha = jnp.asarray(alpha_master, dtype=jnp.float64)
    f = lambda a: _slave_pin_distance(a, g)  # noqa: E731
    t, dt, d2t = _derivs(f, alpha)
    return PistonMotion(slave_tdc_distance(g) - t, -dt, -d2t)


@functools.partial(jax.jit, static_argnames="samples")
def slave_tdc_distance(g: SlaveGeometry, samples: int = 1024):
    """Largest distance of the slave piston pin from the crank centre [m] (its TDC).

    Found on a grid of ``samples`` master angles and refined by a parabola through the
    best three points (error ≈ 1e-12 m for ordinary dimensions).
    """
    grid = jnp.linspace(0.0, 2 * jnp.pi, samples, endpoint=False)
    t = _slave_pin_distance(grid, g)
    i = jnp.argmax(t)
    h = 2 * jnp.pi / samples
    t0, t1, t2 = t[(i - 1) % samples], t[i], t[(i + 1) % samples]
    denom = t0 - 2 * t1 + t2
    shift = jnp.where(denom < 0, 0.5 * (t0 - t2) / jnp.where(denom < 0, denom, -1.0), 0.0)
    return _slave_pin_distance(grid[i] + shift * h, g)


@jax.jit  # one compiled call per shape, not dozens of eager operations
def knuckle_velocity_sq(alpha_master, g: SlaveGeometry):
    """|d(knuckle pin)/dα|² [m²/rad²]: the knuckle pin's speed squared per unit crank speed."""
    alpha = jnp.asarray(alpha_master, dtype=jnp.float64)
    ones = jnp.ones_like(alpha)
    _, (vx, vy) = jax.jvp(lambda a: _knuckle(a, g), (alpha,), (ones,))
    return vx**2 + vy**2
