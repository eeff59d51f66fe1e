"""The plots of torsional vibration: mode shapes and the Campbell diagram.

Each function draws what a result of :mod:`rotor.torsion` hands it (the mode shapes and
frequencies of a :class:`rotor.TorsionalModes`, the lines and critical speeds of a
:class:`rotor.Campbell`); nothing here solves an eigenproblem.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .common import place_legend, plain, settle_legends, speed_axis

__all__ = ["plot_mode_shapes", "plot_campbell"]


def plot_mode_shapes(
    mass_names: Sequence[str],
    shapes: np.ndarray,
    frequencies_hz: np.ndarray,
    title: str,
    throw_masses: Sequence[int] = (),
    ax: Any = None,
) -> Any:
    """Draw torsional mode shapes: the relative amplitude [-] of each mass (from the front)
    for each mode.

    **Arguments:** ``mass_names`` (n,); ``shapes`` (modes, n) [-]; ``frequencies_hz``
    (modes,) [Hz]; ``title``; ``throw_masses``: 0-based indices of the crank throws'
    masses (shaded); ``ax``: one Axes per mode, one Axes for all, or None (a new figure,
    one Axes per mode).

    **Returns:** the Axes (an array of them for several modes, or the one given).
    """
    shapes = np.atleast_2d(np.asarray(shapes, dtype=np.float64))
    count = shapes.shape[0]
    x = np.arange(1, shapes.shape[1] + 1)
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(count, 1, figsize=(8, 1.9 * count + 1.2), sharex=True, squeeze=False, layout="constrained")
        ax = ax[:, 0]
    axes = np.ravel(np.asarray(ax, dtype=object))
    single = len(axes) == 1
    for j in range(count):
        axis = axes[0] if single else axes[j]
        label = f"mode {j + 1}: {frequencies_hz[j]:.1f} Hz"
        axis.plot(x, shapes[j], marker="o", lw=1.5, label=label)
        axis.axhline(0, color="k", lw=0.6)
        for m in throw_masses:
            axis.axvspan(m + 0.6, m + 1.4, color="0.9", zorder=0)
        axis.set_ylim(-1.15, 1.15)
        axis.set_ylabel("amplitude [-]")
        axis.grid(True, alpha=0.3)
        place_legend(axis, fontsize=8)
    last = axes[-1] if not single else axes[0]
    last.set_xticks(x)
    last.set_xticklabels([plain(n) for n in mass_names], rotation=30, ha="right", fontsize=8)
    axes[0].set_title(plain(title) + ("  (shaded: crank throws)" if len(throw_masses) else ""))
    settle_legends(axes[0].figure)
    return axes[0] if single else axes


def plot_campbell(
    rpm: np.ndarray,
    orders: np.ndarray,
    frequencies_hz: np.ndarray,
    title: str,
    critical_rpm: np.ndarray,
    critical_frequency_hz: np.ndarray,
    critical_major: np.ndarray,
    frequency_min_hz: np.ndarray | None = None,
    frequency_max_hz: np.ndarray | None = None,
    major_orders: Sequence[float] = (),
    ax: Any = None,
) -> Any:
    """Draw a Campbell diagram: the natural frequencies [Hz] as horizontal lines (with
    their range over the crank angle shaded where given), the engine orders as rays
    f = order·rpm/60 (the major orders bold), and the critical speeds marked.

    **Arguments:** ``rpm`` (speeds,) [rev/min]; ``orders`` (orders,) [-];
    ``frequencies_hz`` (modes,) [Hz]; ``title``; ``critical_rpm``,
    ``critical_frequency_hz``, ``critical_major`` (one per critical speed) [rev/min, Hz,
    bool]; ``frequency_min_hz``, ``frequency_max_hz`` (modes,) [Hz] or None;
    ``major_orders``: the orders drawn bold; ``ax``: an Axes or None (a new figure).

    **Returns:** the Axes.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(8, 5.5), layout="constrained")
    rpm = np.asarray(rpm, dtype=np.float64)
    lo, hi = float(rpm.min()), float(rpm.max())
    f = np.asarray(frequencies_hz, dtype=np.float64)
    order_max = float(np.max(orders)) if len(orders) else 1.0
    top = max(order_max * hi / 60.0, float(f.min()) if len(f) else 1.0) * 1.05
    shown = f[f <= top * 1.5]
    for j, fj in enumerate(shown):
        ax.axhline(fj, color="C0", lw=1.4)
        ax.annotate(
            f"mode {j + 1}: {fj:.0f} Hz", (lo, fj), xytext=(3, 3), textcoords="offset points", fontsize=8, color="C0"
        )
        if frequency_min_hz is not None and frequency_max_hz is not None:
            ax.axhspan(frequency_min_hz[j], frequency_max_hz[j], color="C0", alpha=0.15, lw=0)
    major = {float(q) for q in major_orders}
    for q in np.asarray(orders, dtype=np.float64):
        bold = float(q) in major
        ax.plot([lo, hi], [q * lo / 60.0, q * hi / 60.0], color="k" if bold else "0.6", lw=1.3 if bold else 0.7)
        y = q * hi / 60.0
        if y <= top:
            ax.annotate(f"{q:g}", (hi, y), xytext=(2, 0), textcoords="offset points", fontsize=7, va="center")
    cr = np.asarray(critical_rpm, dtype=np.float64)
    cf = np.asarray(critical_frequency_hz, dtype=np.float64)
    cm = np.asarray(critical_major, dtype=bool)
    if cr.size:
        ax.plot(cr[~cm], cf[~cm], "o", mfc="none", mec="C3", ms=6, label="critical speed")
        ax.plot(cr[cm], cf[cm], "o", color="C3", ms=7, label="critical speed, major order")
    ax.set_xlim(lo, hi)
    ax.set_ylim(0, top)
    ax.set_xlabel("engine speed [rpm]")
    speed_axis(ax, "x")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title(plain(title))
    ax.grid(True, alpha=0.3)
    place_legend(ax, fontsize=8)
    return ax
