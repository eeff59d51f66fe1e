"""The plot of a run: speed or torque over the last cycle."""

from __future__ import annotations

import numpy as np

from .common import angle_axis, new_axes

__all__ = ["plot_speed"]


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
    ax = new_axes(ax)
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
    angle_axis(ax, cycle_deg)
    return ax
