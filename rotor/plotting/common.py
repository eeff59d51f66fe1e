"""Helpers every plot shares: new axes, the crank-angle axis, saving a figure whole."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

__all__ = ["new_axes", "angle_axis", "plain", "save_figure"]


def plain(text: object) -> str:
    """``text`` as matplotlib shows it, letter for letter: every ``$`` escaped, so that what a
    user wrote (the name of an engine, a mass or a file) is never read as mathematics (an
    engine named ``Test $x_$ engine`` would stop the drawing). Every text of the user's
    passes here on its way to a figure."""
    return str(text).replace("$", r"\$")


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


def save_figure(ax: Any, path: str | os.PathLike) -> None:
    """Save the figure holding ``ax`` (an Axes, an array of them, or what a ``plot()``
    returned) to ``path`` (a file's path; its extension, ``.png`` by default, picks the
    format), whole or not at all, and close it. Every file error is one line naming
    ``path`` (never the temporary file); an extension matplotlib cannot write is a
    ``ValueError`` naming ``path``."""
    import matplotlib.pyplot as plt

    from ..fileio import atomic_path

    name = os.fspath(path)
    fmt = os.path.splitext(name)[1].lstrip(".").lower() or "png"
    fig = np.ravel(ax)[0].figure
    try:
        if fmt not in fig.canvas.get_supported_filetypes():
            raise ValueError(
                f"{name}: cannot save a plot as .{fmt}: give one of "
                + ", ".join(f".{k}" for k in sorted(fig.canvas.get_supported_filetypes()))
            )
        with atomic_path(name) as tmp:
            fig.savefig(tmp, dpi=120, format=fmt)
    finally:
        plt.close(fig)
