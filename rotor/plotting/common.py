"""Helpers every plot shares: new axes, the crank-angle axis, saving a figure whole."""

from __future__ import annotations

import numpy as np

__all__ = ["new_axes", "angle_axis", "save_figure"]


def new_axes(ax, nrows=1, figsize=(8, 4.5)):
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(nrows, 1, figsize=figsize, sharex=True, squeeze=True, layout="constrained")
    return axes


def angle_axis(ax, cycle_deg):
    ax.set_xlim(0, cycle_deg)
    ax.set_xticks(np.arange(0, cycle_deg + 1, 90))
    ax.grid(True, alpha=0.3)


def save_figure(ax, path) -> None:
    """Save the figure holding ``ax`` to ``path``, whole or not at all, and close it."""
    import matplotlib.pyplot as plt

    from ..fileio import atomic_path

    fig = np.ravel(ax)[0].figure
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=120, format=str(path).rsplit(".", 1)[-1] if "." in str(path) else "png")
    finally:
        plt.close(fig)
