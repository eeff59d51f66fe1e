"""Plots of kinematics, forces, torque and inertia. matplotlib is imported only here,
and only when a plot is asked for. Every function takes ``ax=`` and returns what it drew
on."""

from __future__ import annotations

import numpy as np
import jax.numpy as jnp

__all__ = ["plot_table", "plot_torque", "plot_inertia", "plot_speed", "save_figure", "plot_log_analysis",
           "plot_identification", "plot_flywheel_design"]


def _axes(ax, nrows=1, figsize=(8, 4.5)):
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(nrows, 1, figsize=figsize, sharex=True, squeeze=True, layout="constrained")
    return axes


def _angle_axis(ax, cycle_deg):
    ax.set_xlim(0, cycle_deg)
    ax.set_xticks(np.arange(0, cycle_deg + 1, 90))
    ax.grid(True, alpha=0.3)


def plot_table(table, which="forces", ax=None):
    """Plot a :class:`rotor.CrankTable`: ``"kinematics"`` (S, V, J on three axes),
    ``"forces"`` (Pg, Pj, PΣ, N, K, Z, T in kN) or ``"torque"`` (M in N·m).

    **Returns:** the Axes (an array of three for kinematics).
    """
    c = table.columns
    a = c["angle_deg"]
    cycle = a[-1]
    if which == "kinematics":
        axes = _axes(ax, 3, figsize=(8, 7))
        for axis, (col, label) in zip(axes, (("s_m", "S [m]"), ("v_m_s", "V [m/s]"), ("j_m_s2", "J [m/s²]"))):
            axis.plot(a, c[col], lw=1.5)
            axis.set_ylabel(label)
            _angle_axis(axis, min(cycle, 360))
        axes[0].set_title(f"{table.engine_name}: piston kinematics at {table.rpm:g} rpm ({table.kinematics})")
        axes[-1].set_xlabel("crank angle [deg]")
        return axes
    axis = _axes(ax)
    if which == "forces":
        for col, label in (("pg_N", "$P_g$"), ("pj_N", "$P_j$"), ("psum_N", "$P_Σ$"), ("n_N", "N"),
                           ("k_N", "K"), ("z_N", "Z"), ("t_N", "T")):
            axis.plot(a, c[col] / 1e3, lw=1.3, label=label)
        axis.set_ylabel("force [kN]")
        axis.legend(ncol=4, fontsize=8)
        axis.set_title(f"{table.engine_name}: forces of cylinder {table.cylinder} at {table.rpm:g} rpm")
    elif which == "torque":
        axis.plot(a, c["m_Nm"], lw=1.5)
        axis.set_ylabel("torque of one cylinder [N·m]")
        axis.set_title(f"{table.engine_name}: cylinder {table.cylinder} torque at {table.rpm:g} rpm")
    else:
        raise ValueError(f"which must be 'kinematics', 'forces' or 'torque', got {which!r}")
    axis.axhline(0, color="k", lw=0.6)
    axis.set_xlabel("crank angle [deg]")
    _angle_axis(axis, cycle)
    return axis


def plot_torque(engine, rpm=None, ax=None, points_per_deg: int = 2):
    """Total torque of the engine over a cycle (textbook: gas + reciprocating inertia at
    constant speed), its gas and inertia parts, and its mean.

    **Arguments:** ``engine``; ``rpm``: speed [rev/min] (default ``[operating] rpm``); ``ax``.

    **Returns:** the Axes.
    """
    from ..engine.forces import gas_torque, total_torque

    rpm = float(engine.operating.rpm) if rpm is None else float(rpm)
    cycle_deg = 360 * engine.strokes / 2
    deg = np.linspace(0, cycle_deg, int(cycle_deg * points_per_deg) + 1)
    theta = jnp.deg2rad(deg)
    gas = np.asarray(gas_torque(engine, theta))
    total = np.asarray(total_torque(engine, theta, rpm * np.pi / 30))
    inertia = total - gas
    axis = _axes(ax)
    axis.plot(deg, gas, lw=1, alpha=0.7, label="gas")
    axis.plot(deg, inertia, lw=1, alpha=0.7, label="reciprocating inertia")
    axis.plot(deg, total, lw=1.8, color="k", label="total")
    axis.axhline(total[:-1].mean(), color="C3", ls="--", lw=1.2, label=f"mean {total[:-1].mean():.0f} N·m")
    axis.axhline(0, color="k", lw=0.5)
    axis.set_xlabel("crank angle of cylinder 1 [deg]")
    axis.set_ylabel("torque [N·m]")
    axis.set_title(f"{engine.name}: total torque at {rpm:g} rpm")
    axis.legend(fontsize=8, ncol=2)
    _angle_axis(axis, cycle_deg)
    return axis


