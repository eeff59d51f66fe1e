"""The diagrams of the bearing loads (Shishkov, "Dinamika dvigatelei", SUSU 2014, §3.2.4–3.2.9):
polar load diagrams, the developed load, the wear diagram, the running torques.

Each function draws the arrays a :class:`rotor.BearingLoads` hands it; nothing here
evaluates the engine. Polar diagrams draw t to the right and z downward with equal
scales (the textbook's axes), so the frame's radial axis points up; the wear diagram uses
the same orientation (ray 0 up, rays in the direction of rotation, clockwise on the page).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from jaxtyping import ArrayLike

from .common import angle_axis, new_axes, place_legend, plain, segments_touching, settle_legends

__all__ = [
    "LABEL_OFFSETS",
    "angle_labels",
    "plot_polar_load",
    "plot_developed_load",
    "plot_wear",
    "plot_running_torques",
    "plot_bearing_loads",
]


def _square_axes(ax: Any, size: float = 5.5) -> Any:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, ax = plt.subplots(figsize=(size, size), layout="constrained")
    return ax


def plot_polar_load(
    angle_deg: ArrayLike,
    t_N: ArrayLike,
    z_N: ArrayLike,
    *,
    title: str,
    t_label: str = "T [kN]",
    z_label: str = "Z [kN]",
    label_every_deg: float = 60.0,
    ax: Any = None,
) -> Any:
    """Polar load diagram: the load's components ``t_N``, ``z_N`` [N] at crank angles
    ``angle_deg`` [deg] (one cycle, endpoint excluded) in kN, t to the right and z
    downward, equal scales, the pole marked, the crank angle written along the curve every
    ``label_every_deg`` [deg] (no two labels overlapping: :func:`angle_labels`) and the
    largest load marked. ``ax``: an Axes or None.

    **Returns:** the Axes.
    """
    ax = _square_axes(ax)
    a = np.asarray(angle_deg, dtype=float)
    t = np.asarray(t_N, dtype=float) / 1e3
    z = np.asarray(z_N, dtype=float) / 1e3
    ax.plot(np.append(t, t[:1]), np.append(z, z[:1]), lw=1.3, color="C0")
    ax.axhline(0, color="k", lw=0.6)
    ax.axvline(0, color="k", lw=0.6)
    ax.plot([0], [0], "ko", ms=4)
    q = np.hypot(t, z)
    i = int(np.argmax(q))
    ax.plot([0, t[i]], [0, z[i]], color="C3", lw=1.0)
    ax.plot([t[i]], [z[i]], "o", color="C3", ms=4, label=f"max {q[i]:.2f} kN at {a[i]:g}°")
    marks: list[tuple[float, float, list[str]]] = []
    if len(a) > 1:
        step = a[1] - a[0]
        cycle = a[-1] + step
        # angles whose points lie within 3 % of the diagram's size of each other share one label
        # ("180, 540"): written apart they overprint each other
        near = 0.03 * max(float(np.ptp(t)), float(np.ptp(z)), 1e-12)
        for target in np.arange(0.0, cycle, label_every_deg):
            k = int(np.argmin(np.abs(np.mod(a - target + cycle / 2, cycle) - cycle / 2)))
            ax.plot([t[k]], [z[k]], ".", color="C0", ms=5)
            for mt, mz, names in marks:
                if np.hypot(t[k] - mt, z[k] - mz) < near:
                    names.append(f"{target:g}")
                    break
            else:
                marks.append((float(t[k]), float(z[k]), [f"{target:g}"]))
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    ax.set_xlabel(t_label)
    ax.set_ylabel(z_label + " (downward)")
    ax.set_title(plain(title), fontsize=10)
    ax.grid(True, alpha=0.3)
    legend = place_legend(ax, fontsize=8)
    angle_labels(ax, marks, [] if legend is None else [legend])
    return ax


LABEL_OFFSETS = ((3, 3), (3, -11), (-3, 3), (-3, -11), (8, -4), (-8, -4), (3, 12), (-3, 12), (3, -20), (-3, -20))
"""Where an angle label of a polar diagram is tried, in points from its point ((x, y), y
up; a negative x puts the label's right end there), in this order."""


def angle_labels(ax: Any, marks: list[tuple[float, float, list[str]]], avoid: list[Any]) -> list[Any]:
    """Write each mark's angles (``(t, z, names)``: data coordinates and the angles there)
    beside its point, at the first of :data:`LABEL_OFFSETS` whose box overlaps no label
    written before it and none of the artists ``avoid`` (a legend), preferring a place the
    diagram's curve (the first line of ``ax``) does not cross; a label with no free place
    joins the text of the nearest one. The labels stay out of the figure's layout, so that
    writing them moves nothing. **Returns:** the labels (Annotations)."""
    fig = ax.figure
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    curve = ax.get_lines()[0]
    curve_px = curve.get_transform().transform(np.asarray(curve.get_xydata(), dtype=float))
    taken = [artist.get_window_extent(renderer).padded(2) for artist in avoid]
    placed: list[tuple[Any, list[str]]] = []
    for mt, mz, names in marks:
        free = []  # (crosses the curve, label, box) of every place no other label takes
        for dx, dy in LABEL_OFFSETS:
            label = ax.annotate(
                ", ".join(names),
                (mt, mz),
                textcoords="offset points",
                xytext=(dx, dy),
                ha="left" if dx >= 0 else "right",
                fontsize=7,
            )
            label.set_in_layout(False)
            box = label.get_window_extent(renderer).padded(3)  # a gap between two labels: read apart
            if any(box.overlaps(other) for other in taken):
                label.remove()
                continue
            free.append((segments_touching(box, curve_px) > 0, label, box))
            if not free[-1][0]:
                break
        if not free:  # every place taken: the nearest label names these angles too
            nearest = min(placed, key=lambda p: float(np.hypot(p[0].xy[0] - mt, p[0].xy[1] - mz)))
            nearest[1].extend(names)
            nearest[0].set_text(", ".join(nearest[1]))
            continue
        _, label, box = min(free, key=lambda f: f[0])  # the first that the curve leaves free, else the first
        for _, other, _ in free:
            if other is not label:
                other.remove()
        taken.append(box)
        placed.append((label, list(names)))
    return [p[0] for p in placed]


def plot_developed_load(angle_deg: ArrayLike, q_N: ArrayLike, *, title: str, cycle_deg: float, ax: Any = None) -> Any:
    """The developed load diagram: ``q_N`` [N] against crank angle ``angle_deg`` [deg] in
    kN with its mean, maximum and minimum over the cycle of ``cycle_deg`` [deg].

    **Returns:** the Axes.
    """
    ax = new_axes(ax)
    a = np.asarray(angle_deg, dtype=float)
    q = np.asarray(q_N, dtype=float) / 1e3
    ax.plot(a, q, lw=1.5, color="C0", label="Q")
    ax.axhline(float(np.mean(q)), color="C3", ls="--", lw=1.2, label=f"mean {np.mean(q):.2f} kN")
    i_hi, i_lo = int(np.argmax(q)), int(np.argmin(q))
    ax.plot([a[i_hi]], [q[i_hi]], "^", color="C3", label=f"max {q[i_hi]:.2f} kN at {a[i_hi]:g}°")
    ax.plot([a[i_lo]], [q[i_lo]], "v", color="C2", label=f"min {q[i_lo]:.2f} kN at {a[i_lo]:g}°")
    ax.set_xlabel("crank angle [deg]")
    ax.set_ylabel("load [kN]")
    ax.set_ylim(bottom=0)
    ax.set_title(plain(title), fontsize=10)
    angle_axis(ax, cycle_deg)
    place_legend(ax, fontsize=8)
    return ax


def plot_wear(ray_angles_deg: ArrayLike, wear_N: ArrayLike, *, title: str, ax: Any = None) -> Any:
    """The wear diagram: each ray's wear index ``wear_N`` [N] laid inward from a circle at
    its angle ``ray_angles_deg`` [deg] (ray 0 up, the others clockwise, as the polar
    diagrams are drawn), the tips joined, the least loaded ray (the oil hole) marked.

    **Returns:** the Axes.
    """
    ax = _square_axes(ax, 4.5)
    g = np.deg2rad(np.asarray(ray_angles_deg, dtype=float))
    w = np.asarray(wear_N, dtype=float)
    top = float(np.max(w))
    depth = 0.7 * w / top if top > 0 else np.zeros_like(w)
    s = np.linspace(0, 2 * np.pi, 361)
    ax.plot(np.sin(s), np.cos(s), color="k", lw=1.0)
    for gi in g:
        ax.plot([0, np.sin(gi)], [0, np.cos(gi)], color="0.7", lw=0.6)
    r = 1 - depth
    xi, yi = np.append(r * np.sin(g), r[0] * np.sin(g[0])), np.append(r * np.cos(g), r[0] * np.cos(g[0]))
    ax.fill(np.concatenate([np.sin(s), xi[::-1]]), np.concatenate([np.cos(s), yi[::-1]]), color="C1", alpha=0.35, lw=0)
    ax.plot(xi, yi, color="C1", lw=1.5)
    for k, gi in enumerate(g):
        ax.annotate(str(k), (1.12 * np.sin(gi), 1.12 * np.cos(gi)), ha="center", va="center", fontsize=7)
    best = int(np.argmin(w))
    gb = g[best]
    sx, cy = np.sin(gb), np.cos(gb)
    ax.annotate(
        f"oil hole ({np.rad2deg(gb):g}°)",
        xy=(sx, cy),
        xytext=(1.3 * sx + 0.25 * np.sign(sx) * (abs(sx) > 0.3), 1.3 * cy + 0.2 * np.sign(cy)),
        ha="left" if sx > 0.3 else "right" if sx < -0.3 else "center",
        va="center",
        fontsize=8,
        color="C3",
        arrowprops={"arrowstyle": "->", "color": "C3"},
    )
    ax.set_xlim(-2.2, 2.2)
    ax.set_ylim(-1.8, 1.8)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(f"{plain(title)}\nlargest wear index {top / 1e3:.2f} kN", fontsize=10)
    return ax


def plot_running_torques(
    angle_deg: ArrayLike, torque_Nm: ArrayLike, *, title: str, cycle_deg: float, ax: Any = None
) -> Any:
    """The running torque passed on by each main journal [N·m], ``torque_Nm`` of shape
    (angles, journals), against crank angle ``angle_deg`` [deg]; journal 1, which passes
    none, is left out.

    **Returns:** the Axes.
    """
    ax = new_axes(ax)
    a = np.asarray(angle_deg, dtype=float)
    m = np.asarray(torque_Nm, dtype=float)
    for j in range(1, m.shape[1]):
        ax.plot(a, m[:, j], lw=1.2, label=f"journal {j + 1} (range {np.ptp(m[:, j]):.0f})")
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("crank angle [deg]")
    ax.set_ylabel("running torque [N·m]")
    ax.set_title(plain(title), fontsize=10)
    angle_axis(ax, cycle_deg)
    place_legend(ax, fontsize=7, ncol=2)
    return ax


def plot_bearing_loads(result: Any, ax: Any = None) -> Any:
    """The main diagrams of a :class:`rotor.BearingLoads` on a 2 × 3 grid (``ax``: six
    Axes or None): crank pin 1, the big end of its first rod, the developed load of crank
    pin 1, its wear, the most loaded main journal and the running torques.

    **Returns:** the array of Axes.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(2, 3, figsize=(15, 9.5), layout="constrained")
    axes = np.ravel(np.asarray(ax, dtype=object))
    if len(axes) < 6:
        raise ValueError(f"BearingLoads.plot(ax=...): needs six Axes, got {len(axes)}")
    result.plot_crank_pin(ax=axes[0], throw=1)
    result.plot_big_end(ax=axes[1], cylinder=result.big_end_cylinders[0])
    result.plot_developed(ax=axes[2], throw=1)
    result.plot_wear(ax=axes[3], throw=1)
    result.plot_main_journal(ax=axes[4])
    result.plot_running_torques(ax=axes[5])
    settle_legends(axes[0].figure)
    return ax
