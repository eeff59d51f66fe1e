"""Helpers every plot shares: new axes, the crank-angle, cycle and speed axes, a legend in
the corner its lines leave free, saving a figure whole."""

from __future__ import annotations

import os
import weakref
from typing import Any

import numpy as np

__all__ = [
    "CORNERS",
    "angle_axis",
    "cycle_axis",
    "legend_overlap",
    "new_axes",
    "place_legend",
    "plain",
    "save_figure",
    "segments_touching",
    "settle_legends",
    "speed_axis",
]


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


def cycle_axis(ax: Any, axis: str = "x") -> None:
    """Cycles are whole numbers: the ticks of ``ax``'s ``axis`` ("x" or "y") on integers only."""
    from matplotlib.ticker import MaxNLocator

    (ax.xaxis if axis == "x" else ax.yaxis).set_major_locator(MaxNLocator(integer=True))


def speed_axis(ax: Any, axis: str = "y") -> None:
    """A speed axis shows its speeds as they are (3000.01, never "+3e3" above ticks of 0.01):
    no offset and no scientific notation on ``ax``'s ``axis`` ("x" or "y")."""
    ax.ticklabel_format(axis=axis, useOffset=False, style="plain")


CORNERS = ("upper right", "upper left", "lower left", "lower right")
"""The corners a legend is tried in, in this order (:func:`place_legend`)."""


def _points_px(ax: Any) -> list[tuple[Any, bool]]:
    """The display coordinates [px] of every line's vertices and every collection's points
    (scatter markers) of ``ax``: (an (n, 2) array, whether its points are joined by
    segments), one per line or collection."""
    out = []
    for line in ax.get_lines():
        if not line.get_visible():
            continue
        xy = np.asarray(line.get_xydata(), dtype=float)
        if xy.size:
            joined = line.get_linestyle() not in ("None", "none", "", " ")
            out.append((line.get_transform().transform(xy), joined))
    for coll in ax.collections:
        offsets = np.asarray(coll.get_offsets(), dtype=float)
        if coll.get_visible() and offsets.size and offsets.ndim == 2:
            out.append((coll.get_offset_transform().transform(offsets), False))
    return out


def _points_inside(box: Any, xy: Any) -> int:
    """How many of the points ``xy`` [px] lie in the rectangle ``box`` (a Bbox in px)."""
    inside = (xy[:, 0] >= box.x0) & (xy[:, 0] <= box.x1) & (xy[:, 1] >= box.y0) & (xy[:, 1] <= box.y1)
    return int(np.count_nonzero(inside))


def segments_touching(box: Any, xy: Any) -> int:
    """How many segments of the polyline ``xy`` [px] (one line's vertices, in order) touch
    the rectangle ``box`` (a matplotlib Bbox in px), a lone point counted if inside."""
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if xy.shape[0] == 0:
        return 0
    x0, y0, x1, y1 = box.x0, box.y0, box.x1, box.y1
    if xy.shape[0] == 1:
        return int(x0 <= xy[0, 0] <= x1 and y0 <= xy[0, 1] <= y1)
    p, q = xy[:-1], xy[1:]
    # outside the box's extent on one side: the segment misses it
    miss = (
        ((p[:, 0] < x0) & (q[:, 0] < x0))
        | ((p[:, 0] > x1) & (q[:, 0] > x1))
        | ((p[:, 1] < y0) & (q[:, 1] < y0))
        | ((p[:, 1] > y1) & (q[:, 1] > y1))
    )
    # else it touches the box unless all four corners lie on one side of its line
    d = q - p
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    side = d[:, None, 0] * (corners[None, :, 1] - p[:, None, 1]) - d[:, None, 1] * (corners[None, :, 0] - p[:, None, 0])
    one_side = np.all(side > 0, axis=1) | np.all(side < 0, axis=1)
    return int(np.count_nonzero(~miss & ~one_side))


