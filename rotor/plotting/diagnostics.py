"""The plots of the diagnostics subpackage: an identification (speed fit, cylinder torques, IMEP
and misfires), a calibration (measured against identified IMEP per cycle), TDC from the
speed (the fit's residual against the offset) and a pressure gain from motored cycles (their
compression on log p – log V axes)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..units import PA_PER_BAR, RPM_PER_RAD_S
from .common import cycle_axis, new_axes, place_legend, plain, settle_legends, speed_axis

__all__ = [
    "CALIBRATION_PANELS",
    "IDENTIFICATION_PANELS",
    "plot_calibration",
    "plot_identification",
    "plot_indicated_torque",
    "plot_motored_gain",
    "plot_speed_tdc",
    "plot_torque_orders",
]


IDENTIFICATION_PANELS = ("speed", "torque", "imep")
"""The panels of :func:`plot_identification`, each drawn alone with ``kind=``."""


def plot_identification(
    *,
    omega: Any,
    omega_model: Any,
    cylinder_torques: Any,
    imep_pa: Any,
    imep_std_pa: Any,
    misfire: Any,
    title: str,
    measured_imep_pa: Any = None,
    ax: Any = None,
    kind: str | None = None,
) -> Any:
    """The plot of a :class:`rotor.Identification`, from what it hands over: the speed over
    the record, measured ``omega`` and the model's ``omega_model`` ((cycles, P) [rad/s]); the
    identified gas torque of each cylinder ``cylinder_torques`` ((cycles, P, cylinders)
    [N·m]); each cylinder's IMEP per cycle ``imep_pa`` ± ``imep_std_pa`` ((cycles, cylinders)
    [Pa]) with the ``misfire`` flags ((cycles, cylinders) bool) marked, and cylinder 1's IMEP
    per cycle from a pressure channel ``measured_imep_pa`` ((cycles,) [Pa], or None) over
    it. ``title``: of the speed panel. ``kind``: None (the three panels: ``ax`` three Axes,
    or None for a new figure) or one of :data:`IDENTIFICATION_PANELS` (that panel alone on
    the one Axes ``ax``, or a new one).

    **Returns:** the array of three Axes, or with ``kind`` the one Axes.
    """
    if kind is not None and kind not in IDENTIFICATION_PANELS:
        raise ValueError(f"kind = {kind!r}: None (all panels) or one of {', '.join(IDENTIFICATION_PANELS)}")
    omega, omega_model = np.asarray(omega), np.asarray(omega_model)
    imep_pa, imep_std_pa, misfire = np.asarray(imep_pa), np.asarray(imep_std_pa), np.asarray(misfire)
    C, P = omega.shape
    cylinders = imep_pa.shape[1]
    x = 1 + np.arange(C * P) / P  # record angle in cycles, cycle k from k to k + 1

    def speed(ax_w: Any) -> None:
        ax_w.plot(x, omega.reshape(-1) * RPM_PER_RAD_S, lw=0.8, color="C0", label="measured")
        ax_w.plot(x, omega_model.reshape(-1) * RPM_PER_RAD_S, lw=0.8, color="C1", ls="--", label="model (identified)")
        ax_w.set_ylabel("speed [rpm]")
        speed_axis(ax_w)
        ax_w.set_xlabel("cycle (from 1; cycle k spans k … k + 1)")
        ax_w.set_xlim(1, C + 1)
        cycle_axis(ax_w)
        ax_w.grid(True, alpha=0.3)
        ax_w.set_title(plain(title))
        place_legend(ax_w, fontsize=8)

    def torque(ax_m: Any) -> None:
        m = np.asarray(cylinder_torques)
        for c in range(m.shape[2]):
            ax_m.plot(x, m[:, :, c].reshape(-1), lw=0.8, label=f"cylinder {c + 1}")
        ax_m.set_ylabel("gas torque [N·m]")
        ax_m.set_title("identified gas torque per cylinder (motored + scale × combustion)")
        ax_m.set_xlim(1, C + 1)
        cycle_axis(ax_m)
        ax_m.set_xlabel("cycle (from 1; cycle k spans k … k + 1)")
        ax_m.grid(True, alpha=0.3)
        if m.shape[2] <= 8:
            place_legend(ax_m, fontsize=8, ncol=min(4, m.shape[2]))

    def imep(ax_i: Any) -> None:
        k = np.arange(1, C + 1)  # cycles count from 1
        for c in range(cylinders):
            ax_i.errorbar(
                k + 0.08 * (c - (cylinders - 1) / 2),
                imep_pa[:, c] / PA_PER_BAR,
                yerr=imep_std_pa[:, c] / PA_PER_BAR,
                fmt="o-",
                ms=3,
                lw=0.8,
                capsize=2,
                label=f"cylinder {c + 1}",
            )
        if measured_imep_pa is not None:
            measured = np.asarray(measured_imep_pa, dtype=np.float64).reshape(-1)
            ax_i.plot(
                np.arange(1, measured.size + 1),
                measured / PA_PER_BAR,
                "s--",
                ms=4,
                lw=0.8,
                color="k",
                mfc="none",
                label="cylinder 1, pressure channel",
            )
        mk, mc = np.nonzero(misfire)
        if mk.size:
            ax_i.plot(mk + 1, imep_pa[mk, mc] / PA_PER_BAR, "x", color="red", ms=10, mew=2, label="misfire")
        ax_i.set_xlabel("cycle (from 1)")
        cycle_axis(ax_i)
        ax_i.set_ylabel("IMEP [bar]")
        ax_i.grid(True, alpha=0.3)
        ax_i.set_title(f"IMEP per cylinder and cycle ({mk.size} misfire{'s' if mk.size != 1 else ''})")
        place_legend(ax_i, fontsize=8, ncol=min(5, cylinders + 2))

    draw = {"speed": speed, "torque": torque, "imep": imep}
    if kind is not None:
        one = new_axes(ax)
        draw[kind](one)
        return one
    axes = ax
    if axes is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(3, 1, figsize=(11, 9), layout="constrained")
    axes = np.asarray(axes).ravel()
    for panel, axis in zip(IDENTIFICATION_PANELS, axes[:3]):
        draw[panel](axis)
    settle_legends(axes[0].figure)
    return axes


CALIBRATION_PANELS = ("imep", "loss")
"""The panels of :func:`plot_calibration`, each drawn alone with ``kind=``."""


def plot_calibration(
    *,
    imep_measured_pa: Any,
    loss_torque_Nm: Any,
    imep_file_pa: float | None,
    title: str,
    ax: Any = None,
    kind: str | None = None,
) -> Any:
    """The plot of a :class:`rotor.Calibration`: the calibration recording's IMEP of each
    cycle from its pressure channel ``imep_measured_pa`` ((cycles,) [Pa], with the engine
    file's ``imep_file_pa`` [Pa] as a line when known), and the loss torque (friction plus
    load) fitted per cycle ``loss_torque_Nm`` ((cycles,) [N·m]). ``ax``: with ``kind`` None,
    two Axes, or None for a new figure; with ``kind`` ``"imep"`` or ``"loss"``, that panel
    alone on the one Axes ``ax`` (or a new one).

    **Returns:** the array of two Axes, or with ``kind`` the one Axes.
    """
    if kind is not None and kind not in CALIBRATION_PANELS:
        raise ValueError(f"kind = {kind!r}: None (both panels) or one of {', '.join(CALIBRATION_PANELS)}")
    imep = np.asarray(imep_measured_pa, dtype=np.float64)
    loss = np.asarray(loss_torque_Nm, dtype=np.float64)

    def imep_panel(ax_p: Any) -> None:
        ax_p.plot(np.arange(1, imep.size + 1), imep / PA_PER_BAR, "o-", ms=4, color="C0", label="pressure channel")
        if imep_file_pa is not None:
            ax_p.axhline(imep_file_pa / PA_PER_BAR, color="0.4", ls="--", lw=1, label="engine file")
        ax_p.set_ylabel("IMEP [bar]")
        cycle_axis(ax_p)
        ax_p.grid(True, alpha=0.3)
        ax_p.set_title(plain(title))
        place_legend(ax_p, fontsize=8)

    def loss_panel(ax_l: Any) -> None:
        ax_l.plot(np.arange(1, loss.size + 1), loss, "s-", ms=4, color="C3")
        ax_l.set_xlabel("cycle (from 1)")
        cycle_axis(ax_l)
        ax_l.set_ylabel("friction + load [N·m]")
        ax_l.grid(True, alpha=0.3)

    if kind is not None:
        one = new_axes(ax)
        (imep_panel if kind == "imep" else loss_panel)(one)
        if kind == "imep":
            one.set_xlabel("cycle (from 1)")
        return one
    axes = ax
    if axes is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True, layout="constrained")
    axes = np.asarray(axes).ravel()
    imep_panel(axes[0])
    loss_panel(axes[1])
    settle_legends(axes[0].figure)
    return axes


def plot_indicated_torque(*, theta: Any, torque: Any, net_torque: Any, title: str, ax: Any = None) -> Any:
    """The indicated torque of every cycle over the record: ``theta`` the cycle-angle grid
    (P,) [rad], ``torque`` and ``net_torque`` (cycles, P) [N·m] (the gas torque and the
    torque accelerating the crank train). ``ax``: one Axes or None. **Returns:** the Axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(10, 4), layout="constrained")
    theta = np.asarray(theta)
    torque, net = np.atleast_2d(np.asarray(torque)), np.atleast_2d(np.asarray(net_torque))
    C, P = torque.shape
    x = np.arange(C * P) / P  # record angle in cycles
    ax.plot(x, torque.reshape(-1), lw=0.9, color="C0", label="indicated (gas) torque")
    ax.plot(x, net.reshape(-1), lw=0.7, color="C1", alpha=0.8, label="net torque d(½Iω²)/dθ")
    ax.set_xlim(0, C)
    cycle_axis(ax)
    ax.set_xlabel(f"cycle (of {np.rad2deg(theta[-1] + theta[1] - theta[0]):.0f}° each)")
    ax.set_ylabel("torque [N·m]")
    ax.grid(True, alpha=0.3)
    ax.set_title(plain(title))
    place_legend(ax, fontsize=8)
    return ax


