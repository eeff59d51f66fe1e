"""The plots of the logs subpackage: a logged-speed analysis and a wheel's tooth errors."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..units import RPM_PER_RAD_S
from .common import angle_axis, cycle_axis, new_axes, place_legend, plain, settle_legends, speed_axis

__all__ = ["LOG_ANALYSIS_PANELS", "plot_log_analysis", "plot_reading", "plot_tooth_errors"]


def plot_tooth_errors(errors_deg: Any, method: str, ax: Any = None) -> Any:
    """Each tooth's angle error as a bar: ``errors_deg`` [deg] (tooth 0 = the first edge
    after the gap), ``method`` (how they were found, for the title). **Returns:** the Axes."""
    ax = new_axes(ax)
    errors_deg = np.asarray(errors_deg)
    ax.bar(np.arange(errors_deg.size), errors_deg, color="C1")
    ax.set_xlabel("tooth (0 = first after the gap)")
    ax.set_ylabel("tooth error [deg]")
    ax.grid(True, alpha=0.3, axis="y")
    ax.set_title(f"tooth errors applied ({plain(method)})")
    return ax


LOG_ANALYSIS_PANELS = ("speed", "cycles", "orders", "signal")
"""The panels of :func:`plot_log_analysis`, each drawn alone with ``kind=``."""


def plot_log_analysis(analysis: Any, ax: Any = None, kind: str | None = None) -> Any:
    """The combined plot of a :class:`rotor.LogAnalysis`: speed over the cycle (every
    cycle and their mean), each cycle's mean speed and δ, the order spectrum (mean and
    cycle-to-cycle spread), and the pressure signal over the cycle (or, without one,
    the tooth errors applied).

    ``ax``: with ``kind`` None, a 2×2 array of Axes (or four Axes), or None for a new
    figure; with ``kind`` one of :data:`LOG_ANALYSIS_PANELS` (``"speed"``, ``"cycles"``,
    ``"orders"``, ``"signal"``), that panel alone on the one Axes ``ax`` (or a new one).

    **Returns:** the 2×2 array of Axes, or with ``kind`` the one Axes.
    """
    if kind is not None and kind not in LOG_ANALYSIS_PANELS:
        raise ValueError(f"kind = {kind!r}: None (all panels) or one of {', '.join(LOG_ANALYSIS_PANELS)}")
    a = analysis
    cycle_deg = np.rad2deg(a.cycle_rad)

    def speed(ax_w: Any) -> None:
        ang = np.rad2deg(a.cycle_angle_rad)
        rpm = a.omega * RPM_PER_RAD_S
        for row in rpm:
            ax_w.plot(ang, row, lw=0.6, color="0.6", alpha=0.6)
        label = f"mean of {a.cycles} cycles" if a.cycles != 1 else "1 cycle"
        ax_w.plot(ang, rpm.mean(axis=0), lw=1.8, color="C0", label=label)
        if str(a.tdc_method).startswith("unknown"):  # the cycles start at the gap: no TDC to name
            ax_w.set_xlabel("cycle angle from the gap [deg] (TDC unknown)")
        else:
            ax_w.set_xlabel("cycle angle [deg] (360 = firing TDC)" if a.strokes == 4 else "crank angle from TDC [deg]")
        ax_w.set_ylabel("speed [rpm]")
        speed_axis(ax_w)
        angle_axis(ax_w, cycle_deg)
        ax_w.set_title(f"{plain(a.source)}: speed over the cycle")
        place_legend(ax_w, fontsize=8)

    def cycles(ax_c: Any) -> None:
        k = np.arange(1, a.cycles + 1)  # cycles count from 1
        ax_c.plot(k, a.mean_rpm, "o-", color="C0", ms=4)
        ax_c.set_xlabel("cycle (from 1)")
        cycle_axis(ax_c)
        ax_c.set_ylabel("mean speed [rpm]", color="C0")
        speed_axis(ax_c)
        twin = ax_c.twinx()
        twin.plot(k, a.delta, "s--", color="C3", ms=4)
        twin.set_ylabel("δ per cycle, trend removed [-]", color="C3")
        ax_c.grid(True, alpha=0.3)
        ax_c.set_title("cycle to cycle")

    def orders(ax_o: Any) -> None:
        m, s = (
            a.amplitude_rad_s.mean(axis=0),
            (a.amplitude_rad_s.std(axis=0, ddof=1) if a.cycles > 1 else np.zeros(a.order.size)),
        )
        ax_o.bar(a.order, m, width=0.3, yerr=s, capsize=2, color="C0")
        ax_o.set_xlabel("engine order [per revolution]")
        ax_o.set_ylabel("speed amplitude [rad/s]")
        ax_o.grid(True, alpha=0.3, axis="y")
        ax_o.set_title("order spectrum (mean ± cycle-to-cycle std)")

    def signal(ax_p: Any) -> None:
        if a.pressure is not None:
            ph, pv, cyc = a.pressure
            order = np.argsort(cyc * 10 + ph / a.cycle_rad, kind="stable")
            ax_p.plot(np.rad2deg(ph[order]), pv[order], ",", color="C2", alpha=0.5)
            ax_p.set_xlabel("cycle angle [deg]")
            ax_p.set_ylabel("pressure signal [V]")
            angle_axis(ax_p, cycle_deg)
            ax_p.set_title(f"pressure; TDC {np.rad2deg(a.tdc_rad):.1f}° after the gap")
        elif a.tooth_errors is not None:
            plot_tooth_errors(a.tooth_errors.errors_deg, a.tooth_errors.method, ax=ax_p)
        else:
            ax_p.set_axis_off()

    draw = {"speed": speed, "cycles": cycles, "orders": orders, "signal": signal}
    if kind is not None:
        one = new_axes(ax)
        draw[kind](one)
        return one
    axes = ax
    if axes is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 2, figsize=(12, 8), layout="constrained")
    axes = np.asarray(axes)
    for panel, axis in zip(LOG_ANALYSIS_PANELS, axes.ravel()[:4]):
        draw[panel](axis)
    settle_legends(axes.ravel()[0].figure)
    return axes


def plot_reading(
    t_s: Any,
    v: Any,
    edge_times_s: Any,
    levels_v: dict,
    repairs: Any,
    title: str,
    *,
    span_s: tuple | None = None,
    steps: bool = False,
    ax: Any = None,
) -> Any:
    """The wheel signal as read (``steps``: a capture's 0/1 levels, held from one transition
    to the next, labelled as levels): the samples ``t_s`` [s], ``v`` (volts, or 0/1 levels), the
    levels found (``levels_v``: name → value [V], or a level of a capture, drawn as horizontal lines), the edges taken
    (``edge_times_s`` [s], markers on the signal) and every repair (each with ``time_s`` and
    ``kind``: a vertical line, labelled by kind), within ``span_s`` (start, end) [s] (default:
    the whole record). **Returns:** the Axes."""
    ax = new_axes(ax)
    t = np.asarray(t_s, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    lo, hi = (t[0], t[-1]) if span_s is None else span_s
    a, b = np.searchsorted(t, [lo, hi])
    step = max(1, (b - a) // 200_000)
    ax.plot(
        t[a:b:step], v[a:b:step], lw=0.6, color="0.4", label="signal", drawstyle="steps-post" if steps else "default"
    )
    for k, (name, level) in enumerate(levels_v.items()):
        unit = "" if steps else " V"
        ax.axhline(level, ls="--", lw=0.8, color=f"C{k + 1}", label=plain(f"{name} {level:.3g}{unit}"))
    e = np.asarray(edge_times_s, dtype=np.float64)
    e = e[(e >= lo) & (e <= hi)]
    at = v[np.clip(np.searchsorted(t, e, side="right") - 1, 0, v.size - 1)] if steps else np.interp(e, t, v)
    ax.plot(e, at, "o", ms=3, color="C0", label=f"edges taken ({e.size})")
    seen = set()
    for r in repairs:
        if lo <= r.time_s <= hi:
            ax.axvline(r.time_s, color="C3", lw=0.8, alpha=0.7, label=None if r.kind in seen else plain(r.kind))
            seen.add(r.kind)
    ax.set_xlim(lo, hi)
    ax.set_xlabel("time [s]")
    if steps:  # a logic analyser's channel: levels, not volts
        ax.set_ylabel("level (0 = low, 1 = high)")
        ax.set_yticks([0, 1])
    else:
        ax.set_ylabel("signal [V]")
    ax.set_title(plain(title))
    ax.grid(True, alpha=0.3)
    place_legend(ax, fontsize=7)
    return ax