def legend_overlap(ax: Any, legend: Any, renderer: Any = None) -> int:
    """How many segments and points of ``ax``'s lines and markers, and how many of its bars,
    the box of ``legend`` touches, as drawn now (the figure's layout as last drawn)."""
    renderer = renderer or ax.figure.canvas.get_renderer()
    box = legend.get_window_extent(renderer).padded(3)
    bars = [patch for container in ax.containers if hasattr(container, "patches") for patch in container.patches]
    lines = sum(segments_touching(box, xy) if joined else _points_inside(box, xy) for xy, joined in _points_px(ax))
    return lines + sum(bool(box.overlaps(bar.get_window_extent(renderer))) for bar in bars)


_LEGENDS: weakref.WeakKeyDictionary[Any, dict[str, Any]] = weakref.WeakKeyDictionary()
"""The keyword arguments of every legend :func:`place_legend` placed, by its Axes: what
:func:`settle_legends` places again once the figure's layout is final."""


def place_legend(ax: Any, **kwargs: Any) -> Any:
    """``ax.legend(**kwargs)`` in the first of :data:`CORNERS` whose box touches none of the
    lines, markers and bars drawn (each segment tested against the box, not only the
    vertices, with a margin of 3 px); where every corner touches some, the y axis is raised
    by the legend's height (at most twice) to free the upper corners, and failing that the
    corner touching fewest is taken. Call it once the data and the limits are set; a
    figure of several panels calls :func:`settle_legends` once all are drawn (their layout
    moves the boxes), and :func:`save_figure` does. ``kwargs`` go to ``Axes.legend`` (a
    ``loc`` among them is ignored). **Returns:** the Legend, or None where nothing is labelled."""
    kwargs.pop("loc", None)
    if not ax.get_legend_handles_labels()[0]:
        return None
    _LEGENDS[ax] = kwargs
    fig = ax.figure
    fig.draw_without_rendering()  # the layout settled: the boxes and the data where they will be drawn
    renderer = fig.canvas.get_renderer()
    best: tuple[int, str] | None = None
    for attempt in range(3):
        for corner in CORNERS:
            legend = ax.legend(loc=corner, **kwargs)
            n = legend_overlap(ax, legend, renderer)
            if n == 0:
                return legend
            if best is None or n < best[0]:
                best = (n, corner)
        if attempt == 2:
            break
        # headroom: the y range grown by the legend's share of the axes' height (and a margin)
        share = legend.get_window_extent(renderer).height / max(ax.get_window_extent(renderer).height, 1.0)
        factor = min(share + 0.04, 0.6) / max(1.0 - share - 0.04, 0.4)
        bottom, top = ax.get_ylim()  # top < bottom on an inverted axis: the sign keeps "up" up
        if ax.get_yscale() == "log":
            ax.set_ylim(bottom, top * (top / bottom) ** factor)
        else:
            ax.set_ylim(bottom, top + (top - bottom) * factor)
        fig.draw_without_rendering()
    assert best is not None
    return ax.legend(loc=best[1], **kwargs)


def settle_legends(fig: Any) -> None:
    """Place again every legend of ``fig`` that :func:`place_legend` placed and that now
    touches its lines: the layout of the whole figure (its other panels, their labels)
    moves the boxes after each was placed."""
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        legend = ax.get_legend()
        if ax in _LEGENDS and legend is not None and legend_overlap(ax, legend, renderer):
            place_legend(ax, **_LEGENDS[ax])


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
        settle_legends(fig)
        if fmt not in fig.canvas.get_supported_filetypes():
            raise ValueError(
                f"{name}: cannot save a plot as .{fmt}: give one of "
                + ", ".join(f".{k}" for k in sorted(fig.canvas.get_supported_filetypes()))
            )
        with atomic_path(name) as tmp:
            fig.savefig(tmp, dpi=120, format=fmt)
    finally:
        plt.close(fig)
