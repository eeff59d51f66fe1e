"""The plots of a torsional chain's forced response and transient: speed at the flywheel and
at the pulley over a cycle, the shafts' twist and vibratory torque, and the resonance
curves (vibratory torque against speed).

Each function draws what the result hands it (:class:`rotor.TorsionalResponse`,
:class:`rotor.TorsionalSweep`, :class:`rotor.TorsionalRun`); nothing here solves anything.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from jaxtyping import Float

from .common import angle_axis, place_legend, plain, settle_legends, speed_axis

__all__ = ["plot_torsional_response", "plot_torsional_sweep", "plot_torsional_run"]


def _axes(ax: Any, rows: int, figsize: tuple[float, float]) -> Any:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, axes = plt.subplots(rows, 1, figsize=figsize, sharex=True, layout="constrained")
    return axes


def plot_torsional_response(
    angle_deg: Float[np.ndarray, " P"],
    rpm_reference: Float[np.ndarray, " P"],
    rpm_front: Float[np.ndarray, " P"],
    names: tuple[str, str],
    twist_rad: Float[np.ndarray, "m P"],
    vibratory_torque_Nm: Float[np.ndarray, "m P"],
    section_names: Sequence[str],
    title: str,
    ax: Any = None,
) -> Any:
    """Three panels against the reference mass's crank angle [deg]: the speed of the
    reference mass (``rpm_reference``) and of the front mass (``rpm_front``) [rpm], named
    by ``names``; each section's twist ``twist_rad`` [rad, drawn in mrad]; each section's
    vibratory torque ``vibratory_torque_Nm`` [N·m], named by ``section_names``. ``ax``:
    three Axes or None (a new figure). Returns the three Axes."""
    axes = _axes(ax, 3, (9, 8.5))
    a0, a1, a2 = np.ravel(axes)[:3]
    cycle = float(np.round(angle_deg[-1] + (angle_deg[1] - angle_deg[0])))
    a0.plot(angle_deg, rpm_reference, lw=1.6, label=f"{plain(names[0])} (reference)")
    if names[1] != names[0]:
        a0.plot(angle_deg, rpm_front, lw=1.0, label=plain(names[1]))
    a0.set_ylabel("speed [rpm]")
    speed_axis(a0)
    a0.set_title(plain(title))
    many = len(section_names) > 10
    for i, name in enumerate(section_names):
        a1.plot(angle_deg, np.asarray(twist_rad[i]) * 1e3, lw=0.9, label=None if many else plain(name))
        a2.plot(angle_deg, vibratory_torque_Nm[i], lw=0.9, label=None if many else plain(name))
    a1.set_ylabel("twist θᵢ − θᵢ₊₁ [mrad]")
    a2.set_ylabel("vibratory torque [N·m]")
    a2.set_xlabel("crank angle of the reference mass [deg]")
    for a in (a0, a1, a2):
        angle_axis(a, cycle)
    place_legend(a0, fontsize=8)
    if not many:
        place_legend(a1, fontsize=7, ncol=2)
    settle_legends(a0.figure)
    return axes


def plot_torsional_sweep(
    rpm: Float[np.ndarray, " S"],
    torque_pp_Nm: Float[np.ndarray, "S m"],
    section_names: Sequence[str],
    critical_rpm: Sequence[float],
    title: str,
    ax: Any = None,
) -> Any:
    """Each section's vibratory torque peak to peak ``torque_pp_Nm`` [N·m] against speed
    ``rpm`` [rpm] (log scale), with vertical marks at ``critical_rpm`` [rpm]. ``ax``: one
    Axes or None. Returns the Axes."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(9, 4.8), layout="constrained")
    for i, name in enumerate(section_names):
        ax.plot(rpm, torque_pp_Nm[:, i], lw=1.0, label=plain(name))
    for r in critical_rpm:
        ax.axvline(r, color="k", lw=0.6, ls=":", alpha=0.6)
    finite = np.asarray(torque_pp_Nm)[np.isfinite(torque_pp_Nm)]
    if finite.size and np.all(finite > 0):
        ax.set_yscale("log")
    ax.set_xlabel("mean speed [rpm]" + (" (dotted: critical speeds of the strong orders)" if critical_rpm else ""))
    speed_axis(ax, "x")
    ax.set_ylabel("vibratory torque, peak to peak [N·m]")
    ax.set_title(plain(title))
    ax.grid(True, alpha=0.3)
    if len(section_names) <= 12:
        place_legend(ax, fontsize=7, ncol=2)
    return ax


def plot_torsional_run(
    t_s: Float[np.ndarray, " T"],
    rpm: Float[np.ndarray, "T n"],
    names: Sequence[str],
    torque_Nm: Float[np.ndarray, "T m"],
    section_names: Sequence[str],
    title: str,
    ax: Any = None,
) -> Any:
    """Two panels against time ``t_s`` [s]: the speed of each mass ``rpm`` [rpm] (named
    ``names``) and each section's torque ``torque_Nm`` [N·m] (``section_names``). ``ax``:
    two Axes or None. Returns the two Axes."""
    axes = _axes(ax, 2, (9, 6))
    a0, a1 = np.ravel(axes)[:2]
    many = len(names) > 10
    for j, name in enumerate(names):
        a0.plot(t_s, rpm[:, j], lw=0.9, label=None if many else plain(name))
    for i, name in enumerate(section_names):
        a1.plot(t_s, torque_Nm[:, i], lw=0.8, label=None if len(section_names) > 10 else name)
    a0.set_ylabel("speed [rpm]")
    speed_axis(a0)
    a0.set_title(plain(title))
    a1.set_ylabel("shaft torque [N·m]")
    a1.set_xlabel("time [s]")
    for a in (a0, a1):
        a.grid(True, alpha=0.3)
    if not many:
        place_legend(a0, fontsize=7, ncol=2)
    settle_legends(a0.figure)
    return axes
