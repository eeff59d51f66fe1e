"""The plots of the design subpackage: a flywheel design, the textbook sizing, a disc flywheel.

Each function draws what the result hands it (the design's δ sweep comes computed, from
:meth:`rotor.FlywheelDesign.delta_sweep`); nothing here evaluates the engine.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from jaxtyping import Float

from .common import place_legend, plain, settle_legends, speed_axis

__all__ = ["plot_flywheel_design", "plot_textbook_flywheel", "plot_disc_flywheel"]


def _one_axes(ax: Any) -> bool:
    return ax is not None and hasattr(ax, "plot")


def plot_flywheel_design(
    design: Any,
    sweep_rpm: Float[np.ndarray, " n"],
    delta_designed: Float[np.ndarray, " n"] | None,
    delta_textbook: Float[np.ndarray, " n"] | None,
    ax: Any = None,
) -> Any:
    """Plot a :class:`rotor.FlywheelDesign`: δ against mean speed [rpm] with the designed
    and the textbook ``[crankshaft]`` inertia (``delta_designed``, ``delta_textbook`` [-]
    at ``sweep_rpm`` [rev/min]; None: not drawn), the points with their targets (left);
    the inertia each point needs, by Newton through the steady state and by the textbook
    [kg·m²] (right). ``ax``: two Axes, one Axes (the left panel only) or None (a new figure).

    **Returns:** the two Axes (or the one given).
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    one = _one_axes(ax)
    left, bx = (ax, None) if one else ax
    rpms = np.array([p.rpm for p in design.points])
    order = np.argsort(rpms)
    for J, d, label, style in (
        (design.crankshaft_inertia_kgm2, delta_designed, "designed", "-"),
        (design.textbook_inertia_kgm2, delta_textbook, "textbook", "--"),
    ):
        if d is not None:
            left.plot(sweep_rpm, d, style, label=f"{label}, J = {J:.4g} kg·m²")
    targets = [p.delta_target for p in design.points]
    if len(set(targets)) == 1:
        left.axhline(targets[0], color="k", lw=0.8, ls=":", label=f"target δ = {targets[0]:g}")
    else:
        left.plot(rpms[order], np.asarray(targets)[order], "k:", lw=0.8, marker="_", ms=14, label="targets")
    left.plot(rpms, [p.delta for p in design.points], "o", color="C0", label="operating points (design)")
    left.plot([design.binding_rpm], [design.delta_achieved], "*", ms=14, color="C3", label="binding point")
    if len(set(rpms)) < len(rpms):
        left.text(
            0.02,
            0.02,
            "several points share a speed: the curve follows the nearest",
            transform=left.transAxes,
            fontsize=7,
        )
    left.set_xlabel("mean speed [rpm] (fuelling interpolated between the points)")
    speed_axis(left, "x")
    left.set_ylabel("δ = (ω_max − ω_min)/ω_mean")
    left.grid(True, alpha=0.3)
    place_legend(left, fontsize=8)
    if bx is not None:
        x = np.arange(len(rpms))
        bx.bar(x - 0.2, [p.inertia_kgm2 for p in design.points], 0.4, label="Newton through the steady state")
        bx.bar(
            x + 0.2,
            [p.textbook.crankshaft_inertia_kgm2 for p in design.points],
            0.4,
            label="textbook J₀ − rods and pistons",
        )
        bx.set_xticks(x, [f"{r:g} rpm" + (f" #{i + 1}" if list(rpms).count(r) > 1 else "") for i, r in enumerate(rpms)])
        bx.set_ylabel("[crankshaft] inertia for δ target [kg·m²]")
        bx.grid(True, axis="y", alpha=0.3)
        place_legend(bx, fontsize=8)
    left.set_title(plain(design.engine_name), fontsize=10)
    settle_legends(left.figure)
    return ax


def plot_textbook_flywheel(textbook: Any, ax: Any = None) -> Any:
    """Plot a :class:`rotor.TextbookFlywheel`: J₀, its split into the rods and pistons and
    the ``[crankshaft]`` equivalent, and the textbook's flywheel 0.85·J₀, as bars [kg·m²].

    **Returns:** the Axes.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(7, 3.2), layout="constrained")
    names = ["J₀ (all that turns)", "rods and pistons", "[crankshaft] equivalent", "flywheel 0.85·J₀"]
    values = [
        textbook.total_inertia_kgm2,
        textbook.total_inertia_kgm2 - textbook.crankshaft_inertia_kgm2,
        textbook.crankshaft_inertia_kgm2,
        textbook.flywheel_kgm2,
    ]
    y = np.arange(len(names))[::-1]
    ax.barh(y, values, color=["C0", "C7", "C1", "C2"])
    ax.set_yticks(y, names)
    ax.axvline(0, color="k", lw=0.7)
    ax.set_xlabel("inertia [kg·m²]")
    ax.set_title(
        f"textbook at {textbook.rpm:g} rpm, δ = {textbook.delta:g}: L_excess = {textbook.excess_work_J:.1f} J, "
        f"rim {textbook.mass_kg:.1f} kg at D = {textbook.mean_diameter_m:.3f} m",
        fontsize=9,
    )
    ax.grid(True, axis="x", alpha=0.3)
    return ax


def plot_disc_flywheel(disc: Any, ax: Any = None) -> Any:
    """Plot a :class:`rotor.DiscFlywheel`: its axial section through the axis [mm] (width
    across, diameter up), with its mass and rim speed in the title.

    **Returns:** the Axes.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5, 5), layout="constrained")
    from matplotlib.patches import Rectangle

    r_out, r_in, b = 500 * disc.outer_diameter_m, 500 * disc.bore_m, 1000 * disc.width_m
    for lo in (r_in, -r_out):
        ax.add_patch(Rectangle((-b / 2, lo), b, r_out - r_in, facecolor="0.7", edgecolor="k"))
    ax.axhline(0, color="k", lw=0.7, ls="-.")
    half = 1.15 * max(r_out, b / 2)
    ax.set_xlim(-half, half)
    ax.set_ylim(-half, half)
    ax.set_aspect("equal")
    ax.set_xlabel("width [mm]")
    ax.set_ylabel("radius [mm]")
    ax.set_title(
        f"disc {disc.inertia_kgm2:.4g} kg·m², {disc.mass_kg:.1f} kg\nrim {disc.rim_speed_m_s:.1f} m/s at "
        f"{disc.peak_rpm:.0f} rpm ({disc.limited_by} limit)",
        fontsize=9,
    )
    return ax
