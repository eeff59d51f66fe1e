"""Plots of the engine: the textbook table, torque and inertia over the cycle."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from .common import angle_axis, new_axes

__all__ = ["plot_table", "plot_torque", "plot_inertia"]


def plot_table(table, which="forces", ax=None):
    """Plot a :class:`rotor.CrankTable`: ``"kinematics"`` (S, V, J on three axes),
    ``"forces"`` (Pg, Pj, PΣ, N, K, Z, T in kN) or ``"torque"`` (M in N·m).

    **Returns:** the Axes (an array of three for kinematics).
    """
    c = table.columns
    a = c["angle_deg"]
    cycle = a[-1]
    if which == "kinematics":
        axes = new_axes(ax, 3, figsize=(8, 7))
        for axis, (col, label) in zip(axes, (("s_m", "S [m]"), ("v_m_s", "V [m/s]"), ("j_m_s2", "J [m/s²]"))):
            axis.plot(a, c[col], lw=1.5)
            axis.set_ylabel(label)
            angle_axis(axis, min(cycle, 360))
        axes[0].set_title(f"{table.engine_name}: piston kinematics at {table.rpm:g} rpm ({table.kinematics})")
        axes[-1].set_xlabel("crank angle [deg]")
        return axes
    axis = new_axes(ax)
    if which == "forces":
        for col, label in (
            ("pg_N", "$P_g$"),
            ("pj_N", "$P_j$"),
            ("psum_N", "$P_Σ$"),
            ("n_N", "N"),
            ("k_N", "K"),
            ("z_N", "Z"),
            ("t_N", "T"),
        ):
            axis.plot(a, c[col] / 1e3, lw=1.3, label=label)
        axis.set_ylabel("force [kN]")
        axis.legend(ncol=4, fontsize=8)
        axis.set_title(f"{table.engine_name}: forces of cylinder {table.cylinder} at {table.rpm:g} rpm")
    elif which == "torque":
        axis.plot(a, c["m_Nm"], lw=1.5)
        axis.set_ylabel("torque of one cylinder [N·m]")
        axis.set_title(f"{table.engine_name}: cylinder {table.cylinder} torque at {table.rpm:g} rpm")
    else:
        raise ValueError(f"which must be 'kinematics', 'forces' or 'torque', got {which!r}")
    axis.axhline(0, color="k", lw=0.6)
    axis.set_xlabel("crank angle [deg]")
    angle_axis(axis, cycle)
    return axis


def plot_torque(engine, rpm=None, ax=None, points_per_deg: int = 2):
    """Total torque of the engine over a cycle (textbook: gas + reciprocating inertia at
    constant speed), its gas and inertia parts, and its mean.

    **Arguments:** ``engine``; ``rpm``: speed [rev/min] (default ``[operating] rpm``); ``ax``.

    **Returns:** the Axes.
    """
    from ..engine.forces import gas_torque, total_torque

    rpm = float(engine.operating.rpm) if rpm is None else float(rpm)
    cycle_deg = 360 * engine.strokes / 2
    deg = np.linspace(0, cycle_deg, int(cycle_deg * points_per_deg) + 1)
    theta = jnp.deg2rad(deg)
    gas = np.asarray(gas_torque(engine, theta))
    total = np.asarray(total_torque(engine, theta, rpm * np.pi / 30))
    inertia = total - gas
    axis = new_axes(ax)
    axis.plot(deg, gas, lw=1, alpha=0.7, label="gas")
    axis.plot(deg, inertia, lw=1, alpha=0.7, label="reciprocating inertia")
    axis.plot(deg, total, lw=1.8, color="k", label="total")
    axis.axhline(total[:-1].mean(), color="C3", ls="--", lw=1.2, label=f"mean {total[:-1].mean():.0f} N·m")
    axis.axhline(0, color="k", lw=0.5)
    axis.set_xlabel("crank angle of cylinder 1 [deg]")
    axis.set_ylabel("torque [N·m]")
    axis.set_title(f"{engine.name}: total torque at {rpm:g} rpm")
    axis.legend(fontsize=8, ncol=2)
    angle_axis(axis, cycle_deg)
    return axis


def plot_inertia(engine, ax=None):
    """Reduced inertia I(θ) over a revolution: exact, the seed 003 form, and the mean.

    **Returns:** the Axes.
    """
    from ..engine.inertia import reduced_inertia

    deg = np.linspace(0, 360, 721)
    theta = jnp.deg2rad(deg)
    axis = new_axes(ax)
    for model, style in (("exact", "-"), ("coefficients", "--"), ("mean", ":")):
        axis.plot(deg, np.asarray(reduced_inertia(engine, theta, model)), style, lw=1.5, label=model)
    axis.set_xlabel("crank angle [deg]")
    axis.set_ylabel("I(θ) [kg·m²]")
    axis.set_title(f"{engine.name}: reduced moment of inertia")
    axis.legend(fontsize=8)
    angle_axis(axis, 360)
    return axis
