"""The plot of a flywheel design."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_flywheel_design"]


def plot_flywheel_design(design, engine, axes=None, rpm_range=None, n: int = 25):
    """Plot a :class:`rotor.design.flywheel.FlywheelDesign`: δ against mean speed [rpm] with the
    designed and the textbook ``[crankshaft]`` inertia, the fuelling interpolated between
    the operating points (balancing load), the points with their targets (left); the
    inertia each point needs, by Newton through the steady state and by the textbook
    [kg·m²] (right). ``rpm_range``: (low, high) of the sweep [rev/min] (default the
    points' range ±20 %); ``n``: sweep points.

    **Returns:** the two Axes.
    """
    from ..design.flywheel import OperatingPoint, _Evaluator

    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    ax, bx = axes
    rpms = np.array([p.rpm for p in design.points])
    lo, hi = rpm_range if rpm_range is not None else (0.8 * rpms.min(), 1.2 * rpms.max())
    sweep = np.linspace(lo, hi, n)
    s = design.settings
    ev = _Evaluator(engine, design.fidelity, design.friction, s.get("grid_deg", 0.25))
    order = np.argsort(rpms)
    # each cylinder's fuelling interpolated between the points, the nearest point's load
    scales = np.stack([np.broadcast_to(np.asarray(p.imep_scale, float), (engine.cylinders,)) for p in design.points])
    fuel = np.stack([np.interp(sweep, rpms[order], scales[order, c]) for c in range(engine.cylinders)], axis=1)
    loads = design.loads or (None,) * len(rpms)
    near = [loads[int(np.argmin(np.abs(rpms - r)))] for r in sweep]
    for J, label, style in (
        (design.crankshaft_inertia_kgm2, "designed", "-"),
        (design.textbook_inertia_kgm2, "textbook", "--"),
    ):
        if J <= 0:
            continue
        d = [
            ev.state(J, OperatingPoint(r, f if np.ptp(f) else float(f[0]), ld))[0]
            for r, f, ld in zip(sweep, fuel, near)
        ]
        ax.plot(sweep, d, style, label=f"{label}, J = {J:.4g} kg·m²")
    targets = [p.delta_target for p in design.points]
    if len(set(targets)) == 1:
        ax.axhline(targets[0], color="k", lw=0.8, ls=":", label=f"target δ = {targets[0]:g}")
    else:
        ax.plot(rpms[order], np.asarray(targets)[order], "k:", lw=0.8, marker="_", ms=14, label="targets")
    ax.plot(rpms, [p.delta for p in design.points], "o", color="C0", label="operating points (design)")
    ax.plot([design.binding_rpm], [design.delta_achieved], "*", ms=14, color="C3", label="binding point")
    if len(set(rpms)) < len(rpms):
        ax.text(
            0.02,
            0.02,
            "several points share a speed: the curve follows the nearest",
            transform=ax.transAxes,
            fontsize=7,
        )
    ax.set_xlabel("mean speed [rpm] (fuelling interpolated between the points)")
    ax.set_ylabel("δ = (ω_max − ω_min)/ω_mean")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
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
    bx.legend(fontsize=8)
    bx.grid(True, axis="y", alpha=0.3)
    ax.set_title(design.engine_name, fontsize=10)
    return axes
