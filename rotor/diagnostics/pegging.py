"""The pressure channel's gain and offset from motored cycles (pressure pegging).

A piezoelectric cylinder-pressure sensor gives a signal u = (p − b)/g whose gain g and
offset b are rarely known: the charge amplifier drifts, and a recording may come without
the sensor's data sheet. A **motored** cycle (no combustion: a motored stretch, an
ignition cut, a fuel cut) compresses its charge polytropically, p·V^n constant from the
closing of the intake valve to TDC, with n about 1.3 (1.3 ± 0.05 on the log p – log V
diagram of a cycle; Heywood, *Internal Combustion Engine Fundamentals*, on the
measurement and analysis of cylinder pressure). So over the compression

    u(θ) = α·(V_BDC/V(θ))^n + β,

linear in α and β (V from the engine's geometry and compression ratio, n the engine
file's ``compression_exponent``, else 1.3; TDC where this fit puts it, within 5° of the
recording's, since a TDC 0.7° off already moves the gain by 1.5 %): the shape fixes the offset in signal units,
β, but not the gain: a gain and a pressure level too large by the same factor give the
same trace. The gain needs one absolute pressure: the cylinder pressure at the start of
the compression equals the intake manifold's (the usual pegging of a pressure trace,
Heywood, ibid.; Randolph, "Methods of processing cylinder-pressure transducer signals to
maximize data accuracy", SAE 900170), ``intake_pa`` (default: the engine file's).
Then g = p_intake/α and b = −g·β.

**Which cycles are motored**: a fired cycle's expansion lies well above its compression
at the same volume; a motored one's a little below (heat loss). A cycle whose signal
10–60° after firing TDC exceeds the one as far before by less than :data:`MOTORED_RISE`
of its compression's rise (BDC to 10° before TDC) is motored.

**Accuracy and limits**: the gain is as good as the intake pressure: a throttled engine's
manifold pressure changes with the throttle, so give ``intake_pa`` for the motored
stretch's (a manifold pressure sensor) where it is not the engine file's operating
point. The compression is taken to start at BDC, as the engine files' single-zone cycles
have it; a real engine closes its intake 30–60° after BDC, with the charge near the
manifold pressure there, so the window fitted (:data:`WINDOW_DEG`, before TDC) starts
later and the polytrope is anchored at BDC. On simulated recordings (the engine file's
single-zone cycle, the bench sensor's noise, two motored cycles) the gain came back within
0.0–0.7 % (``tests/diagnostics/test_calibrate_cli.py`` holds 1 %): the recorded angle of each pressure
sample, read off the wheel, leaves the compression about 0.7 % low at the angles the
engine's TDC puts it, the limit of this pegging rather than its noise.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import EngineError
from ..logs.analysis import LogAnalysis
from ..results import Result, json_safe

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = [
    "MotoredGain",
    "binned_pressure",
    "motored_cycles",
    "pressure_gain_from_motored",
    "DEFAULT_EXPONENT",
    "MOTORED_RISE",
    "WINDOW_DEG",
]

DEFAULT_EXPONENT = 1.3
"""The compression's polytropic exponent where the engine file gives none [-] (Heywood)."""
MOTORED_RISE = 0.15
"""A cycle whose expansion exceeds its compression by less than this fraction of the
compression's rise is motored [-]."""
WINDOW_DEG = (100.0, 20.0)
"""The compression fitted: from this many degrees before firing TDC to this many [deg]
(after any intake valve closing, before the heat loss and blow-by near TDC)."""
BIN_DEG = 0.5
SHIFT_MAX_DEG = 5.0  # TDC as the compression puts it: searched within ± this of the recording's [deg]
SHIFT_STEP_DEG = 0.1


def binned_pressure(analysis: LogAnalysis, step_deg: float = BIN_DEG) -> tuple[np.ndarray, np.ndarray]:
    """Each complete cycle's pressure signal averaged in bins of ``step_deg`` [deg]: (bin
    centres [rad] from the cycle's start, (cycles, bins) [signal units]). Empty bins are
    interpolated within the cycle. Raises :class:`rotor.EngineError` without a pressure
    channel or with too few samples."""
    if analysis.pressure is None:
        raise EngineError(f"{analysis.source}: no pressure channel in the recording (a column pressure_v)")
    ph, pv, cyc = analysis.pressure
    step = np.deg2rad(step_deg)
    nb = int(round(analysis.cycle_rad / step))
    centres = (np.arange(nb) + 0.5) * analysis.cycle_rad / nb
    out = np.empty((analysis.cycles, nb))
    b_all = np.clip((ph / analysis.cycle_rad * nb).astype(int), 0, nb - 1)
    for k in range(analysis.cycles):
        m = cyc == k
        n = np.bincount(b_all[m], minlength=nb)
        if np.count_nonzero(n) < nb // 2:
            raise EngineError(
                f"{analysis.source}: cycle {k} has pressure samples in only {np.count_nonzero(n)} of "
                f"{nb} bins of {step_deg:g}°: sample the pressure faster"
            )
        s = np.bincount(b_all[m], weights=pv[m], minlength=nb)
        ok = n > 0
        out[k] = np.interp(centres, centres[ok], s[ok] / n[ok], period=analysis.cycle_rad)
    return centres, out


