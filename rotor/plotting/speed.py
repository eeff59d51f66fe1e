"""Plots of a run: speed or torque over the last cycle, speed against time, orders.

Each function draws the arrays a :class:`rotor.SpeedResult` (or :class:`rotor.Orders`)
hands it; nothing here computes a δ, a mean or a harmonic.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from jaxtyping import ArrayLike

from .common import angle_axis, new_axes, place_legend, plain, speed_axis

__all__ = ["plot_speed", "plot_speed_time", "plot_cycle_torque", "plot_orders"]


def plot_speed(
    angle_deg: ArrayLike, rpm: ArrayLike, mean_rpm: float, title: str, cycle_deg: float, ax: Any = None
) -> Any:
    """Speed over one cycle against crank angle, with its time mean as a dashed line.

    **Arguments:** ``angle_deg``: crank angle in the cycle [deg]; ``rpm``: speed there
    [rev/min]; ``mean_rpm``: the cycle's time-mean speed [rev/min]; ``title``;
    ``cycle_deg``: the cycle's length [deg]; ``ax``: an Axes or None (a new figure).

    **Returns:** the Axes.
    """
    ax = new_axes(ax)
    ax.plot(angle_deg, rpm, lw=1.5)
    ax.axhline(mean_rpm, color="0.5", lw=0.8, ls="--", label="time mean")
    ax.set_ylabel("speed [rpm]")
    speed_axis(ax)
    ax.set_title(plain(title))
    ax.set_xlabel("crank angle in the cycle [deg]")
    angle_axis(ax, cycle_deg)
    place_legend(ax)
    return ax


def plot_speed_time(
    t_s: ArrayLike, rpm: ArrayLike, title: str, stall_time_s: float | None = None, ax: Any = None
) -> Any:
    """Speed over the whole run against time, with the stall marked if there is one.

    **Arguments:** ``t_s``: time [s]; ``rpm``: speed [rev/min]; ``title``;
    ``stall_time_s``: when the crankshaft stopped [s], or None; ``ax``.

    **Returns:** the Axes.
    """
    ax = new_axes(ax)
    ax.plot(t_s, rpm, lw=1.0)
    if stall_time_s is not None:
        ax.axvline(stall_time_s, color="C3", ls="--", label="stall")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("speed [rpm]")
    speed_axis(ax)
    ax.grid(True, alpha=0.3)
    ax.set_title(plain(title))
    place_legend(ax)
    return ax


def plot_cycle_torque(
    angle_deg: ArrayLike,
    torque_Nm: ArrayLike,
    load_Nm: ArrayLike,
    title: str,
    cycle_deg: float,
    ax: Any = None,
    total_Nm: ArrayLike | None = None,
) -> Any:
    """Engine torque and load-plus-friction torque over one cycle.

    **Arguments:** ``angle_deg``: crank angle in the cycle [deg]; ``torque_Nm``: the gas
    torque [N·m]; ``load_Nm``: load plus friction [N·m]; ``title``; ``cycle_deg`` [deg];
    ``ax``; ``total_Nm``: the total torque that drives the speed, gas plus the inertia
    torque of the moving masses [N·m], or None. Where it is given it is the solid line
    against the load (the crank speeds up where it lies above) and the gas torque is thin.

    **Returns:** the Axes.
    """
    ax = new_axes(ax)
    if total_Nm is None:
        ax.plot(angle_deg, torque_Nm, lw=1.2, label="engine (gas)")
    else:
        ax.plot(angle_deg, torque_Nm, lw=0.8, color="0.6", label="gas torque")
        ax.plot(angle_deg, total_Nm, lw=1.5, color="C0", label="total torque (gas + inertia of the moving masses)")
    ax.plot(angle_deg, load_Nm, lw=1.2, color="C1", label="load + friction")
    ax.set_ylabel("torque [N·m]")
    ax.set_title(plain(title))
    ax.set_xlabel("crank angle in the cycle [deg]")
    angle_axis(ax, cycle_deg)
    place_legend(ax)
    return ax


def plot_orders(order: ArrayLike, amplitude_rad_s: ArrayLike, title: str, ax: Any = None) -> Any:
    """Bars of the speed harmonic amplitudes by engine order, in rad/s as in the text and
    JSON outputs.

    **Arguments:** ``order``: engine orders [per revolution]; ``amplitude_rad_s``: speed
    amplitude of each [rad/s]; ``title``; ``ax``.

    **Returns:** the Axes.
    """
    order = np.asarray(order)
    ax = new_axes(ax)
    ax.bar(order, amplitude_rad_s, width=0.3)
    ax.set_xlabel("engine order [per revolution]")
    ax.set_ylabel("speed amplitude [rad/s]")
    ax.set_xticks(order[1::2] if len(order) > 12 else order)
    ax.grid(True, alpha=0.3, axis="y")
    ax.set_title(plain(title))
    return ax


def plot_sweep(x: ArrayLike, delta: ArrayLike, x_label: str, title: str, ax: Any = None) -> Any:
    """δ of many steady states against the input that varies, one dot each.

    **Arguments:** ``x``: the input of each item (its unit in ``x_label``); ``delta``: the
    speed irregularity of each [-]; ``x_label``; ``title``; ``ax``.

    **Returns:** the Axes.
    """
    ax = new_axes(ax)
    ax.plot(np.asarray(x), np.asarray(delta), ".", ms=3)
    ax.set_xlabel(x_label)
    ax.set_ylabel("speed irregularity δ [-]")
    ax.grid(True, alpha=0.3)
    ax.set_title(plain(title))
    return ax
