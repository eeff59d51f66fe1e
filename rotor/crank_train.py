"""The engine prepared for its equation of motion: periodic tables over one cycle.

Every function of the crank angle that the equation of motion needs is sampled once,
with its exact derivative (automatic differentiation), on a uniform grid over the cycle
(0.25° by default), and evaluated between the nodes by cubic Hermite interpolation
(fourth-order accurate, C¹, periodic). The columns are

- ``I``: reduced inertia I(θ) [kg·m²] at the chosen fidelity;
- ``k``: coefficient of the explicit reciprocating inertia torque k(θ)·ω² [kg·m²]
  (nonzero only at the ``"constant"`` fidelity, where I is constant);
- ``M_motored``: the engine's gas torque with no cylinder firing [N·m];
- ``dM_c``: cylinder c's combustion torque, fired minus motored [N·m], one column each.

Fidelity (``fidelity=``):

- ``"variable"``: exact I(θ) (:func:`rotor.reduced_inertia`); the reciprocating inertia
  torque −½·I′(θ)·ω² comes out of I(θ) and k = 0. The default.
- ``"coefficients"``: I(θ) in the seed 003 form A·cos²θ + B·cosθ + C per cylinder, k = 0.
- ``"constant"``: I = the cycle mean of the exact I(θ) and k(θ) = −Σ m_rec·s″·s′ (the
  textbook inertia torque, seed 004); the reciprocating masses are never counted twice.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._checks import EngineError
from .forces import cylinder_gas_torques, reciprocating_inertia_torque
from .inertia import mean_reduced_inertia, reduced_inertia

__all__ = ["CrankTrain", "crank_train", "FIDELITIES"]

FIDELITIES = ("variable", "coefficients", "constant")
_I, _K, _MM, _DM = 0, 1, 2, 3


def check_fidelity(fidelity):
    if fidelity not in FIDELITIES:
        raise EngineError(f"fidelity = {fidelity!r}: must be one of {', '.join(map(repr, FIDELITIES))}")


def grid_points(strokes: int, grid_deg: float) -> int:
    cycle = 180.0 * strokes
    n = int(round(cycle / grid_deg))
    if not (np.isfinite(grid_deg) and grid_deg > 0 and np.isclose(n * grid_deg, cycle) and n >= 16):
        raise EngineError(f"grid_deg = {grid_deg!r}: must divide the {cycle:g}° cycle into 16 or more equal steps")
    return n


class CrankTrain(eqx.Module):
    """Periodic tables of the equation of motion on a uniform cycle grid (see module doc).

    **Fields:** ``values``, ``slopes``: (N, 3 + cylinders) node values and dθ-derivatives;
    ``cycle_rad``: cycle angle Θ [rad]; ``firing_rad``: each cylinder's firing TDC in
    [0, Θ) [rad]; ``imep_motored_pa``, ``imep_combustion_pa``: each cylinder's IMEP
    without firing and the part added by its combustion [Pa]; ``mean_inertia``: cycle
    mean of I [kg·m²]; ``fidelity`` (static).
    """

    values: jnp.ndarray
    slopes: jnp.ndarray
    firing_rad: jnp.ndarray
    imep_motored_pa: jnp.ndarray
    imep_combustion_pa: jnp.ndarray
    mean_inertia: jnp.ndarray
    cycle_rad: float = eqx.field(static=True)
    strokes: int = eqx.field(static=True)
    fidelity: str = eqx.field(static=True)

    @property
    def points(self) -> int:
        return self.values.shape[0]

    @property
    def cylinders(self) -> int:
        return self.values.shape[1] - _DM

    @property
    def step_rad(self):
        return self.cycle_rad / self.points

    def at(self, theta):
        """Hermite-interpolated (values, slopes) at engine angle(s) θ [rad]: shape θ.shape + (K,)."""
        theta = jnp.asarray(theta, dtype=jnp.float64)
        h = self.step_rad
        u = theta / h
        j = jnp.floor(u)
        tau = (u - j)[..., None]
        j0 = jnp.mod(j, self.points).astype(jnp.int32)
        j1 = jnp.mod(j0 + 1, self.points)
        f0, f1 = self.values[j0], self.values[j1]
        d0, d1 = self.slopes[j0] * h, self.slopes[j1] * h
        t2, t3 = tau * tau, tau * tau * tau
        val = (2 * t3 - 3 * t2 + 1) * f0 + (t3 - 2 * t2 + tau) * d0 + (3 * t2 - 2 * t3) * f1 + (t3 - t2) * d1
        der = ((6 * t2 - 6 * tau) * (f0 - f1) + (3 * t2 - 4 * tau + 1) * d0 + (3 * t2 - 2 * tau) * d1) / h
        return val, der

    def nodes(self):
        """Node angles over one cycle [rad], shape (N,)."""
        return jnp.arange(self.points) * self.step_rad

    def scale_index(self, theta, cycles: int):
        """Index k of each cylinder's firing whose half-cycle window holds θ, clipped to the run."""
        theta = jnp.asarray(theta, dtype=jnp.float64)
        k = jnp.floor((theta[..., None] - self.firing_rad) / self.cycle_rad + 0.5)
        return jnp.clip(k, 0, cycles - 1).astype(jnp.int32)