def _at(centres, sig, angle_rad):
    return np.array([np.interp(angle_rad, centres, row) for row in sig])


def motored_cycles(analysis: LogAnalysis) -> np.ndarray:
    """Which complete cycles of a four-stroke recording (cycles starting at TDC before
    intake, firing TDC at 360°) are motored, from the pressure signal's shape (see the
    module doc): (cycles,) bool. Any gain and offset."""
    if analysis.strokes != 4:
        raise EngineError(f"{analysis.source}: motored cycles are found in four-stroke recordings")
    centres, sig = binned_pressure(analysis)
    tdc = np.pi * 2
    after = np.deg2rad(np.arange(10.0, 61.0, 2.0))
    rise = np.mean(_at(centres, sig, tdc + after) - _at(centres, sig, tdc - after), axis=1)
    comp = _at(centres, sig, [tdc - np.deg2rad(10.0)])[:, 0] - _at(centres, sig, [np.pi])[:, 0]
    return (comp > 0) & (rise < MOTORED_RISE * comp)


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class MotoredGain(Result):
    """The pressure channel's scale from motored cycles (see the module doc).

    **Fields:** ``gain_pa`` [Pa per signal unit] and ``offset_pa`` [Pa] (p = gain·u +
    offset); ``cycles`` (the motored cycles used, indices among the complete ones);
    ``exponent`` (n) [-]; ``intake_pa`` (the pressure at BDC pegged to) [Pa];
    ``window_deg`` (the compression fitted, degrees before firing TDC); ``r2`` (of the
    polytropic fit of the cycles' mean signal) [-]; ``rms_pa`` (its residual) [Pa];
    ``tdc_shift_deg`` (where the compression puts TDC, after the recording's) [deg];
    ``volume_ratio`` (V/V_BDC over the window) [-] and ``pressure_pa`` (the cycles' mean
    pressure there, with the gain and offset found) [Pa], for the plot.
    """

    gain_pa: float
    offset_pa: float
    cycles: tuple[int, ...]
    exponent: float
    intake_pa: float
    window_deg: tuple[float, float]
    r2: float
    rms_pa: float
    tdc_shift_deg: float
    volume_ratio: np.ndarray
    pressure_pa: np.ndarray

    def plot(self, ax: Any = None) -> Any:
        """The motored compression on log p – log V axes with the polytrope fitted, on ``ax``
        (or a new figure) (:func:`rotor.plotting.diagnostics.plot_motored_gain`). Returns the Axes."""
        from ..plotting.diagnostics import plot_motored_gain

        return plot_motored_gain(
            volume_ratio=self.volume_ratio,
            pressure_pa=self.pressure_pa,
            exponent=self.exponent,
            intake_pa=self.intake_pa,
            title=f"pressure gain from {len(self.cycles)} motored cycle{'s' if len(self.cycles) != 1 else ''}: "
            f"{self.gain_pa / 1e5:.4g} bar per unit, R² {self.r2:.4f}",
            ax=ax,
        )

    def summary(self) -> str:
        """One line: the gain and offset, from which cycles, how well."""
        return (
            f"pressure = {self.gain_pa / 1e5:.4g} bar × signal {'+' if self.offset_pa >= 0 else '−'} "
            f"{abs(self.offset_pa) / 1e5:.4g} bar, from {len(self.cycles)} motored cycle"
            f"{'s' if len(self.cycles) != 1 else ''} (p·V^{self.exponent:.3g} constant, pegged at "
            f"{self.intake_pa / 1e5:.3g} bar at BDC; R² {self.r2:.4f})\n"
        )

    def to_json_dict(self) -> dict:
        """The figures (not the plot's arrays); ``None``, never NaN."""
        skip = ("volume_ratio", "pressure_pa")
        return json_safe({f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in skip})

    def to_pandas(self) -> Any:
        """One row of the figures."""
        import pandas as pd

        d = self.to_json_dict()
        d["cycles"] = ",".join(str(c) for c in self.cycles)
        d["window_deg"] = f"{self.window_deg[0]:g}–{self.window_deg[1]:g}"
        return pd.DataFrame([d])


