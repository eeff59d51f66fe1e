"""Kinematics of the crank mechanism: V. N. Lukanin (ed.), "Internal combustion engines,
vol. 2: Dynamics and design" (2009) and A. I. Yamanin & A. V. Zharov, "Dynamics of piston
engines", for the exact and offset (desaxial) forms; the Russian Wikipedia article
"Кривошипно-шатунный механизм" (crank mechanism) for the piston motion equations;
Shishkov, "Dinamika dvigatelei" (SUSU, 2014) §3.2.1 for the λ-series.

Conventions: ``theta`` is the crank angle [rad] of the throw measured from the cylinder
axis in the direction of rotation (0 = the throw points at the cylinder head). The
piston pin may be offset by ``k`` [m] from the line through the crank centre (desaxial
mechanism, offset ratio z = k/R); then the rod angle obeys sin β = λ (sin θ − z).

Everything is returned as derivatives with respect to the crank angle, so that the
same functions serve a constant and a varying crank speed: the piston velocity is
``ds/dθ · ω`` [m/s] and its acceleration ``d²s/dθ² · ω² + ds/dθ · ε`` [m/s²].

``model="exact"`` is the reference. ``model="series"`` is the textbook λ-series
(Lukanin 2009; Yamanin & Zharov; Shishkov (2014) §3.2.1), accurate to O(λ³) for a central mechanism and to
O(λ³ + λ²z²) for an offset one.
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import numpy as np
from jaxtyping import Array, ArrayLike

from ..checks import TRACED, called_from_outside, guard, guard_number, is_tracer
from ..errors import EngineError
from ..jaxconfig import jax, jnp
from .plausible import checked_angle, require_real

__all__ = [
    "PistonMotion",
    "RodMotion",
    "piston_motion",
    "rod_motion",
    "mean_piston_speed",
]

_MODELS = ("exact", "series")


class PistonMotion(NamedTuple):
    """Piston displacement from TDC and its crank-angle derivatives.

    **Fields:**
    - ``s``: displacement from top dead centre, towards the crank [m].
    - ``ds``: ds/dθ [m/rad] (velocity = ds·ω).
    - ``d2s``: d²s/dθ² [m/rad²] (acceleration at constant speed = d2s·ω²).
    """

    s: jnp.ndarray
    ds: jnp.ndarray
    d2s: jnp.ndarray


class RodMotion(NamedTuple):
    """Connecting-rod swing angle and its crank-angle derivatives.

    **Fields:**
    - ``beta``: rod angle from the cylinder axis [rad].
    - ``dbeta``: dβ/dθ [-] (rod angular velocity = dbeta·ω).
    - ``d2beta``: d²β/dθ² [-] (rod angular acceleration at constant speed = d2beta·ω²).
    """

    beta: jnp.ndarray
    dbeta: jnp.ndarray
    d2beta: jnp.ndarray


def _check_model(model: str) -> None:
    if model not in _MODELS:
        raise ValueError(f"kinematics model must be one of {_MODELS}, got {model!r}")


def checked_mechanism(call: str, crank_radius_m: Any, rod_length_m: Any, pin_offset_m: Any) -> tuple[Any, Any, Any]:
    """R, L and k [m] of a public kinematics function ``call``: real and finite, R > 0 and
    L > R + |k| (else the crank cannot turn), each error naming ``call(argument)``; traced
    values are checked when the program runs. Returns the values to use."""
    names = ("crank_radius_m", "rod_length_m", "pin_offset_m")
    values = [crank_radius_m, rod_length_m, pin_offset_m]
    for name, v in zip(names, values):
        require_real(call, name, v, "m")
    if not any(is_tracer(v) for v in values):
        R, L, k = (np.asarray(v, dtype=np.float64) for v in values)
        for name, v in zip(names, (R, L, k)):
            if not np.all(np.isfinite(v)):
                raise EngineError(f"{call}({name}): must be finite [m], got a NaN or an infinity")
        if not np.all(R > 0):
            raise EngineError(f"{call}(crank_radius_m): must be positive [m]")
        if not np.all(L > R + np.abs(k)):
            raise EngineError(
                f"{call}(rod_length_m): the rod must be longer than crank_radius_m plus |pin_offset_m| [m], or the "
                "crank cannot turn"
            )
        return crank_radius_m, rod_length_m, pin_offset_m
    R = guard_number(crank_radius_m, f"{call}(crank_radius_m)", 0.0, above=True, unit="m")
    k = guard_number(pin_offset_m, f"{call}(pin_offset_m)", unit="m")
    L = guard_number(rod_length_m, f"{call}(rod_length_m)", unit="m")
    short = ~jnp.all(jnp.asarray(L) > jnp.asarray(R) + jnp.abs(jnp.asarray(k)))
    L = guard(
        L,
        short,
        f"{call}(rod_length_m): the rod must be longer than crank_radius_m plus |pin_offset_m| [m], or the crank "
        f"cannot turn; {TRACED}",
    )
    return R, L, k


def rod_motion(
    theta: ArrayLike, crank_radius_m: ArrayLike, rod_length_m: ArrayLike, pin_offset_m: ArrayLike = 0.0
) -> RodMotion:
    """Exact rod angle β(θ) and its derivatives (Lukanin 2009; Yamanin & Zharov).

    **Arguments:**
    - ``theta``: crank angle from the cylinder axis [rad].
    - ``crank_radius_m``: R [m]. ``rod_length_m``: L, centre to centre [m].
    - ``pin_offset_m``: piston-pin offset k [m] (0 for a central mechanism).

    **Returns:** a :class:`RodMotion`.

    **Raises:** a :class:`TypeError` for arguments that are not real numbers, a
    :class:`rotor.EngineError` for a NaN or an infinity, R ≤ 0 or a rod no longer than
    R + |k|, naming the argument; traced values (``jax.jit``/``vmap``/``grad``) are checked
    when the program runs.
    """
    if called_from_outside():  # rotor's own callers pass a checked engine's geometry
        theta = checked_angle("rod_motion", "theta", theta)
        crank_radius_m, rod_length_m, pin_offset_m = checked_mechanism(
            "rod_motion", crank_radius_m, rod_length_m, pin_offset_m
        )
    return _rod_motion(theta, crank_radius_m, rod_length_m, pin_offset_m)


@jax.jit  # one compiled program per shape, not one per operation when called outside a jit
def _rod_motion(
    theta: ArrayLike, crank_radius_m: ArrayLike, rod_length_m: ArrayLike, pin_offset_m: ArrayLike
) -> RodMotion:
    theta = jnp.asarray(theta, dtype=jnp.float64)
    R, L, k = crank_radius_m, rod_length_m, pin_offset_m
    sin_beta = (R * jnp.sin(theta) - k) / L
    beta = jnp.arcsin(sin_beta)
    cos_beta = jnp.sqrt(1.0 - sin_beta**2)
    dbeta = R * jnp.cos(theta) / (L * cos_beta)
    d2beta = jnp.tan(beta) * dbeta**2 - R * jnp.sin(theta) / (L * cos_beta)
    return RodMotion(beta, jnp.asarray(dbeta), jnp.asarray(d2beta))


def piston_motion(
    theta: ArrayLike,
    crank_radius_m: ArrayLike,
    rod_length_m: ArrayLike,
    pin_offset_m: ArrayLike = 0.0,
    model: str = "exact",
) -> PistonMotion:
    """Piston displacement from TDC, ds/dθ and d²s/dθ² (Lukanin; Yamanin & Zharov;
    Wikipedia; Shishkov §3.2.1).

    Exact: s = R[√((1+1/λ)² − z²) − cos θ − cos β / λ], ds/dθ = R sin(θ+β)/cos β,
    d²s/dθ² = R[cos(θ+β)/cos β + λ cos²θ / cos³β].

    Series: s = R[(1 + λ/4) − cos θ − (λ/4) cos 2θ − λ z sin θ],
    ds/dθ = R(sin θ + (λ/2) sin 2θ − λ z cos θ), d²s/dθ² = R(cos θ + λ cos 2θ + λ z sin θ).

    **Arguments:**
    - ``theta``: crank angle from the cylinder axis [rad].
    - ``crank_radius_m``: R [m]. ``rod_length_m``: L [m]. ``pin_offset_m``: k [m].
    - ``model``: ``"exact"`` (default) or ``"series"``.

    **Returns:** a :class:`PistonMotion` [m, m/rad, m/rad²].

    **Raises:** as :func:`rod_motion`.
    """
    _check_model(model)
    if called_from_outside():  # rotor's own callers pass a checked engine's geometry
        theta = checked_angle("piston_motion", "theta", theta)
        crank_radius_m, rod_length_m, pin_offset_m = checked_mechanism(
            "piston_motion", crank_radius_m, rod_length_m, pin_offset_m
        )
    return _piston_motion(theta, crank_radius_m, rod_length_m, pin_offset_m, model)


@functools.partial(jax.jit, static_argnames="model")
def _piston_motion(
    theta: ArrayLike, crank_radius_m: ArrayLike, rod_length_m: ArrayLike, pin_offset_m: ArrayLike, model: str
) -> PistonMotion:
    theta = jnp.asarray(theta, dtype=jnp.float64)
    R, L, k = crank_radius_m, rod_length_m, pin_offset_m
    lam = R / L
    z = k / R
    if model == "series":
        s = R * ((1 + lam / 4) - jnp.cos(theta) - lam / 4 * jnp.cos(2 * theta) - lam * z * jnp.sin(theta))
        ds = R * (jnp.sin(theta) + lam / 2 * jnp.sin(2 * theta) - lam * z * jnp.cos(theta))
        d2s = R * (jnp.cos(theta) + lam * jnp.cos(2 * theta) + lam * z * jnp.sin(theta))
        return PistonMotion(jnp.asarray(s), jnp.asarray(ds), jnp.asarray(d2s))
    beta, dbeta, _ = _rod_motion(theta, R, L, k)
    cos_beta = jnp.cos(beta)
    s = jnp.sqrt((R + L) ** 2 - k**2) - R * jnp.cos(theta) - L * cos_beta
    ds = R * jnp.sin(theta + beta) / cos_beta
    d2s = R * jnp.cos(theta + beta) / cos_beta + L * dbeta**2 / cos_beta
    return PistonMotion(jnp.asarray(s), jnp.asarray(ds), jnp.asarray(d2s))


def mean_piston_speed(stroke_m: ArrayLike, omega: ArrayLike) -> Array:
    """Mean piston speed v_m = S·n/30 = S·ω/π [m/s].

    **Arguments:** ``stroke_m``: S [m], positive; ``omega``: mean crank speed [rad/s].

    **Raises:** a :class:`TypeError` for arguments that are not real numbers, a
    :class:`rotor.EngineError` for a NaN or an infinity or a stroke not above 0, naming the
    argument; traced values are checked when the program runs.
    """
    if called_from_outside():
        omega = checked_angle("mean_piston_speed", "omega", omega, "rad/s")
        stroke_m = checked_angle("mean_piston_speed", "stroke_m", stroke_m, "m")
        if is_tracer(stroke_m):
            stroke_m = guard_number(stroke_m, "mean_piston_speed(stroke_m)", 0.0, above=True, unit="m")
        elif not np.all(np.asarray(stroke_m, dtype=np.float64) > 0):
            raise EngineError("mean_piston_speed(stroke_m): must be positive [m]")
    return jnp.asarray(stroke_m) * jnp.asarray(omega) / jnp.pi
