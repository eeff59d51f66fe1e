"""An independent reference for the simulator: scipy's DOP853 on rotor's exact physics.

The right-hand side evaluates I(θ) (``rotor.reduced_inertia``) and the gas torque from the
pressure source and the exact piston kinematics at every call — not the simulator's
tables, not diffrax. The angle-domain energy form dE/dθ = M_gas(θ) − c·ω², dt/dθ = 1/ω
is integrated from θ = 0 with ω = rpm. Used by ``tests/dynamics/test_dynamics.py`` and by
``benchmarks/simulator_accuracy.py``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from scipy.integrate import solve_ivp

import rotor
from rotor.units import RPM_PER_RAD_S as RPM


def physics(engine):
    """A jitted θ ↦ (I(θ) [kg·m²], M_gas(θ) [N·m]) on the exact physics."""
    src, g = engine.pressure, engine.geometry
    if isinstance(src, rotor.WiebeCycle):  # its heat scale once, not at every call
        heat = src.heat_scale(g)

        def pressure(phi):
            p0, p1 = src.pressure_parts(phi, g)
            return p0 + heat * p1
    else:

        def pressure(phi):
            return src(phi, g, engine.strokes)

    @jax.jit
    def f(theta):
        p = pressure(engine.cycle_angles(theta))
        ds = rotor.engine_piston_motion(engine, theta).ds
        m_gas = jnp.sum((p - src.crankcase_pa) * g.piston_area_m2 * ds, axis=-1)
        return rotor.reduced_inertia(engine, theta), m_gas

    return f


def scipy_angle_reference(engine, rpm, cycles, load_c, theta_out, rtol=1e-12):
    """ω [rad/s] and t [s] at ``theta_out`` [rad] from DOP853 at ``rtol`` (load c·ω²)."""
    f = physics(engine)

    def rhs(theta, y):
        inertia, m_gas = (float(v) for v in f(theta))
        omega = np.sqrt(2 * y[0] / inertia)
        return [m_gas - load_c * omega**2, 1 / omega]

    i0 = float(f(0.0)[0])
    y0 = [0.5 * i0 * (rpm / RPM) ** 2, 0.0]
    sol = solve_ivp(
        rhs, (0.0, cycles * engine.cycle_rad), y0, method="DOP853", rtol=rtol, atol=rtol * 1e3, dense_output=True
    )
    E, t = sol.sol(theta_out)
    return np.sqrt(2 * E / np.asarray(f(jnp.asarray(theta_out))[0])), t