def pressure_gain_from_motored(
    engine: Engine,
    analysis: LogAnalysis,
    *,
    intake_pa: float | None = None,
    exponent: float | None = None,
    cycles: Any = None,
) -> MotoredGain:
    """The gain and offset of the pressure channel from the recording's motored cycles.

    **Arguments:**
    - ``engine``: the :class:`rotor.Engine` (geometry, compression ratio; its pressure's
      ``compression_exponent`` and ``intake_pa`` as defaults).
    - ``analysis``: a four-stroke :class:`rotor.LogAnalysis` with a pressure channel and
      TDC (cycles from TDC before intake).
    - ``intake_pa``: the intake manifold pressure during the motored cycles [Pa] (default
      the engine file's ``intake_pa``).
    - ``exponent``: the compression's polytropic exponent n [-] (default the engine
      file's, else :data:`DEFAULT_EXPONENT`).
    - ``cycles``: which complete cycles to use (indices), default those
      :func:`motored_cycles` finds.

    **Returns:** :class:`MotoredGain`. **Raises** :class:`rotor.EngineError` (one line)
    where the recording has no motored cycle, the engine no compression ratio or intake
    pressure, or the fit gives no positive gain.
    """
    from ..engine.pressure import cylinder_volume_m3

    cr = getattr(engine.pressure, "compression_ratio", None)
    if cr is None:
        raise EngineError(
            f"engine {engine.name!r}: its pressure ({type(engine.pressure).__name__}) has no compression ratio "
            f"for the polytropic compression"
        )
    if intake_pa is None:
        intake_pa = getattr(engine.pressure, "intake_pa", None)
        if intake_pa is None:
            raise EngineError(
                f"engine {engine.name!r}: no intake pressure in its file: give intake_pa= for the pegging"
            )
    intake_pa = float(intake_pa)
    if not (np.isfinite(intake_pa) and intake_pa > 0):
        raise EngineError(f"intake_pa = {intake_pa!r}: a positive pressure [Pa]")
    if exponent is None:
        exponent = float(getattr(engine.pressure, "compression_exponent", DEFAULT_EXPONENT))
    n = float(exponent)
    if not 1.0 <= n <= 2.0:
        raise EngineError(f"exponent = {exponent!r}: a polytropic exponent lies in 1…2")
    if cycles is None:
        sel = np.flatnonzero(motored_cycles(analysis))
        if sel.size == 0:
            raise EngineError(
                f"{analysis.source}: no motored cycle (every one of the {analysis.cycles} complete cycles fires): "
                f"the pressure gain cannot be found from a motored stretch; give it (pressure_gain=PA_PER_UNIT)"
            )
    else:
        sel = np.unique(np.asarray(cycles, dtype=int).reshape(-1))
        if sel.size == 0 or sel.min() < 0 or sel.max() >= analysis.cycles:
            raise EngineError(f"cycles = {cycles!r}: indices among the {analysis.cycles} complete cycles")
    centres, sig = binned_pressure(analysis)
    u = np.mean(sig[sel], axis=0)
    lo, hi = 2 * np.pi - np.deg2rad(WINDOW_DEG[0]), 2 * np.pi - np.deg2rad(WINDOW_DEG[1])
    w = (centres >= lo) & (centres <= hi)
    geo = engine.geometry
    v_bdc = float(np.asarray(cylinder_volume_m3(np.pi, geo, float(cr))))

    def fit(shift_rad):
        v = np.asarray(cylinder_volume_m3(centres[w] - shift_rad, geo, float(cr)), dtype=np.float64)
        X = np.column_stack([(v_bdc / v) ** n, np.ones(v.size)])
        coef, *_ = np.linalg.lstsq(X, u[w], rcond=None)
        r = u[w] - X @ coef
        return float(np.sum(r**2)), coef, r, v

    # TDC as the compression itself puts it (the recording's TDC may lie a little off): the shift
    # that fits best within ±SHIFT_MAX_DEG, refined between grid points by a parabola
    shifts = np.deg2rad(np.arange(-SHIFT_MAX_DEG, SHIFT_MAX_DEG + 1e-9, SHIFT_STEP_DEG))
    S = np.array([fit(x)[0] for x in shifts])
    i = int(np.clip(np.argmin(S), 1, S.size - 2))
    curv = S[i - 1] - 2 * S[i] + S[i + 1]
    step = shifts[1] - shifts[0]
    shift = shifts[i] + (0.5 * (S[i - 1] - S[i + 1]) / curv * step if curv > 0 else 0.0)
    _, (alpha, beta), r, v = fit(shift)
    if not alpha > 0:
        raise EngineError(
            f"{analysis.source}: the motored cycles' pressure signal does not rise with the compression "
            f"(check the column and TDC)"
        )
    gain = intake_pa / float(alpha)
    ss = float(np.sum((u[w] - u[w].mean()) ** 2))
    return MotoredGain(
        gain_pa=float(gain),
        offset_pa=float(-gain * beta),
        cycles=tuple(int(c) for c in sel),
        exponent=n,
        intake_pa=intake_pa,
        window_deg=WINDOW_DEG,
        r2=float(1 - np.sum(r**2) / ss) if ss > 0 else 0.0,
        rms_pa=float(gain * np.sqrt(np.mean(r**2))),
        tdc_shift_deg=float(np.rad2deg(shift)),
        volume_ratio=v / v_bdc,
        pressure_pa=gain * (u[w] - beta),
    )
