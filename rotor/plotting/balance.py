"""The plots of a balance (:class:`rotor.Balance`): free forces and moments by order, and
the force and moment ellipses of the low orders.

Each function draws what the result hands it (the values by order, the traced
ellipses); nothing here evaluates the engine.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .common import place_legend, plain, settle_legends

__all__ = ["plot_balance_orders", "plot_balance_ellipses"]

_UNITS = {"force": "N", "moment": "N·m"}


def _two_axes(ax: Any) -> Any:
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    axes = np.ravel(np.asarray(ax, dtype=object))
    if len(axes) != 2:
        raise ValueError(f"a balance plot draws on two Axes, got {len(axes)}")
    return axes


def plot_balance_orders(
    orders: np.ndarray,
    with_cw: Mapping[str, np.ndarray],
    without_cw: Mapping[str, np.ndarray] | None,
    title: str,
    ax: Any = None,
) -> Any:
    """Bars of the free force [N] (left) and the free moment [N·m] (right) by order:
    ``with_cw`` and ``without_cw`` map ``"force"`` and ``"moment"`` to their values by
    ``orders`` (``without_cw`` None: an engine without counterweights, one bar per order);
    ``title``: the engine and speed; ``ax``: two Axes or None (a new figure).

    **Returns:** the two Axes.
    """
    axes = _two_axes(ax)
    x = np.asarray(orders)
    for axis, quantity in zip(axes, ("force", "moment")):
        if without_cw is None:
            axis.bar(x, with_cw[quantity], width=0.6, color="C0", label="free")
        else:
            axis.bar(x - 0.2, without_cw[quantity], width=0.4, color="C1", label="without counterweights")
            axis.bar(x + 0.2, with_cw[quantity], width=0.4, color="C0", label="with counterweights")
        axis.set_xticks(x)
        axis.set_ylim(bottom=0)
        if not np.any(with_cw[quantity]) and (without_cw is None or not np.any(without_cw[quantity])):
            axis.text(0.5, 0.5, f"no free {quantity} at these orders", transform=axis.transAxes, ha="center")
        axis.set_xlabel("order (× crank speed)")
        axis.set_ylabel(f"free {quantity} [{_UNITS[quantity]}]")
        axis.set_title(f"{plain(title)}\nfree {quantity}s by order", fontsize=10)
        axis.grid(True, axis="y", alpha=0.3)
        place_legend(axis, fontsize=8)
    settle_legends(axes[0].figure)
    return axes


def plot_balance_ellipses(
    curves: Mapping[str, Mapping[str, tuple[np.ndarray, np.ndarray]]], title: str, ax: Any = None
) -> Any:
    """The ellipses traced by the free force [N] (left) and moment [N·m] (right) of the
    low orders over a revolution: ``curves`` maps ``"force"`` and ``"moment"`` to
    {label: (horizontal, vertical)} (none: the axes say that nothing is free); equal
    scales, vertical up; ``title``: the engine and
    speed; ``ax``: two Axes or None (a new figure).

    **Returns:** the two Axes.
    """
    axes = _two_axes(ax)
    for axis, quantity in zip(axes, ("force", "moment")):
        for label, (h, v) in curves.get(quantity, {}).items():
            (line,) = axis.plot(h, v, lw=1.5, label=label)
            axis.plot(h[:1], v[:1], "o", color=line.get_color(), ms=4)  # at crank angle 0
        axis.axhline(0, color="k", lw=0.6)
        axis.axvline(0, color="k", lw=0.6)
        axis.set_aspect("equal", adjustable="datalim")
        unit = _UNITS[quantity]
        axis.set_xlabel(f"horizontal [{unit}]")
        axis.set_ylabel(f"vertical [{unit}]")
        axis.set_title(f"{plain(title)}\nfree {quantity} of the low orders (dot: crank angle 0)", fontsize=10)
        axis.grid(True, alpha=0.3)
        if curves.get(quantity):
            place_legend(axis, fontsize=8)
        else:
            axis.text(0.5, 0.6, f"no free {quantity} at these orders", transform=axis.transAxes, ha="center")
    settle_legends(axes[0].figure)
    return axes