def plot_torque_orders(*, order: Any, amplitude_Nm: Any, title: str, ax: Any = None) -> Any:
    """Torque harmonics by engine order: ``order`` (K,) [per revolution], ``amplitude_Nm``
    (cycles, K) [N·m] as bars of the cycles' mean with their spread. ``ax``: one Axes or
    None. **Returns:** the Axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 4), layout="constrained")
    order = np.asarray(order)
    amp = np.atleast_2d(np.asarray(amplitude_Nm))
    spread = amp.std(axis=0, ddof=1) if amp.shape[0] > 1 else np.zeros(order.size)
    width = 0.6 * float(np.min(np.diff(order))) if order.size > 1 else 0.3
    ax.bar(order, amp.mean(axis=0), width=width, yerr=spread, capsize=2, color="C0")
    ax.set_xlabel("engine order [per revolution]")
    ax.set_ylabel("torque amplitude [N·m]")
    ax.grid(True, alpha=0.3, axis="y")
    ax.set_title(plain(title))
    return ax


def plot_speed_tdc(
    *,
    candidates_deg: Any,
    residual: Any,
    offset_deg: float,
    std_deg: float,
    r2: float,
    cycle_deg: float,
    given_deg: float | None = None,
    ax: Any = None,
) -> Any:
    """The plot of a :class:`rotor.diagnostics.phase.SpeedTdc`: the fit's summed residual over
    the speed fluctuation's power ``residual`` ((D,) [-]) against the candidate offset of
    cylinder 1's TDC from the cycle grid's start ``candidates_deg`` ((D,) [deg]), the best
    ``offset_deg`` [deg] (± ``std_deg`` [deg], R² ``r2`` [-]) marked, and a checked TDC
    ``given_deg`` [deg, same frame] where there is one; ``cycle_deg``: the cycle's length
    [deg]. ``ax``: one Axes or None for a new figure. **Returns:** the Axes."""
    from .common import angle_axis, new_axes

    ax = new_axes(ax)
    ax.plot(np.asarray(candidates_deg), np.asarray(residual), lw=1.0, label="residual / fluctuation power")
    ax.axvline(offset_deg, color="C3", lw=1.0, ls="--", label=f"TDC {offset_deg:.1f}°")
    if given_deg is not None:
        ax.axvline(
            given_deg % cycle_deg, color="0.4", lw=1.0, ls=":", label=f"checked TDC {given_deg % cycle_deg:.1f}°"
        )
    angle_axis(ax, cycle_deg)
    ax.set_xlabel("offset of cylinder 1's TDC from the cycle grid's start [deg]")
    ax.set_ylabel("residual [-]")
    ax.set_title(f"TDC from the speed: {offset_deg:.1f}° ± {std_deg:.2f}°, R² {r2:.3f}")
    place_legend(ax, fontsize="small")
    return ax


def plot_motored_gain(
    *, volume_ratio: Any, pressure_pa: Any, exponent: float, intake_pa: float, title: str, ax: Any = None
) -> Any:
    """The plot of a :class:`rotor.diagnostics.pegging.MotoredGain`: the motored cycles' mean
    pressure ``pressure_pa`` ((n,) [Pa], with the gain and offset found) against the volume
    ``volume_ratio`` ((n,) V/V_BDC [-]) on log–log axes, and the polytrope
    p = ``intake_pa``·(V/V_BDC)^(−``exponent``) it was pegged to. ``ax``: one Axes or None.
    **Returns:** the Axes."""
    from .common import new_axes

    ax = new_axes(ax, figsize=(6, 4.5))
    v = np.asarray(volume_ratio, dtype=np.float64)
    ax.loglog(v, np.asarray(pressure_pa) / PA_PER_BAR, ".", ms=3, color="C0", label="motored cycles (mean)")
    vv = np.geomspace(float(v.min()), 1.0, 50)
    ax.loglog(
        vv,
        intake_pa * vv ** (-exponent) / PA_PER_BAR,
        "--",
        lw=1,
        color="C3",
        label=f"p·V^{exponent:.3g} constant from {intake_pa / PA_PER_BAR:.3g} bar at BDC",
    )
    ax.set_xlabel("V / V_BDC [-]")
    ax.set_ylabel("pressure [bar]")
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title(plain(title), fontsize=9)
    place_legend(ax, fontsize=8)
    return ax
