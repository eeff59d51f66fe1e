"""Friction of the engine as a friction mean effective pressure (FMEP).

The usual correlation (Chen and Flynn, SAE 650733, without its peak-pressure term):

    FMEP = fmep_pa + fmep_per_speed_pa_s_per_m · c_m + fmep_per_speed2_pa_s2_per_m2 · c_m²

with c_m = S·ω/π the mean piston speed [m/s]. The friction torque is the FMEP's work
over a cycle spread evenly over the cycle angle:

    M_f(ω) = FMEP(c_m) · V_total / Θ,   Θ = 2π·strokes/2.

It acts against the rotation; the dynamics use it for ω ≥ 0 (a run ends when the
crankshaft stops). There is no friction unless the engine file has a ``[friction]``
table or the call passes one.
"""

from __future__ import annotations

from typing import Any, ClassVar, Protocol

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from ..checks import check_finite, check_positive
from .plausible import check_fields_plausible, number

__all__ = ["Friction"]


class EngineLike(Protocol):
    """What friction needs of a :class:`rotor.Engine` (the model imports this module, not
    the other way round)."""

    geometry: Any
    cylinders: int

    @property
    def cycle_rad(self) -> float: ...


class Friction(eqx.Module):
    """``[friction]``: FMEP = a + b·c_m + c·c_m² [Pa], c_m the mean piston speed [m/s].

    **Fields:**
    - ``fmep_pa``: the constant part a [Pa] (typically 0.3–1.0 bar).
    - ``fmep_per_speed_pa_s_per_m``: b [Pa·s/m] (default 0).
    - ``fmep_per_speed2_pa_s2_per_m2``: c [Pa·s²/m²] (default 0).
    """

    fmep_pa: jnp.ndarray = eqx.field(converter=number("friction", "fmep_pa"))
    fmep_per_speed_pa_s_per_m: jnp.ndarray = eqx.field(
        converter=number("friction", "fmep_per_speed_pa_s_per_m"), default=0.0
    )
    fmep_per_speed2_pa_s2_per_m2: jnp.ndarray = eqx.field(
        converter=number("friction", "fmep_per_speed2_pa_s2_per_m2"), default=0.0
    )
    table: ClassVar[str] = "friction"

    def __check_init__(self):
        for key in ("fmep_pa", "fmep_per_speed_pa_s_per_m", "fmep_per_speed2_pa_s2_per_m2"):
            check_finite(self.table, key, getattr(self, key))
            check_positive(self.table, key, getattr(self, key), allow_zero=True)
        check_fields_plausible(self)

    def fmep(self, piston_speed_m_s: ArrayLike) -> Array:
        """FMEP [Pa] at mean piston speed c_m [m/s]."""
        c = piston_speed_m_s
        return self.fmep_pa + self.fmep_per_speed_pa_s_per_m * c + self.fmep_per_speed2_pa_s2_per_m2 * c**2

    def torque_coefficients(self, engine: EngineLike) -> tuple[Array, Array, Array]:
        """(a, b, c) with M_f = a + b·ω + c·ω² [N·m, N·m·s, N·m·s²] for ``engine``."""
        g = engine.geometry
        scale = g.displacement_m3 * engine.cylinders / engine.cycle_rad
        k = g.stroke_m / jnp.pi  # c_m = k·ω
        return (
            self.fmep_pa * scale,
            self.fmep_per_speed_pa_s_per_m * k * scale,
            self.fmep_per_speed2_pa_s2_per_m2 * k**2 * scale,
        )

    def torque(self, engine: EngineLike, omega: ArrayLike) -> Array:
        """Friction torque [N·m] of ``engine`` at crank speed ``omega`` [rad/s] (ω ≥ 0)."""
        a, b, c = self.torque_coefficients(engine)
        return a + b * omega + c * omega**2
