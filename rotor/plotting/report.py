"""Plots of the report of the whole calculation (:mod:`rotor.design.report`): curves over the
crank angle, the tangential forces of the cylinders and their sum, and the turning-moment
diagram with its excess work (Shishkov, "Dinamika dvigatelei", SUSU 2014, §3.2.3 and
§3.2.12). Each draws on a new figure and returns its Axes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .common import angle_axis, new_axes, place_legend, plain

__all__ = ["plot_curves", "plot_tangential_forces", "plot_turning_moment"]


def plot_curves(
    angle: np.ndarray, curves: Sequence[tuple[np.ndarray, str]], ylabel: str, title: str, cycle: float
) -> Any:
    """Several curves over the crank angle on one new Axes: ``angle`` [deg], ``curves``
    (values, label) pairs in the unit of ``ylabel``, ``cycle`` the axis length [deg]."""
    ax = new_axes(None)
    for y, label in curves:
        ax.plot(angle, y, lw=1.4, label=label)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel("crank angle [deg]")
    ax.set_ylabel(ylabel)
    ax.set_title(plain(title), fontsize=10)
    angle_axis(ax, cycle)
    place_legend(ax, fontsize=8, ncol=3)
    return ax


def plot_tangential_forces(
    angle: np.ndarray, t_cyl: dict[int, np.ndarray], t_sum: np.ndarray, t_mean: float, title: str, cycle: float
) -> Any:
    """Each cylinder's tangential force T and their sum T_Σ [N] with its mean, drawn in kN over
    ``angle`` [deg]."""
    ax = new_axes(None)
    for c, y in t_cyl.items():
        ax.plot(angle, y / 1e3, lw=0.9, alpha=0.6, label=f"T, cylinder {c}")
    ax.plot(angle, t_sum / 1e3, lw=1.8, color="k", label="T_Σ")
    ax.axhline(t_mean / 1e3, color="C3", ls="--", lw=1.2, label=f"T_Σ mean {t_mean / 1e3:.2f} kN")
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("crank angle [deg]")
    ax.set_ylabel("tangential force [kN]")
    ax.set_title(plain(title), fontsize=10)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the plot: many cylinders
    angle_axis(ax, cycle)
    return ax


def plot_turning_moment(
    angle: np.ndarray, torque: np.ndarray, mean: float, work: np.ndarray, excess: float, title: str, cycle: float
) -> Any:
    """The total torque with its mean, the areas above and below it, and the work
    ∫(M − M_mean)dθ whose largest swing is the excess work."""
    top, bottom = new_axes(None, 2, figsize=(8, 6.5))
    top.plot(angle, torque, color="k", lw=1.5, label="total torque M_Σ")
    top.axhline(mean, color="C3", ls="--", lw=1.2, label=f"mean {mean:.0f} N·m")
    top.fill_between(angle, torque, mean, where=torque >= mean, color="C2", alpha=0.3, label="excess (above mean)")
    top.fill_between(angle, torque, mean, where=torque < mean, color="C0", alpha=0.3, label="deficit (below mean)")
    top.axhline(0, color="k", lw=0.5)
    top.set_ylabel("torque [N·m]")
    top.set_title(plain(title), fontsize=10)
    angle_axis(top, cycle)
    place_legend(top, fontsize=8, ncol=2)
    bottom.plot(angle, work, color="C4", lw=1.5, label="∫(M_Σ − M_mean)dθ")
    i_lo, i_hi = int(np.argmin(work)), int(np.argmax(work))
    bottom.plot([angle[i_lo], angle[i_hi]], [work[i_lo], work[i_hi]], "o", color="C3")
    bottom.axhline(work[i_lo], color="C3", lw=0.6, ls=":")
    bottom.axhline(work[i_hi], color="C3", lw=0.6, ls=":")
    bottom.annotate(
        f"L_excess = {excess:.1f} J",
        xy=(angle[i_hi], 0.5 * (work[i_lo] + work[i_hi])),
        xytext=(8, 0),
        textcoords="offset points",
        color="C3",
        fontsize=9,
    )
    bottom.set_xlabel("crank angle [deg]")
    bottom.set_ylabel("work [J]")
    angle_axis(bottom, cycle)
    place_legend(bottom, fontsize=8)
    return np.array([top, bottom])