def _columns(engine, fidelity, theta):
    """The table columns at angles θ (shape (N,)) → (N, K)."""
    n = engine.cylinders
    if fidelity == "constant":
        inertia = jnp.broadcast_to(mean_reduced_inertia(engine), theta.shape)
        k = reciprocating_inertia_torque(engine, theta, 1.0)
    else:
        inertia = reduced_inertia(engine, theta, "exact" if fidelity == "variable" else "coefficients")
        k = jnp.zeros_like(theta)
    motored = engine.replace(pressure=engine.pressure.motored(engine.strokes))
    m_mot = cylinder_gas_torques(motored, theta)
    m_fired = cylinder_gas_torques(engine, theta)
    cols = [inertia[..., None], k[..., None], jnp.sum(m_mot, axis=-1, keepdims=True), m_fired - m_mot]
    out = jnp.concatenate(cols, axis=-1)
    assert out.shape[-1] == _DM + n
    return out


@eqx.filter_jit
def _build(engine, fidelity, points):
    cycle = engine.cycle_rad
    theta = jnp.arange(points) * (cycle / points)
    values, slopes = jax.jvp(lambda t: _columns(engine, fidelity, t), (theta,), (jnp.ones_like(theta),))
    # each cylinder's IMEP, motored and the combustion part, from the same tables
    motored = engine.replace(pressure=engine.pressure.motored(engine.strokes))
    m_mot = cylinder_gas_torques(motored, theta)
    vh = engine.geometry.displacement_m3
    w = cycle / points  # periodic trapezoid rule: spectrally accurate
    imep_m = jnp.sum(m_mot, axis=0) * w / vh
    imep_c = jnp.sum(values[:, _DM:], axis=0) * w / vh
    firing = jnp.mod(engine.firing_angles_rad, cycle)
    return values, slopes, imep_m, imep_c, jnp.mean(values[:, _I]), firing


def crank_train(engine, fidelity: str = "variable", grid_deg: float = 0.25) -> CrankTrain:
    """Prepare ``engine`` for the equation of motion (tables over one cycle).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``fidelity``: ``"variable"`` (default), ``"coefficients"`` or ``"constant"``.
    - ``grid_deg``: node spacing [deg]; must divide the cycle (default 0.25°).
    """
    check_fidelity(fidelity)
    points = grid_points(engine.strokes, grid_deg)
    values, slopes, imep_m, imep_c, mean_i, firing = _build(engine, fidelity, points)
    return CrankTrain(values, slopes, firing, imep_m, imep_c, mean_i, engine.cycle_rad, engine.strokes, fidelity)
