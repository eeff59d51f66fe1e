"""Model-based identification: each firing's combustion scale (IMEP) from the crank speed.

:func:`identify` fits the engine model to a measured (or simulated) speed ω(θ) on the
uniform cycle-angle grid of consecutive cycles, by least squares through the closed-form
energy cycle of :mod:`rotor.dynamics.equation`:

    dE/dθ = M_motored(θ) + Σ_c s[k, c]·ΔM_c(θ) − a_k − 2(c − k(θ))/I(θ)·E,   E = ½·I(θ)·ω²,

with the losses a_k + c·ω² (friction and load: c known from the friction and the load
model, a_k an unknown constant torque per cycle). Firing k of cylinder c (TDC at
θ_fire,c + k·Θ) owns the half cycle either side of its TDC, as in the simulator.

**Parameters** (per block of cycles, see below): the kinetic energy at the block's start,
the load torque a_k of every cycle, and the combustion scale s of every firing.
E(θ) is *affine* in all of them (the factor Φ(θ) = exp(−∫2(c − k)/I) does not depend on
them), so every basis function ∫ΔM_c/Φ is computed once on the table nodes with the
simulator's fourth-order Hermite rule and only combined per fit. The start is the exact
weighted linear least-squares solution in E (weights 1/(I·ω), so that an error in E counts
as the speed error it makes); then :class:`optimistix.LevenbergMarquardt` minimises the
residual ω_model − ω_measured itself (JAX Jacobian), in about three steps.

**Blocks.** A long record is cut into blocks of ``block_cycles`` cycles that overlap by
``overlap`` cycles on each side; each block is fitted on its own (all blocks at once,
``jax.vmap``) and gives the results of its core cycles. The fits stay small (a 12-cycle
block of a six: about 90 parameters, 2880 residuals), well conditioned and fast: 100
cycles of a six in 0.48 s after compile (4chn15 0.39 s; 2-CPU machine,
``benchmarks/identification.py``; the first call compiles for about 4 s). The overlap
keeps the block-edge effects (the energy at the block start, the firings cut by the
block edge) out of the results: a fit in blocks agrees with one fit of the whole record.

**Firings cut by the record's ends.** A firing whose combustion torque lies less than half
inside the block is still fitted on its own (so that a misfire just before the record does
not bias the first cycle: it did by up to 5.6 % of IMEP when such firings shared their
neighbour's scale), but ``identified`` is False for it; one with less than 1 % inside is
not fitted and shares the scale of the nearest fitted firing of its cylinder.

**Uncertainty and fit.** The covariance of each block is the least-squares sandwich
(JᵀJ)⁻¹·JᵀΣJ·(JᵀJ)⁻¹ with the residual's noise taken as stationary, its spectrum the
residual's periodogram smoothed over ±½ engine order: a speed from tooth times carries
the timer's jitter differentiated (noise growing with the order, little of it at the low
orders that carry the scales), and the white-noise σ²·(JᵀJ)⁻¹ overstated the scatter
7.5× there (200 ns jitter, 4chn15). Per cycle: the covariance of the cycle's scales and
load (``covariance``, (cycles, n+1, n+1)); ``scale_std``; ``rms_residual_rad_s``; ``r2``:
1 − Σ residual² / Σ (ω − cycle mean)², the share of the speed fluctuation that the model
explains. The covariance is that of the noise; a bias common to every revolution (the
wheel's tooth errors left after calibration, which fall on the engine orders) is not in it.

**Accuracy measured** (``benchmarks/identification.py``: 4chn15 at 800/1250/1800 rpm, mwm6
at 1200/1700/2200 rpm, loads 10/20/50/100 %, ±10 % IMEP spread, 2 % cycle-to-cycle
variation, 3 % random misfires, 60-2 wheel with ±0.2° tooth errors calibrated on a
coast-down, 20 ns jitter, 40 cycles, 2 seeds): IMEP error of every firing, relative to
the cylinder's nominal IMEP, at most 0.08 / 0.23 / 0.51 % (rms 0.03 / 0.09 / 0.18 %) for
4chn15 and 0.30 / 0.67 / 1.22 % (rms 0.15 / 0.33 / 0.57 %) for mwm6 by speed, the same at
every load (the errors are those of the speed signal, which grow as ω²: jitter and the
calibration's residual tooth errors, 0.0015° at most); each cylinder's mean IMEP over the
record within 0.73 %. The direct simulated speed (no wheel) gives the scales to 1e-9.

**Misfires** (:mod:`rotor.diagnostics.misfire`): the contribution index s / s_ref and the misfire
flag index < 0.5 (see there for the reference, the floor that makes a coast-down all
misfires, and the rates measured by ``benchmarks/identification.py``).

**Four-stroke phase.** Where the engine is symmetric under a shift of 360° (an inline
four: cylinders 1 and 4, 2 and 3 share a throw and fire 360° apart; an inline six:
1–6, 2–5, 3–4), the crank speed alone cannot tell which revolution holds cylinder 1's
firing: with the wrong one the same fit comes out with the pairs swapped. Unless the
phase is known (``phase_reference=True``, or a :class:`rotor.LogAnalysis` whose firing
revolution came from a pressure or cam channel or was given), the result names the
pairs as ambiguous (``ambiguous_pairs``, a note).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg
import lineax as lx
import numpy as np
import optimistix as optx
from jaxtyping import ArrayLike

from ..cache import padded_size
from ..dynamics.crank_train import (
    COL_COMBUSTION,
    COL_I,
    COL_K,
    COL_MOTORED,
    check_fidelity,
    grid_points,
    train_from_engine,
)
from ..dynamics.equation import friction_coefficients, hermite_cumulative, node_offsets, wrap_periodic
from ..dynamics.loads import ConstantLoad, Load
from ..dynamics.prepared import PreparedEngine, resolve_engine
from ..errors import EngineError
from ..programs import kept_program
from ..results import Result, json_safe
from ..units import PA_PER_BAR
from .misfire import FLOOR_SCALE, MISFIRE_THRESHOLD, contribution_index

if TYPE_CHECKING:
    from ..dynamics.result import SpeedResult
    from ..engine.friction import Friction
    from ..engine.model import Engine
    from ..logs.analysis import LogAnalysis

__all__ = ["Identification", "identify", "NO_FIRING_NOTE", "PARAMETERS", "POOR_FIT_R2"]

PARAMETERS = ("imep_scale",)
TIED_BELOW = 0.5  # a firing with less than this share of its combustion torque inside the block: not identified
FITTED_FROM = 0.01  # … and with less than this share not fitted either (tied to its neighbour)
DEFAULT_BLOCK = 8
DEFAULT_OVERLAP = 2
NO_FIRING_NOTE = "no firing found: the engine does not fire in this record (a coast-down or motored run)"
POOR_FIT_R2 = 0.7
"""Below this R² of the whole fit (the share of the speed fluctuation the model explains) a
result warns that the fit is poor and its IMEP uncertain beyond the ± it reports (which
counts the noise only, as if the model were right). Measured: the real single-cylinder
bench recordings (``tue-single``) diagnosed with their full-load calibration give R² 0.89 (full load, IMEP within
0.1 % of the pressure channel's), 0.83 (half load, −1.9 %) and 0.44 (no load, −17 %); simulated
recordings with their own calibration 0.99 and more. 0.7 sits between the recordings read to
2 % and the one read 17 % low."""


# ----------------------------------------------------------------------------- result
@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Identification(Result):
    """Per-firing combustion scales, IMEP, loads and misfires identified from ω(θ).

    **Per cycle and cylinder** (cycles, cylinders): ``scale`` [-] (the firing's combustion
    scale: 1 = the engine file's cycle, 0 = none), ``scale_std`` [-], ``imep_pa`` and
    ``imep_std_pa`` [Pa] (the estimate's uncertainty: the speed's noise only; the
    cycle-to-cycle spread is :attr:`imep_cycle_std_pa`), ``identified`` (False: a firing cut by the record's end, tied to
    its neighbour), ``contribution`` (index, 1 = a normal firing) [-], ``misfire`` (bool).
    Row k − 1 holds cycle k (cycles and cylinders count from 1 in every output; the
    arrays' rows and columns are 0-based positions): the firing of cylinder c in cycle k
    has its TDC at cycle angle θ_fire,c in that cycle.

    **Per cycle:** ``load_torque_Nm`` (the mean load torque: the fitted constant torque
    less the friction's, plus the load model's c·ω²) and ``load_std_Nm`` [N·m];
    ``loss_torque_Nm`` (all losses, friction included) [N·m]; ``mean_omega`` [rad/s];
    ``t_start_s`` [s] (or None); ``covariance`` (cycles, n+1, n+1): of the cycle's scales
    and its constant loss torque [-, N·m]; ``reference_scale`` (the misfire reference);
    ``rms_residual_rad_s``, ``r2`` (per cycle).

    **Record:** ``omega``, ``omega_model`` (cycles, P) [rad/s]; ``rms_residual`` [rad/s],
    ``fit_r2`` and ``relative_residual`` (rms residual / rms speed fluctuation) of the
    whole record; ``ambiguous_pairs`` (cylinder pairs, numbered from 1, that the crank
    speed cannot tell apart, or ()); ``threshold``; ``notes``; ``wall_s`` [s];
    ``engine``: the :class:`rotor.Engine` identified (its tables explain the speed; after
    :func:`rotor.diagnose` the calibrated and charge-scaled one).

    **The fit:** ``blocks`` (how many), ``block_cycles`` (cycles per block, overlap
    included), ``block_starts`` (the row index, from 0, of each block's first cycle),
    ``iterations`` (Levenberg–Marquardt
    steps of each), ``table_points`` (crank-train table nodes per cycle), ``load_per``.
    """

    scale: np.ndarray
    scale_std: np.ndarray
    imep_pa: np.ndarray
    imep_std_pa: np.ndarray
    identified: np.ndarray
    contribution: np.ndarray
    misfire: np.ndarray
    reference_scale: np.ndarray
    load_torque_Nm: np.ndarray
    load_std_Nm: np.ndarray
    loss_torque_Nm: np.ndarray
    mean_omega: np.ndarray
    covariance: np.ndarray
    rms_residual_rad_s: np.ndarray
    r2: np.ndarray
    omega: np.ndarray
    omega_model: np.ndarray
    rms_residual: float
    fit_r2: float
    relative_residual: float
    imep_nominal_pa: np.ndarray
    threshold: float
    engine: Engine
    ambiguous_pairs: tuple = ()
    t_start_s: np.ndarray | None = None
    notes: tuple = ()
    engine_name: str = ""
    wall_s: float = float("nan")
    blocks: int = 1
    block_cycles: int = 0
    block_starts: tuple = ()
    iterations: tuple = ()
    table_points: int = 0
    load_per: str = "cycle"

    @property
    def cycles(self) -> int:
        """Cycles identified."""
        return int(self.scale.shape[0])

    @property
    def cylinders(self) -> int:
        """Cylinders of the engine identified."""
        return int(self.scale.shape[1])

    @property
    def imep_cycle_std_pa(self) -> np.ndarray:
        """Each cylinder's cycle-to-cycle spread of the identified IMEP [Pa], (cylinders,):
        the standard deviation over its normal identified firings (NaN with fewer than
        two); not the estimate's uncertainty (``imep_std_pa``), which counts the noise only."""
        out = np.full(self.cylinders, np.nan)
        for c in range(self.cylinders):
            ok = self.identified[:, c] & ~self.misfire[:, c]
            if ok.sum() >= 2:
                out[c] = float(np.std(self.imep_pa[ok, c], ddof=1))
        return out

    def misfires(self) -> list:
        """The misfires as (cycle, cylinder) pairs, both counted from 1 (cycle 1 the record's
        first; row ``cycle − 1`` of the per-cycle arrays)."""
        return [(int(k) + 1, int(c) + 1) for k, c in np.argwhere(self.misfire)]

    def cylinder_torques(self) -> np.ndarray:
        """The identified gas torque of each cylinder on each cycle's grid: the motored torque
        plus the firing's scale times its combustion torque, (cycles, P, cylinders) [N·m], of
        :attr:`engine` (firing k of a cylinder owns the half cycle either side of its TDC;
        here each cycle's grid takes the scale of that cycle's firing)."""
        from ..engine.forces import cylinder_gas_torques

        engine = self.engine
        C, P = self.omega.shape
        theta = np.arange(P) * float(engine.cycle_rad) / P
        fired = np.asarray(cylinder_gas_torques(engine, theta))
        motored_engine = engine.replace(pressure=engine.pressure.motored(engine.strokes))
        motored = np.asarray(cylinder_gas_torques(motored_engine, theta))
        comb = fired - motored
        return motored[None, :, :] + self.scale[:, None, :] * comb[None, :, :]

    @property
    def warnings(self) -> tuple[str, ...]:
        """What makes the numbers doubtful, one line each: a fit whose R² lies below
        :data:`POOR_FIT_R2` (the model explains too little of the speed fluctuation, so the
        IMEP is uncertain beyond its ±). Empty when there is nothing to warn about."""
        r2 = float(self.fit_r2)
        if r2 >= POOR_FIT_R2:
            return ()
        share = "none" if not r2 > 0 else f"only {r2:.0%}"
        return (
            f"poor fit: the model explains {share} of the speed fluctuation (R² {r2:.2f}, below "
            f"{POOR_FIT_R2:g}): the IMEP is uncertain beyond its ± (which counts the noise only); check "
            f"the engine file, the calibration and the wheel",
        )

    def summary(self, warnings: Sequence[str] | None = None) -> str:
        """A few lines for a terminal: the fit (and a warning when it is poor, see
        :attr:`warnings`), each cylinder's IMEP, the load, the misfires. ``warnings``: the
        lines to warn with in place of :attr:`warnings` (a :class:`rotor.Diagnosis` gives its own)."""
        lines = [
            f"{self.engine_name}: {_count(self.cycles, 'cycle')} identified, rms residual {self.rms_residual:.3g} "
            f"rad/s ({self.relative_residual:.2%} of the speed fluctuation, R² {self.fit_r2:.5f})",
            *(f"  warning: {w}" for w in (self.warnings if warnings is None else warnings)),
            "  cylinder  IMEP mean [bar]  ±1σ estimate  cycle-to-cycle σ   scale mean   misfires",
        ]
        spread = self.imep_cycle_std_pa
        for c in range(self.cylinders):
            ok = self.identified[:, c] & ~self.misfire[:, c]
            imep = f"{np.mean(self.imep_pa[ok, c]) / PA_PER_BAR:15.3f}" if ok.any() else f"{'—':>15}"
            scale = f"{np.mean(self.scale[ok, c]):10.4f}" if ok.any() else f"{'—':>10}"
            cyc = f"{spread[c] / PA_PER_BAR:16.3f}" if np.isfinite(spread[c]) else f"{'—':>16}"
            lines.append(
                f"  {c + 1:8d}  {imep}  {np.median(self.imep_std_pa[:, c]) / PA_PER_BAR:12.3f}  {cyc}   {scale}   "
                f"{int(np.sum(self.misfire[:, c]))}"
            )
        lines.append(
            "  (over the normal firings; ±1σ estimate: the median uncertainty of one firing's IMEP from the speed's "
            "noise; cycle-to-cycle σ: the spread of the identified IMEP over the cycles) [bar]"
        )
        lines.append(
            f"  load torque {np.mean(self.load_torque_Nm):.2f} N·m (cycles {np.min(self.load_torque_Nm):.2f} … "
            f"{np.max(self.load_torque_Nm):.2f})"
        )
        m = self.misfires()
        lines.append(f"  misfires (cycle, cylinder): {m if m else 'none'}")
        for n in self.notes:
            lines.append(f"  note: {n}")
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """Tidy: one row per cycle and cylinder: ``cycle`` and ``cylinder`` (both from 1),
        ``t_start_s``, ``mean_rpm``, ``scale``, ``scale_std``, ``imep_bar``, ``imep_std_bar``,
        ``identified``, ``contribution``, ``misfire``, ``load_torque_Nm``, ``load_std_Nm``."""
        import pandas as pd

        from ..units import RPM_PER_RAD_S

        C, n = self.scale.shape
        k = np.repeat(np.arange(C), n)
        t0 = np.full(C, np.nan) if self.t_start_s is None else np.asarray(self.t_start_s, dtype=np.float64)
        return pd.DataFrame(
            {
                "cycle": k + 1,
                "cylinder": np.tile(np.arange(1, n + 1), C),
                "t_start_s": t0[k],
                "mean_rpm": np.asarray(self.mean_omega)[k] * RPM_PER_RAD_S,
                "scale": self.scale.reshape(-1),
                "scale_std": self.scale_std.reshape(-1),
                "imep_bar": self.imep_pa.reshape(-1) / PA_PER_BAR,
                "imep_std_bar": self.imep_std_pa.reshape(-1) / PA_PER_BAR,
                "identified": self.identified.reshape(-1),
                "contribution": self.contribution.reshape(-1),
                "misfire": self.misfire.reshape(-1),
                "load_torque_Nm": np.asarray(self.load_torque_Nm)[k],
                "load_std_Nm": np.asarray(self.load_std_Nm)[k],
            }
        )

    def plot(self, ax: Any = None, kind: str | None = None) -> Any:
        """Speed (measured and the model's), the identified gas torque of each cylinder, and
        each cylinder's IMEP per cycle with the misfires marked
        (:func:`rotor.plotting.diagnostics.plot_identification`). ``kind``: None (the three
        panels on ``ax``, three Axes, or a new figure) or ``"speed"``, ``"torque"`` or
        ``"imep"`` (that panel alone on the one Axes ``ax``). Returns what it drew on."""
        return self._plot(ax, kind)

    def _plot(self, ax: Any, kind: str | None, title_end: str = "", measured_imep_pa: Any = None) -> Any:
        """:meth:`plot`, the title ending in ``title_end`` and with the IMEP a pressure
        channel measured per cycle [Pa] where given (:meth:`rotor.Diagnosis.plot`)."""
        from ..plotting.diagnostics import plot_identification

        return plot_identification(
            omega=self.omega,
            omega_model=self.omega_model,
            cylinder_torques=self.cylinder_torques(),
            imep_pa=self.imep_pa,
            imep_std_pa=self.imep_std_pa,
            misfire=self.misfire,
            title=f"{self.engine_name}: speed; rms residual {self.rms_residual:.3g} rad/s, R² {self.fit_r2:.4f}"
            + (" (poor fit)" if self.warnings else "")
            + title_end,
            measured_imep_pa=measured_imep_pa,
            ax=ax,
            kind=kind,
        )

    def to_json_dict(self) -> dict:
        """Plain JSON: the scales, IMEP [Pa], contributions, misfires and loads [N·m] per
        cycle and cylinder, and the fit; ``None``, never NaN."""
        return json_safe(
            {
                "engine": self.engine_name,
                "cycles": self.cycles,
                "cylinders": self.cylinders,
                "scale": self.scale,
                "scale_std": self.scale_std,
                "imep_pa": self.imep_pa,
                "imep_std_pa": self.imep_std_pa,
                "imep_cycle_std_pa": self.imep_cycle_std_pa,
                "identified": self.identified,
                "contribution": self.contribution,
                "misfire": self.misfire,
                "misfires": self.misfires(),
                "threshold": self.threshold,
                "load_torque_Nm": self.load_torque_Nm,
                "load_std_Nm": self.load_std_Nm,
                "rms_residual_rad_s": float(self.rms_residual),
                "r2": float(self.fit_r2),
                "relative_residual": float(self.relative_residual),
                "ambiguous_pairs": [list(p) for p in self.ambiguous_pairs],
                "warnings": list(self.warnings),
                "notes": list(self.notes),
            }
        )


def _count(n: int, noun: str) -> str:
    """``"1 cycle"``, ``"3 cycles"``."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


# ----------------------------------------------------------------------------- the model
class _Bases(eqx.Module):
    """Per-cycle pieces of the affine energy model, sampled at the P + 1 measurement angles.

    E_k(ψ_j) = φ_j·[E_k(0) + m_j − a_k·b_j + Σ_c (s_L,c·BL_jc + s_R,c·BR_jc)]."""

    phi: jnp.ndarray  # (P+1,)
    m: jnp.ndarray  # (P+1,)
    b: jnp.ndarray  # (P+1,)
    BL: jnp.ndarray  # (P+1, n)
    BR: jnp.ndarray  # (P+1, n)
    inertia: jnp.ndarray  # (P,)
    work_L: jnp.ndarray  # (n,) ∫|ΔM_c| over the nodes of the left / right part of the cycle
    work_R: jnp.ndarray
    offset_L: jnp.ndarray  # (n,) int: window offset of the cycle's left part


def _make_bases(train, c_loss, stride: int) -> _Bases:
    """The identification's bases (:class:`_Bases`) on every ``stride``-th node."""
    return _Bases(*_basis_arrays(train, c_loss, stride))


@kept_program(static_argnames=("stride",))
@eqx.filter_jit
def _basis_arrays(train, c_loss, stride: int):
    """:func:`_make_bases`'s arrays in one compiled call: a tuple, so that the program can be
    kept on disk (a module's structure does not come back from another process)."""
    v, d = wrap_periodic(train.values), wrap_periodic(train.slopes)
    h = train.step_rad
    inertia, dinertia, k, dk = v[:, COL_I], d[:, COL_I], v[:, COL_K], d[:, COL_K]
    G = 2 * (c_loss - k) / inertia
    dG = 2 * (-dk * inertia - (c_loss - k) * dinertia) / inertia**2
    phi = jnp.exp(-hermite_cumulative(G, dG, h))

    def basis(f, df):
        return hermite_cumulative(f / phi, (df + f * G) / phi, h)

    off = node_offsets(train)  # (N+1, n)
    left = off == off[0][None, :]
    dm, ddm = v[:, COL_COMBUSTION:], d[:, COL_COMBUSTION:]
    cols = jax.vmap(basis, in_axes=(1, 1), out_axes=1)
    BL = cols(jnp.where(left, dm, 0.0), jnp.where(left, ddm, 0.0))
    BR = cols(jnp.where(left, 0.0, dm), jnp.where(left, 0.0, ddm))
    absw = jnp.abs(dm[:-1]) * h
    s = slice(None, None, stride)
    return (
        phi[s],
        basis(v[:, COL_MOTORED], d[:, COL_MOTORED])[s],
        basis(jnp.ones_like(G), jnp.zeros_like(G))[s],
        BL[s],
        BR[s],
        inertia[:-1][s],
        jnp.sum(jnp.where(left[:-1], absw, 0.0), axis=0),
        jnp.sum(jnp.where(left[:-1], 0.0, absw), axis=0),
        off[0],
    )


def block_layout(work_L, work_R, offset_L, L: int):
    """Static parameter layout of a block of L cycles. Firings f = −1 … L of each cylinder
    whose combustion torque lies at least 1 % inside the block are fitted, each on its own;
    the others share the nearest fitted firing's scale. Returns the position of each
    firing's scale in the scale vector ((L+2, n) ints), which firings 0 … L−1 are
    identified (at least half inside: (L, n) bool), and the number of scale parameters."""
    n = work_L.size
    total = work_L + work_R
    frac = np.zeros((L + 2, n))
    for c in range(n):
        for k in range(L):
            frac[k + offset_L[c] + 1, c] += work_L[c] / total[c]
            frac[k + offset_L[c] + 2, c] += work_R[c] / total[c]
    own = frac[1 : L + 1] >= TIED_BELOW
    for c in range(n):
        if not own[:, c].any():
            own[int(np.argmax(frac[1 : L + 1, c])), c] = True
    fitted = frac >= FITTED_FROM
    fitted[1 : L + 1] |= own
    pos = np.zeros((L + 2, n), np.int32)
    index = -np.ones((L + 2, n), np.int64)
    count = 0
    for f in range(L + 2):
        for c in range(n):
            if fitted[f, c]:
                index[f, c] = count
                count += 1
    for c in range(n):
        rows = np.flatnonzero(fitted[:, c])
        for f in range(L + 2):
            pos[f, c] = index[rows[np.argmin(np.abs(rows - f))], c]
    return pos, own, count


def _energy(p, bases, pos, offset_L, e_ref, a_ref, L: int, na: int):
    """E on the P + 1 samples of each of the block's L cycles, (L, P+1); ``na`` load
    parameters: one per cycle (L) or one for the block (1)."""
    n = pos.shape[1]
    s_full = p[1 + na :][pos]  # (L+2, n)
    cyl = jnp.arange(n)

    def cycle(E0, k):
        sL = s_full[k + offset_L + 1, cyl]
        sR = s_full[k + offset_L + 2, cyl]
        inner = E0 + bases.m - a_ref * p[1 + jnp.minimum(k, na - 1)] * bases.b + bases.BL @ sL + bases.BR @ sR
        E = bases.phi * inner
        return E[-1], E

    _, E = jax.lax.scan(cycle, e_ref * p[0], jnp.arange(L))
    return E


def _sandwich(J, r, npar, bins: int):
    """Covariance of least-squares parameters under stationary, coloured residual noise:
    (JᵀJ)⁻¹·JᵀΣJ·(JᵀJ)⁻¹, JᵀΣJ = (1/m)·Σ_f S(f)·Re(Ĵ(f)ᴴĴ(f)) with S the residual's
    (Hann-tapered) periodogram smoothed over ±``bins`` frequency bins, times m/(m − p). With white noise
    this is σ²·(JᵀJ)⁻¹; a speed from tooth times has noise that grows with the order (the
    derivative of the timer's jitter) and little of it at the low orders that carry the
    scales, which σ²·(JᵀJ)⁻¹ would overstate several times."""
    m = r.shape[0]
    hann = 0.5 - 0.5 * jnp.cos(2 * jnp.pi * (jnp.arange(m) + 0.5) / m)  # tapered: no leakage from the high orders
    R = jnp.fft.rfft(r * hann)
    power = jnp.abs(R) ** 2 / jnp.sum(hann**2)
    kernel = jnp.ones(2 * bins + 1)
    pad = jnp.concatenate([power[1 : bins + 1][::-1], power, power[-bins - 1 : -1][::-1]])
    S = jnp.convolve(pad, kernel, mode="valid") / (2 * bins + 1)
    w = jnp.full(S.shape, 2.0).at[0].set(1.0)
    if m % 2 == 0:
        w = w.at[-1].set(1.0)
    Jf = jnp.fft.rfft(J, axis=0)
    meat = jnp.real(jnp.einsum("f,fi,fj->ij", w * S, jnp.conj(Jf), Jf)) / m * (m / (m - npar))
    A = J.T @ J
    d = jnp.sqrt(jnp.diag(A))
    Ai = jnp.linalg.inv(A / jnp.outer(d, d)) / jnp.outer(d, d)
    return Ai @ meat @ Ai


def _normal_solve(A, y):
    """Least squares min ‖A·x − y‖ by the column-scaled normal equations (Cholesky)."""
    d = jnp.sqrt(jnp.sum(A * A, axis=0))
    d = jnp.where(d > 0, d, 1.0)
    As = A / d
    chol = jax.scipy.linalg.cho_factor(As.T @ As)
    return jax.scipy.linalg.cho_solve(chol, As.T @ y) / d


@kept_program(static_argnames=("rtol", "nscale", "na", "max_steps"))
@eqx.filter_jit
def _fit_blocks(bases, omega, pos, offset_L, a_ref, rtol, nscale: int, na: int, max_steps: int):
    """Fit every block of omega (B, L, P): returns the parameters, covariances, residuals."""
    L, P = omega.shape[1], omega.shape[2]

    def one(w):
        e_meas = 0.5 * bases.inertia * w**2
        e_ref = e_meas[0, 0]
        npar = 1 + na + nscale

        def E_flat(p):
            return _energy(p, bases, pos, offset_L, e_ref, a_ref, L, na)[:, :-1].reshape(-1)

        # E is affine in the parameters, E = E(0) + X·p: exact linear least squares in E, each
        # sample weighted by 1/(I·ω) (the speed error it makes), then the speed residual
        # √(2E/I) − ω from the same X (the model's ω without its recurrence in the solver)
        zero = jnp.zeros(npar)
        E_zero, X = E_flat(zero), jax.jacfwd(E_flat)(zero)
        inertia = jnp.tile(bases.inertia, L)
        wt = 1.0 / (inertia * w.reshape(-1))
        p0 = _normal_solve(X * wt[:, None], (e_meas.reshape(-1) - E_zero) * wt)

        def resid(p, args):
            return jnp.sqrt(2 * jnp.maximum(E_zero + X @ p, 1e-300) / inertia) - w.reshape(-1)

        # normal equations (Cholesky): the parameters are scaled to O(1), JᵀJ is small and well conditioned,
        # and a QR of the tall Jacobian costs ~1 s on CPU
        solver = optx.LevenbergMarquardt(rtol=rtol, atol=rtol, linear_solver=lx.Normal(lx.Cholesky()))
        sol = optx.least_squares(resid, solver, p0, max_steps=max_steps, throw=False)
        p = sol.value
        r = resid(p, None)
        J = jax.jacfwd(resid)(p, None)
        cov = _sandwich(J, r, npar, L)  # L bins of the block's spectrum: one per cycle, ½ order (four-stroke)
        return p, cov, r.reshape(L, P), sol.stats["num_steps"], e_ref, sol.result == optx.RESULTS.successful

    return jax.vmap(one)(omega)


# ----------------------------------------------------------------------------- inputs
def _speed(engine, speed, cycle_rad):
    from ..dynamics.result import SpeedResult
    from ..logs.analysis import LogAnalysis, PhaseSource

    t_start = None
    phase = None
    if isinstance(speed, SpeedResult):
        if not math.isclose(float(speed.cycle_rad), float(engine.cycle_rad), rel_tol=1e-9):
            raise EngineError(
                f"speed (a SpeedResult): its {math.degrees(speed.cycle_rad):g}° cycle does not fit the "
                f"{engine.strokes}-stroke engine {engine.name!r}"
            )
        C, P = speed.uniform_cycles, speed.points_per_cycle
        if C < 1:
            raise EngineError("speed (a SpeedResult) holds no complete cycle sampled in the angle domain")
        omega = np.asarray(speed.omega)[: C * P].reshape(C, P)
        t_start = np.asarray(speed.t)[: C * P : P]
        phase = True
    elif isinstance(speed, LogAnalysis):
        if not math.isclose(float(speed.cycle_rad), float(engine.cycle_rad), rel_tol=1e-9):
            raise EngineError(
                f"speed (a LogAnalysis): its {math.degrees(speed.cycle_rad):g}° cycle does not fit the "
                f"{engine.strokes}-stroke engine {engine.name!r}"
            )
        starts = np.asarray(speed.cycle_start_rad)
        if starts.size > 1 and not np.allclose(np.diff(starts), speed.cycle_rad, rtol=0, atol=1e-9):
            raise EngineError("speed (a LogAnalysis): its cycles are not consecutive")
        if speed.tdc_source is PhaseSource.UNKNOWN:
            raise EngineError(
                "speed (a LogAnalysis): its cycles do not start at TDC (TDC unknown); give tdc_deg or a "
                "pressure channel to analyze_log"
            )
        omega = np.asarray(speed.omega, dtype=np.float64)
        t_start = np.asarray(speed.t_start_s)
        phase = speed.firing_source is not PhaseSource.SPEED
    else:
        if isinstance(speed, jax.core.Tracer):
            raise EngineError("speed: identify works on concrete arrays (it is not traceable)")
        if cycle_rad is not None and not math.isclose(float(cycle_rad), float(engine.cycle_rad), rel_tol=1e-9):
            raise EngineError(f"cycle_rad = {cycle_rad!r} does not fit the {engine.strokes}-stroke engine")
        try:
            omega = np.asarray(speed, dtype=np.float64)
        except (TypeError, ValueError):
            raise EngineError(
                f"speed: a LogAnalysis, a SpeedResult or an array (cycles, points), not {type(speed).__name__}"
            ) from None
        if omega.ndim == 1:
            omega = omega[None, :]
        if omega.ndim != 2:
            raise EngineError(
                f"speed has shape {np.shape(speed)}: needs (cycles, points) on the uniform cycle-angle "
                f"grid of consecutive cycles (0 = TDC of cylinder 1 before intake)"
            )
    if omega.shape[0] < 1 or omega.shape[1] < 16:
        raise EngineError(f"speed has shape {omega.shape}: needs at least one cycle of 16 or more points")
    if not np.all(np.isfinite(omega)):
        bad = np.argwhere(~np.isfinite(omega))[0]
        raise EngineError(f"speed is not finite (NaN or inf) at cycle {bad[0]}, point {bad[1]}")
    if np.any(omega <= 0):
        raise EngineError(
            f"speed must be positive everywhere (the crankshaft turning forwards); its minimum is {omega.min():g} rad/s"
        )
    return omega, t_start, phase


def _losses(engine, friction, load):
    fa, fb, fc = (float(x) for x in np.asarray(friction_coefficients(engine, friction)))
    if fb != 0:
        raise EngineError(
            "identify needs friction of the form a + c·ω² (its closed form); this friction has a "
            "speed-linear term: give friction=rotor.Friction(...) without fmep_per_speed, or False"
        )
    c_load = 0.0
    if load is not None:
        if not isinstance(load, Load):
            try:
                load = ConstantLoad(float(load))
            except (TypeError, ValueError):
                raise EngineError(
                    f"load = {load!r}: None (an unknown constant per cycle) or a rotor load model "
                    f"(ConstantLoad, PolynomialLoad, PropellerLoad)"
                ) from None
        poly = None if load.time_dependent else load.polynomial()
        if poly is None or (poly[1] is not None and float(poly[1]) != 0):
            raise EngineError(
                f"load = {type(load).__name__}: identify takes a load of the form a + c·ω² (ConstantLoad, "
                f"PolynomialLoad with b = 0, PropellerLoad); its constant part is fitted per cycle"
            )
        c_load = 0.0 if poly[2] is None else float(poly[2])
    return fa, fc, c_load


def symmetric_pairs(engine):
    """Cylinder pairs (numbered from 1) that a shift of 360° maps onto each other in a
    four-stroke engine: same TDC crank angle, firing 360° apart. () if not every
    cylinder has such a partner (then the crank speed carries the phase)."""
    if engine.strokes != 4:
        return ()
    tdc = np.mod(np.asarray(engine.tdc_angles_deg, dtype=np.float64), 360.0)
    fire = np.mod(np.rad2deg(np.asarray(engine.firing_angles_rad)), 720.0)
    n = tdc.size
    partner = []
    for c in range(n):
        m = [
            j
            for j in range(n)
            if j != c
            and abs((np.mod(tdc[j] - tdc[c] + 180, 360)) - 180) < 1e-6
            and abs(np.mod(fire[j] - fire[c], 720) - 360) < 1e-6
        ]
        if not m:
            return ()
        partner.append(m[0])
    return tuple(sorted({tuple(sorted((c + 1, p + 1))) for c, p in enumerate(partner)}))


def _check_arguments(
    engine, parameters, fidelity, block_cycles, overlap, max_steps, threshold, misfire_floor, load_per, rtol
):
    """TypeError or :class:`rotor.EngineError` naming the argument of :func:`identify` that cannot be used."""
    from ..engine.model import Engine as EngineType

    if not isinstance(engine, EngineType):
        hint = " (load it first: rotor.load_engine(...))" if isinstance(engine, str) else ""
        raise TypeError(f"identify(engine): expected a rotor.Engine{hint}, got {type(engine).__name__} {engine!r:.60}")
    if parameters not in PARAMETERS:
        raise EngineError(
            f"parameters = {parameters!r}: only 'imep_scale' (one combustion scale per firing) is "
            f"implemented; Wiebe start, Wiebe duration and a pressure scale are not"
        )
    check_fidelity(fidelity, engine)
    for name, v, lo in (("block_cycles", block_cycles, 1), ("overlap", overlap, 0), ("max_steps", max_steps, 1)):
        if not (isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= lo):
            raise EngineError(f"{name} = {v!r}: must be a whole number, {lo} or more")
    if not (isinstance(threshold, (int, float, np.floating)) and 0 < threshold < 1):
        raise EngineError(f"threshold = {threshold!r}: must lie between 0 and 1 (a fraction of a normal firing)")
    if not (isinstance(misfire_floor, (int, float, np.floating)) and 0 < misfire_floor < 1):
        raise EngineError(f"misfire_floor = {misfire_floor!r}: must lie between 0 and 1 (a combustion scale)")
    if load_per not in ("cycle", "block"):
        raise EngineError(f"load_per = {load_per!r}: 'cycle' (an unknown load torque in every cycle) or 'block'")
    if not (np.isfinite(rtol) and 0 < rtol < 1e-2):
        raise EngineError(f"rtol = {rtol!r}: must lie between 0 and 1e-2")


def _blocks(C: int, block_cycles: int, overlap: int) -> tuple[int, np.ndarray, list[tuple[int, int]]]:
    """The blocks of a record of ``C`` cycles: cores of ``block_cycles``, ``overlap`` on each
    side, clamped to the record: the cycles per block, each block's first cycle and each
    core's (first, end) cycles."""
    L = min(C, block_cycles + 2 * overlap)
    nb = int(math.ceil(C / block_cycles)) if C > L else 1
    if nb == 1:
        return L, np.array([0]), [(0, C)]
    cores = [(b * block_cycles, min((b + 1) * block_cycles, C)) for b in range(nb)]
    return L, np.array([int(np.clip(c0 - overlap, 0, C - L)) for c0, _ in cores]), cores


def _per_cycle(fitted, cores, starts, pos, own, na, a_ref, shape):
    """Each cycle's figures from its block's fit (the block whose core holds it): scale,
    its σ, the load torque and its σ, the covariance, which firings are identified, the residual."""
    p, cov, res = fitted
    C, P, n = shape
    scale = np.zeros((C, n))
    scale_std = np.zeros((C, n))
    load_a = np.zeros(C)
    load_sd = np.zeros(C)
    covs = np.zeros((C, n + 1, n + 1))
    ident = np.zeros((C, n), bool)
    resid = np.zeros((C, P))
    for b, ((c0, c1), s0) in enumerate(zip(cores, starts)):
        for k in range(c0, c1):
            j = k - s0
            ja = 1 + min(j, na - 1)
            idx = np.concatenate([1 + na + pos[j + 1], [ja]])
            sub = cov[b][np.ix_(idx, idx)]
            unit = np.concatenate([np.ones(n), [a_ref]])
            covs[k] = sub * np.outer(unit, unit)
            scale[k] = p[b][1 + na + pos[j + 1]]
            scale_std[k] = np.sqrt(np.diag(covs[k])[:n])
            load_a[k] = p[b][ja] * a_ref
            load_sd[k] = math.sqrt(covs[k][n, n])
            ident[k] = own[j]
            resid[k] = res[b][j]
    return scale, scale_std, load_a, load_sd, covs, ident, resid


def _notes(ident, ok, pairs, misfire) -> list[str]:
    """What the fit says of itself: firings cut by the record's end, blocks that did not
    converge, cylinders the crank speed cannot tell apart, no firing at all."""
    notes = []
    if not ident.all():
        cut = [(int(k) + 1, int(c) + 1) for k, c in np.argwhere(~ident)]
        notes.append(
            f"firings {cut} (cycle, cylinder) lie mostly outside the record: each shares the scale of the "
            f"nearest firing of its cylinder (not identified on its own)"
        )
    if not np.all(ok):
        notes.append(
            "the Levenberg–Marquardt iteration did not converge in every block (max_steps); the linear "
            "start stands there"
        )
    if pairs:
        names = ", ".join(f"{a} and {b}" for a, b in pairs)
        notes.append(
            f"the firing revolution is not known from a phase reference (pressure, cam or given), and this "
            f"engine is symmetric under 360°: cylinders {names} cannot be told apart from the crank speed "
            f"alone; a result for one of a pair may belong to the other (give a cam or pressure channel, "
            f"firing=0/1 to analyze_log, or phase_reference=True)"
        )
    if np.all(misfire[ident]) and ident.any():
        notes.append(NO_FIRING_NOTE)
    return notes


# ----------------------------------------------------------------------------- entry point
def _fit_padded(bases, blocks, pos, offset_L, a_ref, rtol, nscale, na, max_steps):
    """:func:`_fit_blocks` of the list ``blocks`` of speed blocks (cycles, P) [rad/s], as many
    as a standard size (the last repeated, its fits dropped): a record of another length
    reuses the compiled fit; each block's fit is its own, so nothing changes. ``a_ref`` [N·m]
    is traced: a new combustion does not recompile. Returns the fits of ``blocks`` as NumPy."""
    nb = len(blocks)
    stacked = np.stack(blocks + [blocks[-1]] * (padded_size(nb) - nb))
    fits = _fit_blocks(
        bases,
        jnp.asarray(stacked),
        jnp.asarray(pos),
        jnp.asarray(offset_L),
        jnp.asarray(a_ref),
        rtol,
        nscale,
        na,
        max_steps,
    )
    return tuple(a[:nb] for a in jax.device_get(fits))


def identify(
    engine: Engine | PreparedEngine,
    speed: LogAnalysis | SpeedResult | ArrayLike,
    *,
    load: Load | float | None = None,
    friction: Friction | bool | None = None,
    parameters: str = "imep_scale",
    fidelity: str = "variable",
    grid_deg: float = 0.25,
    block_cycles: int = DEFAULT_BLOCK,
    overlap: int = DEFAULT_OVERLAP,
    load_per: str = "cycle",
    threshold: float = MISFIRE_THRESHOLD,
    misfire_floor: float = FLOOR_SCALE,
    phase_reference: bool | None = None,
    cycle_rad: float | None = None,
    rtol: float = 1e-6,
    max_steps: int = 50,
) -> Identification:
    """Identify each firing's combustion scale (and IMEP), the load and the misfires from ω(θ).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine` or a :class:`rotor.PreparedEngine` (its tables: inertia, motored and combustion torque).
    - ``speed``: the crank speed on the uniform cycle-angle grid of consecutive cycles
      (0 = TDC of cylinder 1 before intake): a :class:`rotor.LogAnalysis`, a
      :class:`rotor.SpeedResult` (its uniformly sampled cycles) or an array (cycles, P)
      [rad/s].
    - ``load``: None (default: an unknown constant torque per cycle) or a load model
      a + c·ω² (:class:`rotor.PropellerLoad`, :class:`rotor.PolynomialLoad` with b = 0,
      :class:`rotor.ConstantLoad`): its c·ω² shape is used, its constant part is fitted per
      cycle.
    - ``load_per``: ``"cycle"`` (default): the load's constant part is unknown in every
      cycle; ``"block"``: one unknown constant per block of cycles, for a steady load (the
      cycles' mean speeds then pin each cycle's mean combustion, which the per-cycle load
      leaves to the firing-order fluctuation alone).
    - ``friction``: a :class:`rotor.Friction`, None (the engine file's) or False; a + c·ω².
    - ``parameters``: ``"imep_scale"`` (one combustion scale per firing).
    - ``fidelity``, ``grid_deg``: of the tables (:func:`rotor.dynamics.crank_train`); the tables'
      nodes are refined so that the P samples of a cycle fall on nodes.
    - ``block_cycles``, ``overlap``: cycles per block core, and the cycles added on each
      side (see the module doc).
    - ``threshold``, ``misfire_floor``: of the misfire index (:mod:`rotor.diagnostics.misfire`).
    - ``phase_reference``: whether the grid's cycle is known to start at cylinder 1's
      intake TDC (not 360° off); default: True for a SpeedResult or an array, from the
      firing revolution's method for a LogAnalysis (found from the speed: False).
    - ``cycle_rad``: the cycle of an array ``speed`` [rad] (checked against the engine).
    - ``rtol``, ``max_steps``: of the Levenberg–Marquardt iteration (rtol 1e-6 of the
      parameters, all of order 1, lies far below their noise: 3 steps from the linear
      start; 1e-10 gave the same scales to 1e-9 in 2–3× the steps).

    **Returns:** :class:`Identification`. Raises :class:`rotor.EngineError` for input that
    cannot be identified.
    """
    engine = resolve_engine(engine)  # a prepared engine: its tables are reused
    wall = time.perf_counter()
    _check_arguments(
        engine, parameters, fidelity, block_cycles, overlap, max_steps, threshold, misfire_floor, load_per, rtol
    )
    omega, t_start, phase_known = _speed(engine, speed, cycle_rad)
    C, P = omega.shape
    fa, fc, c_load = _losses(engine, friction, load)
    base_n = grid_points(engine.strokes, grid_deg)
    N = P * max(1, int(math.ceil(base_n / P)))
    train = train_from_engine(engine, fidelity, N)
    n = train.cylinders
    comb = np.asarray(train.imep_combustion_pa)
    if not np.all(comb > 0):
        raise EngineError(
            f"engine {engine.name!r}: cylinder(s) {list(np.flatnonzero(~(comb > 0)) + 1)} have no "
            f"combustion in the engine's pressure (fired = motored): nothing to identify"
        )
    bases = _make_bases(train, jnp.asarray(fc + c_load), N // P)
    work_L, work_R, offset_L = (np.asarray(x) for x in (bases.work_L, bases.work_R, bases.offset_L))

    L, starts, cores = _blocks(C, block_cycles, overlap)
    nb = len(cores)
    pos, own, nscale = block_layout(work_L, work_R, offset_L, L)
    na = L if load_per == "cycle" else 1
    vh = float(engine.geometry.displacement_m3)
    a_ref = float(np.sum(comb)) * vh / float(engine.cycle_rad)  # the engine file's mean combustion torque
    p, cov, res, steps, e_ref, ok = _fit_padded(
        bases, [omega[s0 : s0 + L] for s0 in starts], pos, offset_L, a_ref, rtol, nscale, na, max_steps
    )

    scale, scale_std, load_a, load_sd, covs, ident, resid = _per_cycle(
        (p, cov, res), cores, starts, pos, own, na, a_ref, (C, P, n)
    )
    imep_m = np.asarray(train.imep_motored_pa)
    imep = imep_m[None, :] + scale * comb[None, :]
    model = omega + resid
    mean_w2 = np.mean(omega**2, axis=1)
    loss = load_a + fc * mean_w2 + c_load * mean_w2
    load_t = load_a - fa + c_load * mean_w2
    fluct = omega - omega.mean(axis=1, keepdims=True)
    ss_res, ss_tot = np.sum(resid**2, axis=1), np.sum(fluct**2, axis=1)
    index, misfire, ref = contribution_index(scale, scale_std, threshold=threshold, floor=misfire_floor, valid=ident)
    if phase_reference is None:
        phase_reference = True if phase_known is None else phase_known
    pairs = () if phase_reference else symmetric_pairs(engine)
    notes = _notes(ident, ok, pairs, misfire)
    return Identification(
        scale=scale,
        scale_std=scale_std,
        imep_pa=imep,
        imep_std_pa=scale_std * comb[None, :],
        identified=ident,
        contribution=index,
        misfire=misfire,
        reference_scale=ref,
        load_torque_Nm=load_t,
        load_std_Nm=load_sd,
        loss_torque_Nm=loss,
        mean_omega=omega.mean(axis=1),
        covariance=covs,
        rms_residual_rad_s=np.sqrt(np.mean(resid**2, axis=1)),
        r2=1 - ss_res / ss_tot,
        omega=omega,
        omega_model=model,
        rms_residual=float(np.sqrt(np.mean(resid**2))),
        fit_r2=float(1 - ss_res.sum() / ss_tot.sum()),
        relative_residual=float(np.sqrt(ss_res.sum() / ss_tot.sum())),
        imep_nominal_pa=imep_m + comb,
        threshold=float(threshold),
        ambiguous_pairs=pairs,
        t_start_s=t_start,
        notes=tuple(notes),
        engine=engine,
        engine_name=engine.name,
        wall_s=time.perf_counter() - wall,
        blocks=int(nb),
        block_cycles=int(L),
        block_starts=tuple(int(x) for x in starts),
        iterations=tuple(int(x) for x in np.asarray(steps).reshape(-1)),
        table_points=int(N),
        load_per=load_per,
    )
