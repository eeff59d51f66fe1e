"""The plot of an identification: speed fit, cylinder torques, IMEP and misfires."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_identification"]


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
    x = np.arange(C * P) / P  # record angle in cycles
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
        ax_i.errorbar(
            k + 0.08 * (c - (ident.cylinders - 1) / 2),
            ident.imep_pa[:, c] / 1e5,
            yerr=ident.imep_std_pa[:, c] / 1e5,
            fmt="o-",
            ms=3,
            lw=0.8,
            capsize=2,
            label=f"cylinder {c + 1}",
        )
    mk, mc = np.nonzero(ident.misfire)
    if mk.size:
        ax_i.plot(mk, ident.imep_pa[mk, mc] / 1e5, "x", color="red", ms=10, mew=2, label="misfire")
    ax_i.set_xlabel("cycle")
    ax_i.set_ylabel("IMEP [bar]")
    ax_i.grid(True, alpha=0.3)
    ax_i.set_title(f"IMEP per cylinder and cycle ({mk.size} misfire{'s' if mk.size != 1 else ''})")
    ax_i.legend(fontsize=8, ncol=min(5, ident.cylinders + 1))
    return axes