def plot_inertia(engine, ax=None):
    """Reduced inertia I(θ) over a revolution: exact, the seed 003 form, and the mean.

    **Returns:** the Axes.
    """
    from ..engine.inertia import reduced_inertia

    deg = np.linspace(0, 360, 721)
    theta = jnp.deg2rad(deg)
    axis = _axes(ax)
    for model, style in (("exact", "-"), ("coefficients", "--"), ("mean", ":")):
        axis.plot(deg, np.asarray(reduced_inertia(engine, theta, model)), style, lw=1.5, label=model)
    axis.set_xlabel("crank angle [deg]")
    axis.set_ylabel("I(θ) [kg·m²]")
    axis.set_title(f"{engine.name}: reduced moment of inertia")
    axis.legend(fontsize=8)
    _angle_axis(axis, 360)
    return axis


def plot_speed(result, ax=None, kind: str = "cycle"):
    """Plot a :class:`rotor.SpeedResult`.

    ``kind``: ``"cycle"`` (rpm over the last complete cycle against crank angle),
    ``"time"`` (rpm over the whole run against time), ``"torque"`` (engine and load torque
    over the last complete cycle) or ``"orders"`` (speed harmonic amplitudes by engine order).

    **Returns:** the Axes.
    """
    kinds = ("cycle", "time", "torque", "orders")
    if kind not in kinds:
        raise ValueError(f"kind = {kind!r}: one of {', '.join(kinds)}")
    ax = _axes(ax)
    rpm = np.asarray(result.omega) * 30 / np.pi
    t = np.asarray(result.t)
    cycle_deg = np.rad2deg(result.cycle_rad)
    title = f"{result.engine_name} — {result.kind}, {result.method}, {result.fidelity} inertia"
    if kind == "time":
        ax.plot(t, rpm, lw=1.0)
        if result.stalled:
            ax.axvline(result.stall_time_s, color="C3", ls="--", label="stall")
            ax.legend()
        ax.set_xlabel("time [s]")
        ax.set_ylabel("speed [rpm]")
        ax.grid(True, alpha=0.3)
        ax.set_title(title)
        return ax
    if kind == "orders":
        o = result.orders()
        ax.bar(o.order, np.asarray(o.speed_amplitude_rad_s) * 30 / np.pi, width=0.3)
        ax.set_xlabel("engine order [per revolution]")
        ax.set_ylabel("speed amplitude [rpm]")
        ax.set_xticks(o.order[1::2] if len(o.order) > 12 else o.order)
        ax.grid(True, alpha=0.3, axis="y")
        ax.set_title(f"{title}; δ = {float(result.delta):.4g}")
        return ax
    P, C = result.points_per_cycle, result.uniform_cycles
    if C < 1:
        raise ValueError("the run holds no complete cycle to plot against crank angle")
    sl = slice((C - 1) * P, C * P)
    angle = np.arange(P) * cycle_deg / P
    if kind == "cycle":
        ax.plot(angle, rpm[sl], lw=1.5)
        ax.axhline(float(result.cycle_mean_omega[-1]) * 30 / np.pi, color="0.5", lw=0.8, ls="--", label="time mean")
        ax.set_ylabel("speed [rpm]")
        ax.legend()
        ax.set_title(f"{title}; δ = {float(result.delta_per_cycle[-1]):.4g}")
    else:
        ax.plot(angle, np.asarray(result.torque)[sl], lw=1.2, label="engine (gas)")
        ax.plot(angle, np.asarray(result.load_torque)[sl], lw=1.2, label="load + friction")
        ax.set_ylabel("torque [N·m]")
        ax.legend()
        ax.set_title(title)
    ax.set_xlabel("crank angle in the cycle [deg]")
    _angle_axis(ax, cycle_deg)
    return ax


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


