"""A one-screen summary of an engine at an operating speed."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from .forces import imep_pa, mean_gas_torque, total_torque
from .inertia import inertia_coefficients, mean_reduced_inertia, reduced_inertia
from .kinematics import mean_piston_speed

__all__ = ["engine_summary", "format_summary"]


def engine_summary(engine, rpm=None) -> dict:
    """Key figures of an engine at ``rpm`` [rev/min] (default ``[operating] rpm``), in SI units.

    **Returns:** a dict: displacement, crank radius, λ, mean piston speed, IMEP, mean
    gas torque, indicated power, the range of the textbook total torque and its excess
    work (the largest swing of ∫(M − M_mean)dθ, seed 004 §3.2.12), and the mean,
    minimum and maximum of the reduced inertia I(θ).
    """
    rpm = float(engine.operating.rpm) if rpm is None else float(rpm)
    omega = rpm * np.pi / 30
    g = engine.geometry
    theta = jnp.linspace(0.0, engine.cycle_rad, int(720 * engine.strokes / 2), endpoint=False)
    total = total_torque(engine, theta, omega)
    inertia = reduced_inertia(engine, theta)
    torque = float(mean_gas_torque(engine))
    A, B, C = inertia_coefficients(engine)
    work = np.cumsum(np.asarray(total) - float(jnp.mean(total))) * (engine.cycle_rad / theta.shape[0])
    return {
        "name": engine.name,
        "strokes": engine.strokes,
        "cylinders": engine.cylinders,
        "rpm": rpm,
        "displacement_m3": float(g.displacement_m3 * engine.cylinders),
        "crank_radius_m": float(g.crank_radius_m),
        "rod_ratio": float(g.rod_ratio),
        "mean_piston_speed_m_s": float(mean_piston_speed(g.stroke_m, omega)),
        "imep_pa": float(imep_pa(engine)),
        "mean_gas_torque_Nm": torque,
        "indicated_power_w": torque * omega,
        "total_torque_min_Nm": float(jnp.min(total)),
        "total_torque_max_Nm": float(jnp.max(total)),
        "excess_work_J": float(work.max() - work.min()),
        "inertia_mean_kgm2": float(mean_reduced_inertia(engine)),
        "inertia_min_kgm2": float(jnp.min(inertia)),
        "inertia_max_kgm2": float(jnp.max(inertia)),
        "inertia_coefficients_kgm2": {"A": float(A[0]), "B": float(B[0]), "C": float(C[0])},
    }


def format_summary(s: dict) -> str:
    """The summary as aligned text for a terminal."""
    rows = [
        ("engine", f"{s['name']} ({s['cylinders']} cylinders, {s['strokes']}-stroke)"),
        ("speed", f"{s['rpm']:g} rpm"),
        ("displacement", f"{s['displacement_m3'] * 1e3:.3f} L"),
        ("crank radius R, lambda", f"{s['crank_radius_m'] * 1e3:.2f} mm, {s['rod_ratio']:.4f}"),
        ("mean piston speed", f"{s['mean_piston_speed_m_s']:.2f} m/s"),
        ("IMEP", f"{s['imep_pa'] / 1e6:.4f} MPa"),
        ("mean gas torque", f"{s['mean_gas_torque_Nm']:.1f} N*m"),
        ("indicated power", f"{s['indicated_power_w'] / 1e3:.1f} kW"),
        ("total torque (gas + inertia)", f"{s['total_torque_min_Nm']:.0f} ... {s['total_torque_max_Nm']:.0f} N*m"),
        ("excess work (seed 004, 3.2.12)", f"{s['excess_work_J']:.1f} J"),
        (
            "reduced inertia I(theta)",
            f"mean {s['inertia_mean_kgm2']:.4f}, {s['inertia_min_kgm2']:.4f} ... {s['inertia_max_kgm2']:.4f} kg*m^2",
        ),
        (
            "seed 003 form, cylinder 1",
            "A = {A:.5f}, B = {B:.5f}, C = {C:.5f} kg*m^2".format(**s["inertia_coefficients_kgm2"]),
        ),
    ]
    w = max(len(k) for k, _ in rows)
    return "\n".join(f"{k.ljust(w)}  {v}" for k, v in rows) + "\n"
