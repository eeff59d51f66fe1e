"""Plots of the engine: the textbook table, torque and inertia over the cycle.

Each function draws what a result of :mod:`rotor.engine` hands it (a
:class:`rotor.CrankTable`, the arrays of an :class:`rotor.EngineCurves`); nothing here
evaluates the engine.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from jaxtyping import ArrayLike

from .common import angle_axis, new_axes, place_legend, plain

__all__ = ["plot_table", "plot_torque", "plot_inertia"]


def plot_table(table: Any, which: str = "forces", ax: Any = None) -> Any:
    """Plot a :class:`rotor.CrankTable`: ``which`` is ``"kinematics"`` (S, V, J on three
    axes), ``"forces"`` (Pg, Pj, PΣ, N, K, Z, T in kN) or ``"torque"`` (M in N·m); ``ax``:
    an Axes (three for kinematics) or None (a new figure).

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
        axes[0].set_title(f"{plain(table.engine_name)}: piston kinematics at {table.rpm:g} rpm ({table.kinematics})")
        axes[-1].set_xlabel("crank angle [deg]")
        return axes
    axis = new_axes(ax)
    if which == "forces":
        # K = PΣ/cos β differs from PΣ by a few per cent: PΣ is drawn broad and K dashed on it
        for col, label, style in (
            ("pg_N", "$P_g$", {}),
            ("pj_N", "$P_j$", {}),
            ("psum_N", "$P_Σ$", {"lw": 3.2, "alpha": 0.55}),
            ("n_N", "N", {}),
            ("k_N", "K (dashed: ≈ $P_Σ$)", {"ls": "--"}),
            ("z_N", "Z", {}),
            ("t_N", "T", {}),
        ):
            axis.plot(a, c[col] / 1e3, **{"lw": 1.3, **style}, label=label)
        axis.set_ylabel("force [kN]")
        axis.set_title(f"{plain(table.engine_name)}: forces of cylinder {table.cylinder} at {table.rpm:g} rpm")
    elif which == "torque":
        axis.plot(a, c["m_Nm"], lw=1.5)
        axis.set_ylabel("torque of one cylinder [N·m]")
        axis.set_title(f"{plain(table.engine_name)}: cylinder {table.cylinder} torque at {table.rpm:g} rpm")
    else:
        raise ValueError(f"which must be 'kinematics', 'forces' or 'torque', got {which!r}")
    axis.axhline(0, color="k", lw=0.6)
    axis.set_xlabel("crank angle [deg]")
    angle_axis(axis, cycle)
    place_legend(axis, ncol=4, fontsize=8)
    return axis


def plot_torque(
    angle_deg: ArrayLike,
    total_Nm: ArrayLike,
    mean_Nm: float,
    title: str,
    cycle_deg: float,
    *,
    gas_Nm: ArrayLike | None = None,
    inertia_Nm: ArrayLike | None = None,
    xlabel: str = "crank angle [deg]",
    ax: Any = None,
) -> Any:
    """Total torque of the engine over a cycle, its mean and, if given, its gas and
    reciprocating-inertia parts.

    **Arguments:** ``angle_deg``: crank angle [deg]; ``total_Nm``: total torque [N·m];
    ``mean_Nm``: its cycle mean [N·m]; ``title``; ``cycle_deg``: the cycle [deg];
    ``gas_Nm``, ``inertia_Nm``: the parts [N·m]; ``xlabel``; ``ax``.

    **Returns:** the Axes.
    """
    axis = new_axes(ax)
    if gas_Nm is not None:
        axis.plot(angle_deg, gas_Nm, lw=1, alpha=0.7, label="gas")
    if inertia_Nm is not None:
        axis.plot(angle_deg, inertia_Nm, lw=1, alpha=0.7, label="reciprocating inertia")
    axis.plot(angle_deg, total_Nm, lw=1.8, color="k", label="total")
    axis.axhline(mean_Nm, color="C3", ls="--", lw=1.2, label=f"mean {mean_Nm:.0f} N·m")
    axis.axhline(0, color="k", lw=0.5)
    axis.set_xlabel(xlabel)
    axis.set_ylabel("torque [N·m]")
    axis.set_title(plain(title))
    angle_axis(axis, cycle_deg)
    place_legend(axis, fontsize=8, ncol=2)
    return axis


_STYLES = {"exact": "-", "coefficients": "--", "mean": ":"}


def plot_inertia(angle_deg: ArrayLike, curves: Mapping[str, ArrayLike], title: str, ax: Any = None) -> Any:
    """Reduced inertia I(θ) over a revolution, one line per model.

    **Arguments:** ``angle_deg``: crank angle over 0…360° [deg]; ``curves``: {model name:
    I(θ) [kg·m²]} (``"exact"``, ``"coefficients"``, ``"mean"`` get their own line styles);
    ``title``; ``ax``.

    **Returns:** the Axes.
    """
    axis = new_axes(ax)
    for model, y in curves.items():
        axis.plot(angle_deg, y, _STYLES.get(model, "-"), lw=1.5, label=model)
    axis.set_xlabel("crank angle [deg]")
    axis.set_ylabel("I(θ) [kg·m²]")
    axis.set_title(plain(title))
    angle_axis(axis, 360)
    place_legend(axis, fontsize=8)
    return axis