def plot_log_analysis(analysis, axes=None):
    """The combined plot of a :class:`rotor.LogAnalysis`: speed over the cycle (every
    cycle and their mean), each cycle's mean speed and δ, the order spectrum (mean and
    cycle-to-cycle spread), and the pressure signal over the cycle (or, without one,
    the tooth errors applied).

    **Returns:** the 2×2 array of Axes.
    """
    if axes is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 2, figsize=(12, 8), layout="constrained")
    axes = np.asarray(axes)
    a = analysis
    ax_w, ax_c, ax_o, ax_p = axes.ravel()[:4]
    cycle_deg = np.rad2deg(a.cycle_rad)
    ang = np.rad2deg(a.cycle_angle_rad)
    rpm = a.omega * 30 / np.pi
    for row in rpm:
        ax_w.plot(ang, row, lw=0.6, color="0.6", alpha=0.6)
    ax_w.plot(ang, rpm.mean(axis=0), lw=1.8, color="C0", label=f"mean of {a.cycles} cycles")
    ax_w.set_xlabel("cycle angle [deg] (360 = firing TDC)" if a.strokes == 4 else "crank angle from TDC [deg]")
    ax_w.set_ylabel("speed [rpm]")
    ax_w.legend(fontsize=8)
    _angle_axis(ax_w, cycle_deg)
    ax_w.set_title(f"{a.source}: speed over the cycle")
    k = np.arange(a.cycles)
    ax_c.plot(k, a.mean_rpm, "o-", color="C0", ms=4)
    ax_c.set_xlabel("cycle")
    ax_c.set_ylabel("mean speed [rpm]", color="C0")
    twin = ax_c.twinx()
    twin.plot(k, a.delta, "s--", color="C3", ms=4)
    twin.set_ylabel("δ [-]", color="C3")
    ax_c.grid(True, alpha=0.3)
    ax_c.set_title("cycle to cycle")
    m, s = a.amplitude_rad_s.mean(axis=0), (a.amplitude_rad_s.std(axis=0, ddof=1) if a.cycles > 1
                                            else np.zeros(a.order.size))
    ax_o.bar(a.order, m, width=0.3, yerr=s, capsize=2, color="C0")
    ax_o.set_xlabel("engine order [per revolution]")
    ax_o.set_ylabel("speed amplitude [rad/s]")
    ax_o.grid(True, alpha=0.3, axis="y")
    ax_o.set_title("order spectrum (mean ± cycle-to-cycle std)")
    if a.pressure is not None:
        ph, pv, cyc = a.pressure
        order = np.argsort(cyc * 10 + ph / a.cycle_rad, kind="stable")
        ax_p.plot(np.rad2deg(ph[order]), pv[order], ",", color="C2", alpha=0.5)
        ax_p.set_xlabel("cycle angle [deg]")
        ax_p.set_ylabel("pressure signal [V]")
        _angle_axis(ax_p, cycle_deg)
        ax_p.set_title(f"pressure; TDC {np.rad2deg(a.tdc_rad):.1f}° after the gap")
    elif a.tooth_errors is not None:
        te = a.tooth_errors
        ax_p.bar(np.arange(te.errors_rad.size), te.errors_deg, color="C1")
        ax_p.set_xlabel("tooth (0 = first after the gap)")
        ax_p.set_ylabel("tooth error [deg]")
        ax_p.grid(True, alpha=0.3, axis="y")
        ax_p.set_title(f"tooth errors applied ({te.method})")
    else:
        ax_p.set_axis_off()
    return axes


def plot_identification(ident, engine=None, axes=None):
    """The plot of a :class:`rotor.Identification`: the speed over the record (measured and
    the model's), the identified gas torque of each cylinder (needs ``engine``, the one
    identified: ``ident.info["engine"]`` after :func:`rotor.diagnose`; without it the
    panel shows the per-cycle load torque), and each cylinder's IMEP per cycle with the
    misfires marked.

    **Returns:** the array of three Axes.
    """
    if axes is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(3, 1, figsize=(11, 9), layout="constrained")
    axes = np.asarray(axes).ravel()
    ax_w, ax_m, ax_i = axes[:3]
    C, P = ident.omega.shape
    x = (np.arange(C * P) / P)  # record angle in cycles
    rpm = 30.0 / np.pi
    ax_w.plot(x, ident.omega.reshape(-1) * rpm, lw=0.8, color="C0", label="measured")
    ax_w.plot(x, ident.omega_model.reshape(-1) * rpm, lw=0.8, color="C1", ls="--", label="model (identified)")
    ax_w.set_ylabel("speed [rpm]")
    ax_w.set_xlabel("cycle (from the record's first cycle start)")
    ax_w.set_xlim(0, C)
    ax_w.grid(True, alpha=0.3)
    ax_w.legend(fontsize=8)
    ax_w.set_title(f"{ident.engine_name}: speed; rms residual {ident.rms_residual:.3g} rad/s, R² {ident.fit_r2:.4f}")
    if engine is None:
        engine = ident.info.get("engine") if isinstance(ident.info, dict) else None
    if engine is not None:
        from ..diagnostics.calibration import cylinder_torques

        m = cylinder_torques(engine, ident)
        for c in range(m.shape[2]):
            ax_m.plot(x, m[:, :, c].reshape(-1), lw=0.8, label=f"cylinder {c + 1}")
        ax_m.set_ylabel("gas torque [N·m]")
        ax_m.set_title("identified gas torque per cylinder (motored + scale × combustion)")
        if m.shape[2] <= 8:
            ax_m.legend(fontsize=8, ncol=min(4, m.shape[2]))
    else:
        ax_m.plot(np.arange(C) + 0.5, ident.load_torque_Nm, "o-", ms=3)
        ax_m.set_ylabel("load torque [N·m]")
        ax_m.set_title("identified load torque per cycle (give engine= for the cylinders' torque)")
    ax_m.set_xlim(0, C)
    ax_m.grid(True, alpha=0.3)
    k = np.arange(C)
    for c in range(ident.cylinders):
        ax_i.errorbar(k + 0.08 * (c - (ident.cylinders - 1) / 2), ident.imep_pa[:, c] / 1e5,
                      yerr=ident.imep_std_pa[:, c] / 1e5, fmt="o-", ms=3, lw=0.8, capsize=2, label=f"cylinder {c + 1}")
    mk, mc = np.nonzero(ident.misfire)
    if mk.size:
        ax_i.plot(mk, ident.imep_pa[mk, mc] / 1e5, "x", color="red", ms=10, mew=2, label="misfire")
    ax_i.set_xlabel("cycle")
    ax_i.set_ylabel("IMEP [bar]")
    ax_i.grid(True, alpha=0.3)
    ax_i.set_title(f"IMEP per cylinder and cycle ({mk.size} misfire{'s' if mk.size != 1 else ''})")
    ax_i.legend(fontsize=8, ncol=min(5, ident.cylinders + 1))
    return axes


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
    for J, label, style in ((design.crankshaft_inertia_kgm2, "designed", "-"),
                            (design.textbook_inertia_kgm2, "textbook", "--")):
        if J <= 0:
            continue
        d = [ev.state(J, OperatingPoint(r, f if np.ptp(f) else float(f[0]), ld))[0]
             for r, f, ld in zip(sweep, fuel, near)]
        ax.plot(sweep, d, style, label=f"{label}, J = {J:.4g} kg·m²")
    targets = [p.delta_target for p in design.points]
    if len(set(targets)) == 1:
        ax.axhline(targets[0], color="k", lw=0.8, ls=":", label=f"target δ = {targets[0]:g}")
    else:
        ax.plot(rpms[order], np.asarray(targets)[order], "k:", lw=0.8, marker="_", ms=14, label="targets")
    ax.plot(rpms, [p.delta for p in design.points], "o", color="C0", label="operating points (design)")
    ax.plot([design.binding_rpm], [design.delta_achieved], "*", ms=14, color="C3", label="binding point")
    if len(set(rpms)) < len(rpms):
        ax.text(0.02, 0.02, "several points share a speed: the curve follows the nearest", transform=ax.transAxes,
                fontsize=7)
    ax.set_xlabel("mean speed [rpm] (fuelling interpolated between the points)")
    ax.set_ylabel("δ = (ω_max − ω_min)/ω_mean")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    x = np.arange(len(rpms))
    bx.bar(x - 0.2, [p.inertia_kgm2 for p in design.points], 0.4, label="Newton through the steady state")
    bx.bar(x + 0.2, [p.textbook.crankshaft_inertia_kgm2 for p in design.points], 0.4,
           label="textbook J₀ − rods and pistons")
    bx.set_xticks(x, [f"{r:g} rpm" + (f" #{i + 1}" if list(rpms).count(r) > 1 else "") for i, r in enumerate(rpms)])
    bx.set_ylabel("[crankshaft] inertia for δ target [kg·m²]")
    bx.legend(fontsize=8)
    bx.grid(True, axis="y", alpha=0.3)
    ax.set_title(design.engine_name, fontsize=10)
    return axes
