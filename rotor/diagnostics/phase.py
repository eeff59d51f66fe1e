"""TDC from crank speed alone: where the engine's own speed signature lies on the wheel.

A new installation's angle from the wheel's gap to TDC is rarely known, and one copied
from another bench (a preset's calibration) can be off by anything. Compression and
expansion leave a phase signature in every revolution's speed, motored or fired: the
crank slows into each compression and speeds up after it, and a firing revolution
differs from the gas-exchange one. :func:`tdc_from_speed` finds it by fitting the
engine's own simulated speed signature against the measured speed at every candidate
offset, the idea of the speed-based TDC and combustion diagnosis of Taraza et al.
("Determining the top dead centre of an engine from crankshaft speed") and Rizzoni
("Estimate of indicated torque from crankshaft speed fluctuations: a model for the
dynamics of the IC engine", IEEE Trans. Vehicular Technology, 1989):

1. **The signature**: two periodic steady states of the engine at the recording's mean
   speed (:func:`rotor.steady_state`, one compiled solve for both): the fired cycle and
   the motored one (combustion scale 0). Their harmonics up to ``max_order`` (default
   4 per revolution: a bench's coupling resonance lies above, see
   :mod:`rotor.diagnostics.calibration`) are the shapes *combustion* (fired − motored)
   and *motored* (compression, expansion and the reciprocating inertia's ripple).
2. **The fit**: for every candidate offset d (0.25° steps over the whole cycle, 720° for
   a four-stroke, so the firing revolution is chosen too) and every cycle k, the cycle's
   detrended harmonics (:func:`rotor.cycles.cycle_spectrum`) are fitted by
   a_k·combustion + b_k·motored shifted by d, with a_k, b_k ≥ 0 (non-negative least
   squares): each cycle is free to fire or not (an ignition cut, a coast-down) and to
   fire harder or softer, but never with its sign turned (which would let a signature
   half a period off fit as well). The offset minimises the residual summed over the
   cycles, refined between grid points by a parabola.
3. **How sure**: ``std_deg`` (one standard deviation [deg], the larger of the fit's
   curvature estimate, 2σ²/S″, and the spread of the cycles' own offsets, 1.4826 times
   their median absolute deviation, over √cycles) and ``separation`` (how many σ of the residual's noise the best offset
   outside ±:data:`ALTERNATIVE_DEG` of it lies worse: √((S_alt − S)/σ²)). The offset is
   **determined** where the signature explains at least :data:`R2_MIN` of the speed's
   fluctuation up to ``max_order`` and the separation reaches :data:`SEPARATION_MIN`;
   otherwise ``determined`` is False and ``reason`` says why (a constant speed, too
   short a record, noise).
4. **Alike cylinders**: an engine of several evenly firing cylinders repeats its
   signature every firing interval, and the speed cannot tell cylinder 1 from the
   others: shifts under which the signature matches itself (R² above
   :data:`SYMMETRY_R2`) are equivalent (``period_deg``), the offset is given modulo
   them, the one nearest ``prior_deg`` (e.g. a calibration's) reported.

**Accuracy** (measured by ``benchmarks/tdc_from_speed.py``, 3 seeds of the start angle
and noise × the wheel's gap moved 0/30/90/180°; ``tests/test_tdc_from_speed.py`` holds its
records under 1°). Simulated tue-single recordings at 3000 rpm through a 60-2 wheel with
±0.1° tooth errors, 8 cycles, the tooth errors estimated from the same record: worst
0.6° steady (tooth times with 20 ns or 200 ns of timer jitter, or the raw analog bench
signal at ten times the real noise), 0.4° on a coast-down from 3000 to about 2100 rpm,
1.2° with an ignition cut of two cycles (1.2° with the wheel's true tooth errors too: the
cut's transient is not the steady signature); with the true tooth errors, under 0.2°
elsewhere. The stated ± (``std_deg``, 1σ) came out 0.04–2.3°; the error exceeded it in
12 of the 120 records, by at most 1.6×; the firing revolution was right in every record. The real tue-4gb10
recordings (speed only, against the pressure channel's polytropic-fit TDC of 29.4°,
30.7°, 28.9°): the speed puts TDC 7° later at full load, 13° at half load and 21° at no
load (R² 0.97 / 0.94 / 0.79): the engine file's Wiebe cycle is not the engine's
combustion, least so at light load. So the speed corrects a gross error (another
installation's mounting, a wrong firing revolution) but does not replace a pressure
channel, and :func:`check_tdc` keeps a given TDC that leaves less than
:data:`CONTRADICT_RATIO` times the best fit's unexplained fluctuation (1.2–1.5 on the real
recordings; 3 and more for a TDC 30° off on a simulated one).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..cycles import cycle_spectrum
from ..errors import LogError
from ..logs.analysis import LogAnalysis
from ..logs.wheel import ToothErrors
from ..results import Result, json_safe
from ..units import RPM_PER_RAD_S

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = [
    "SpeedTdc",
    "TdcNotDetermined",
    "tdc_from_speed",
    "R2_MIN",
    "SEPARATION_MIN",
    "ALTERNATIVE_DEG",
    "SYMMETRY_R2",
    "AGREE_DEG",
    "DEFAULT_MAX_ORDER",
    "CONTRADICT_RATIO",
    "TOOTH_MISMATCH",
    "TdcCheck",
    "check_tdc",
    "residual_at",
    "tooth_error_mismatch",
    "engine_signature",
]

R2_MIN = 0.5
"""The signature must explain at least this fraction of the speed's fluctuation [-]."""
SEPARATION_MIN = 5.0
"""… and the best offset must beat every other (more than :data:`ALTERNATIVE_DEG` away) by
this many standard deviations of the residual's noise [-]."""
ALTERNATIVE_DEG = 30.0
"""Offsets this far from the best [deg] count as alternatives."""
SYMMETRY_R2 = 0.98
"""A shift under which the engine's signature explains itself this well is one the speed
cannot tell apart (alike cylinders) [-]."""
AGREE_DEG = 10.0
"""A TDC (a calibration's) within this many degrees of the speed's is kept [deg]."""
DEFAULT_MAX_ORDER = 4.0
STEP_DEG = 0.25
TWO_PI = 2.0 * math.pi


class TdcNotDetermined(LogError):
    """The recording's speed cannot determine TDC (or cannot check a given one)."""


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class SpeedTdc(Result):
    """What :func:`tdc_from_speed` found (see the module doc).

    **Fields:** ``offset_deg``: from the start of the speed's cycle grid to cylinder 1's TDC
    at the start of intake [deg], in [0, cycle); ``tdc_after_gap_deg``: from the wheel's gap
    to cylinder 1's TDC [deg] in [0, 360) and ``firing_parity`` (0 or 1, as
    :func:`rotor.analyze_log`'s ``firing``), for a :class:`rotor.LogAnalysis` (None for a
    plain array); ``std_deg``: one standard deviation [deg]; ``separation``: the best
    alternative's distance [σ]; ``alternative_deg``: that alternative's ``offset_deg``;
    ``r2``: fraction of the fluctuation the signature explains [-]; ``determined`` and
    ``reason``; ``period_deg``: the shift under which the signature repeats (alike
    cylinders; the cycle's length when it does not); ``cycles``; per cycle
    ``cycle_offset_deg`` (each cycle's own best offset) and ``cycle_combustion``
    (its combustion amplitude a_k, 1 = the engine file's) [-]; ``candidates_deg`` and
    ``residual`` (the summed residual at each candidate, over the total power) for the plot;
    ``mean_rpm``; ``max_order``.
    """

    offset_deg: float
    tdc_after_gap_deg: float | None
    firing_parity: int | None
    std_deg: float
    separation: float
    alternative_deg: float
    r2: float
    determined: bool
    reason: str
    period_deg: float
    cycle_deg: float
    cycles: int
    cycle_offset_deg: np.ndarray
    cycle_combustion: np.ndarray
    candidates_deg: np.ndarray
    residual: np.ndarray
    mean_rpm: float
    max_order: float
    source: str = ""
    firing_tdc_wheel_deg: float | None = None

    def parity_for(self, tdc_deg: float) -> int | None:
        """The firing parity (as :func:`rotor.analyze_log`'s ``firing``) that puts firing TDC,
        at ``tdc_deg`` [deg] after the gap, nearest this fit's firing TDC (None for a
        two-stroke or a plain array)."""
        if self.firing_tdc_wheel_deg is None or self.cycle_deg < 719.0:
            return None
        return int(round((self.firing_tdc_wheel_deg - float(tdc_deg)) / 360.0)) % 2

    def summary(self) -> str:
        """A few lines: the offset, how sure, and why not where it is not determined."""
        where = (
            f"TDC {self.tdc_after_gap_deg:.1f}° after the gap (firing parity {self.firing_parity})"
            if self.tdc_after_gap_deg is not None
            else f"TDC {self.offset_deg:.1f}° after the grid's start"
        )
        lines = [
            f"TDC from the speed{' of ' + self.source if self.source else ''}: {where}, ± {self.std_deg:.2f}° (1σ); "
            f"R² {self.r2:.3f}, next best offset {self.separation:.1f} σ worse ({self.cycles} cycles, "
            f"{self.mean_rpm:.0f} rpm)",
        ]
        if self.period_deg < self.cycle_deg - 1e-9:
            lines.append(
                f"  the engine's signature repeats every {self.period_deg:g}°: the offset is known modulo it "
                f"(cylinder 1 cannot be told from the others by the speed)"
            )
        if not self.determined:
            lines.append(f"  not determined: {self.reason}")
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """Tidy: one row per cycle: ``cycle``, ``offset_deg`` (its own best offset) and
        ``combustion`` (its fitted combustion amplitude, 1 = the engine file's) [-]."""
        import pandas as pd

        return pd.DataFrame(
            {
                "cycle": np.arange(self.cycles),
                "offset_deg": self.cycle_offset_deg,
                "combustion": self.cycle_combustion,
            }
        )

    def to_json_dict(self) -> dict:
        """The offset, how sure, per cycle figures; ``None``, never NaN."""
        return json_safe(
            {
                "offset_deg": self.offset_deg,
                "tdc_after_gap_deg": self.tdc_after_gap_deg,
                "firing_parity": self.firing_parity,
                "std_deg": self.std_deg,
                "separation_sigma": self.separation,
                "alternative_deg": self.alternative_deg,
                "r2": self.r2,
                "determined": self.determined,
                "reason": self.reason,
                "period_deg": self.period_deg,
                "cycles": self.cycles,
                "cycle_offset_deg": self.cycle_offset_deg,
                "cycle_combustion": self.cycle_combustion,
                "mean_rpm": self.mean_rpm,
                "max_order": self.max_order,
                "source": self.source,
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """The fit's residual (over the fluctuation's power) against the candidate offset,
        the best one marked, on ``ax`` (or a new figure)
        (:func:`rotor.plotting.diagnostics.plot_speed_tdc`). Returns the Axes."""
        return self._plot(ax, None)

    def _plot(self, ax: Any, given_deg: float | None) -> Any:
        from ..plotting.diagnostics import plot_speed_tdc

        return plot_speed_tdc(
            candidates_deg=self.candidates_deg,
            residual=self.residual,
            offset_deg=self.offset_deg,
            std_deg=self.std_deg,
            r2=self.r2,
            cycle_deg=self.cycle_deg,
            given_deg=given_deg,
            ax=ax,
        )


def _harmonics(omega_cycle: np.ndarray, K: int) -> np.ndarray:
    """Harmonics 1 … K of one periodic cycle sampled uniformly (ω ≈ mean + Σ Re(c_m e^{imψ}))."""
    P = omega_cycle.size
    return np.fft.rfft(omega_cycle)[1 : K + 1] * (2.0 / P)


def engine_signature(engine: Engine, rpm: float, harmonics: int) -> np.ndarray:
    """The engine's speed signature at time-mean speed ``rpm`` [rpm]: (3, harmonics)
    complex harmonics [rad/s] of one cycle, cycle angle 0 at cylinder 1's TDC at the start
    of intake, in the convention ω(ψ) ≈ mean + Σ Re(c_m·e^{imψ/r}) (r revolutions per
    cycle): the combustion part (fired − motored steady state), the gas part of the motored
    speed (compression and expansion), and the reciprocating masses' ripple
    (ω ∝ I(θ)^(−1/2) at constant kinetic energy)."""
    from ..dynamics.steady import steady_state
    from ..engine.inertia import reduced_inertia

    fired_ss = steady_state(engine, rpm)
    fired = np.asarray(fired_ss.omega, dtype=np.float64)
    motored = np.asarray(steady_state(engine, rpm, imep_scale=0.0).omega, dtype=np.float64)
    theta = np.asarray(fired_ss.theta, dtype=np.float64)
    inv = 1.0 / np.sqrt(np.asarray(reduced_inertia(engine, theta), dtype=np.float64))
    ripple = np.mean(motored) * inv / np.mean(inv)
    return np.stack(
        [
            _harmonics(fired - motored, harmonics),
            _harmonics(motored - ripple, harmonics),
            _harmonics(ripple, harmonics),
        ]
    )


def _nnls_explained(r: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """max over β ≥ 0 of 2β·r − βᵀGβ (the residual's decrease), for r (..., n) and G (n, n),
    by trying every support (n ≤ 3). Returns (explained (...), β (..., n))."""
    n = G.shape[0]
    best = np.zeros(r.shape[:-1])
    beta = np.zeros(r.shape)
    for mask in range(1, 2**n):
        S = [i for i in range(n) if mask >> i & 1]
        Gs = G[np.ix_(S, S)]
        if abs(np.linalg.det(Gs)) < 1e-300:
            continue
        b = r[..., S] @ np.linalg.inv(Gs).T
        ok = np.all(b >= 0, axis=-1)
        ex = np.sum(b * r[..., S], axis=-1)
        take = ok & (ex > best)
        best = np.where(take, ex, best)
        full = np.zeros(r.shape)
        full[..., S] = b
        beta = np.where(take[..., None], full, beta)
    return best, beta


def _circ(x, period):
    """x wrapped into [−period/2, period/2)."""
    return (np.asarray(x) + period / 2) % period - period / 2


def tdc_from_speed(
    engine: Engine,
    speed: LogAnalysis | np.ndarray,
    *,
    mean_omega: np.ndarray | None = None,
    max_order: float = DEFAULT_MAX_ORDER,
    prior_deg: float | None = None,
) -> SpeedTdc:
    """Cylinder 1's TDC from the crank speed alone (see the module doc).

    **Arguments:**
    - ``engine``: the :class:`rotor.Engine` (its inertia, the calibrated one where there is
      one; its pressure cycle gives the signature's shape, its amplitude is fitted).
    - ``speed``: a :class:`rotor.LogAnalysis` (its cycles, whatever TDC they were cut at:
      a calibration's, ``tdc_deg=0``, …), or an array (cycles, points) of the speed [rad/s]
      on a uniform angle grid of consecutive whole cycles, each starting at the same crank
      phase.
    - ``mean_omega``: for an array, each cycle's time-mean speed [rad/s] (default the
      rows' means).
    - ``max_order``: highest engine order fitted [orders per revolution] (default 4).
    - ``prior_deg``: an offset [deg, same frame as ``offset_deg``] to prefer among shifts
      the speed cannot tell apart (alike cylinders); None: the first.

    **Returns:** :class:`SpeedTdc` (never raises for a poor record: ``determined`` is
    False and ``reason`` says why). Raises :class:`rotor.LogError` for a speed without a
    whole cycle.
    """
    if isinstance(speed, LogAnalysis):
        omega = np.asarray(speed.omega, dtype=np.float64)
        mean_w = np.asarray(speed.mean_omega, dtype=np.float64)
        cycle = float(speed.cycle_rad)
        source = speed.source
    else:
        omega = np.asarray(speed, dtype=np.float64)
        if omega.ndim == 1:
            omega = omega[None, :]
        cycle = TWO_PI * (engine.strokes // 2)
        mean_w = omega.mean(axis=1) if mean_omega is None else np.asarray(mean_omega, dtype=np.float64).reshape(-1)
        source = ""
    if omega.ndim != 2 or omega.shape[0] < 1 or omega.shape[1] < 8:
        raise LogError(f"tdc_from_speed: speed of shape {omega.shape}: needs (cycles, points), a whole cycle or more")
    if not (np.all(np.isfinite(omega)) and np.all(omega > 0)):
        raise LogError("tdc_from_speed: the speed must be finite and positive")
    if not (isinstance(max_order, (int, float)) and max_order > 0):
        raise LogError(f"max_order = {max_order!r}: a positive order")
    revs = round(cycle / TWO_PI)
    C, P = omega.shape
    K = int(min(math.floor(max_order * revs + 1e-9), P // 2 - 1))
    if K < 1:
        raise LogError(f"tdc_from_speed: {P} points per cycle resolve no order up to {max_order:g}")
    rpm = float(np.mean(mean_w)) * RPM_PER_RAD_S
    B = engine_signature(engine, rpm, K)  # (3, K): combustion, compression, ripple
    Y = cycle_spectrum(omega, mean_w, cycle)[:, 1 : K + 1]  # (C, K)
    m = np.arange(1, K + 1)
    D = int(round(360.0 * revs / STEP_DEG))
    d = np.arange(D) * (cycle / D)
    E = np.exp(1j * m[:, None] * d[None, :] / revs)  # (K, D): harmonic m is order m/revs
    G = np.real(B @ B.conj().T)  # (3, 3)
    # r[k, d, j] = Re Σ_m Y_km · conj(B_jm) · e^{imd/revs}: the fit of cycle k's harmonics by shape j shifted by d
    r = np.stack([np.real((Y * B[j].conj()[None, :]) @ E) for j in range(B.shape[0])], axis=-1)  # (C, D, 3)
    explained, beta = _nnls_explained(r, G)
    power = np.sum(np.abs(Y) ** 2, axis=1)  # (C,)
    S = np.sum(power[:, None] - explained, axis=0)  # (D,)
    total = float(np.sum(power))
    i = int(np.argmin(S))
    s0, s1, s2 = S[(i - 1) % D], S[i], S[(i + 1) % D]
    curv = s0 - 2 * s1 + s2
    frac = 0.5 * (s0 - s2) / curv if curv > 0 else 0.0
    step = cycle / D
    best = (d[i] + frac * step) % cycle
    s_best = float(s1 - 0.25 * (s0 - s2) * frac) if curv > 0 else float(s1)
    dof = max(2 * C * K - B.shape[0] * C - 1, 1)
    sigma2 = max(s_best, 1e-300) / dof
    # alike cylinders: the shortest shift cycle/n under which the combustion shape fits itself
    shape = B[0] if np.any(B[0]) else B[1]
    norm = max(float(np.sum(np.abs(shape) ** 2)), 1e-300)
    period = cycle
    for n in range(max(int(engine.cylinders), 1), 1, -1):
        if np.real(np.sum(np.abs(shape) ** 2 * np.exp(1j * m * (cycle / n) / revs))) / norm > SYMMETRY_R2:
            period = cycle / n
            break
    # an equivalent offset nearest the prior
    if period < cycle and prior_deg is not None:
        shifts = best + period * np.arange(round(cycle / period))
        best = float(shifts[np.argmin(np.abs(_circ(shifts - np.deg2rad(prior_deg), cycle)))] % cycle)
    far = np.abs(_circ(d - best, period)) > np.deg2rad(ALTERNATIVE_DEG)
    if far.any():
        j_alt = int(np.flatnonzero(far)[np.argmin(S[far])])
        s_alt, alt = float(S[j_alt]), float(d[j_alt])
    else:
        s_alt, alt = float("inf"), float("nan")
    separation = math.sqrt(max(s_alt - s_best, 0.0) / sigma2) if math.isfinite(s_alt) else float("inf")
    std_curv = math.sqrt(2 * sigma2 / (curv / step**2)) if curv > 0 else float("inf")
    # each cycle's own best offset (within the equivalence) and combustion amplitude at the best offset
    Sk = power[:, None] - explained
    per = d[np.argmin(Sk, axis=1)]
    per = best + _circ(per - best, period)
    j_best = int(round(best / step)) % D
    a_k = beta[:, j_best, 0]
    # the cycles' own offsets, robustly (a cycle between firing and not may stand apart): 1.4826·MAD/√C
    spread = float(1.4826 * np.median(np.abs(_circ(per - best, period))) / math.sqrt(C)) if C >= 3 else 0.0
    std = max(std_curv, spread)
    r2 = 1.0 - s_best / total if total > 0 else 0.0
    reasons = []
    if total <= 0 or r2 < R2_MIN:
        reasons.append(
            f"the engine's speed signature explains {max(r2, 0.0):.0%} of the speed's fluctuation up to order "
            f"{max_order:g} (at least {R2_MIN:.0%} needed): a speed without the engine's compression and firing in it "
            f"(constant, noise, or another engine)"
        )
    if separation < SEPARATION_MIN:
        reasons.append(
            f"another offset ({np.rad2deg(alt):.0f}°) fits nearly as well ({separation:.1f} σ worse; "
            f"{SEPARATION_MIN:g} σ needed): {C} cycle{'s' if C != 1 else ''} too few or too noisy"
        )
    tdc_gap = parity = firing_wheel = None
    if isinstance(speed, LogAnalysis):
        # cylinder 1's TDC before intake at wheel angle start + best; firing TDC one revolution later
        start = float(speed.cycle_start_rad[0])
        tdc_before_intake = start + best
        tdc_gap = float(np.rad2deg(np.mod(tdc_before_intake, TWO_PI)))
        if speed.strokes == 4:
            firing_tdc = tdc_before_intake + TWO_PI
            parity = int(math.floor(firing_tdc / TWO_PI + 1e-9)) % 2
            firing_wheel = float(np.rad2deg(firing_tdc))
    return SpeedTdc(
        offset_deg=float(np.rad2deg(best)),
        tdc_after_gap_deg=tdc_gap,
        firing_parity=parity,
        std_deg=float(np.rad2deg(std)),
        separation=float(separation),
        alternative_deg=float(np.rad2deg(alt)),
        r2=float(r2),
        determined=not reasons,
        reason="; ".join(reasons),
        period_deg=float(np.rad2deg(period)),
        cycle_deg=float(np.rad2deg(cycle)),
        cycles=C,
        cycle_offset_deg=np.rad2deg(np.mod(per, cycle)),
        cycle_combustion=a_k,
        candidates_deg=np.rad2deg(d),
        residual=S / total if total > 0 else S,
        mean_rpm=rpm,
        max_order=float(max_order),
        source=source,
        firing_tdc_wheel_deg=firing_wheel,
    )


CONTRADICT_RATIO = 2.0
"""A TDC (a calibration's) is contradicted where it leaves more than this many times the
best offset's unexplained fluctuation [-] (the best fit's own residual is the model's
error on this engine: 3–22 % on the tue-4gb10 recordings, whose pressure TDC leaves
1.2–1.5 times that; a TDC 30° off on a simulated one, 3 times)."""
TOOTH_MISMATCH = 0.5
"""A calibration's tooth errors whose rms difference from the recording's own estimate
exceeds this fraction of their rms (outside the orders left to the engine) belong to
another wheel [-] (the same wheel's recordings: under 0.1; another wheel's: about 1.1)."""


def residual_at(fit: SpeedTdc, offset_deg: float) -> float:
    """The fraction of the speed's fluctuation that ``fit``'s signature leaves unexplained
    with cylinder 1's TDC at ``offset_deg`` [deg, the fit's frame] (1 − R² there) [-]."""
    x = np.append(fit.candidates_deg, fit.cycle_deg)
    y = np.append(fit.residual, fit.residual[0])
    return float(np.interp(float(offset_deg) % fit.cycle_deg, x, y))


def tooth_error_mismatch(given: ToothErrors, own: ToothErrors) -> float:
    """How far a given wheel's tooth errors (a calibration's) lie from the recording's own
    estimate: the rms of their difference over the rms of the given ones, both without the
    orders the estimate left to the engine [-] (0: the same wheel; about 1.1 for another
    wheel of the same kind). NaN where the wheels differ in spec."""
    if given.wheel != own.wheel:
        return float("nan")

    def strip(e):
        e = np.asarray(e, dtype=np.float64) - np.mean(e)
        X = np.fft.rfft(e)
        for k in own.engine_orders:
            if 0 < int(round(k)) < X.size:
                X[int(round(k))] = 0.0
        return np.fft.irfft(X, n=e.size)

    g, o = strip(given.errors_rad), strip(own.errors_rad)
    rms = float(np.sqrt(np.mean(g**2)))
    return float(np.sqrt(np.mean((g - o) ** 2)) / rms) if rms > 0 else 0.0


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class TdcCheck(Result):
    """A TDC (a calibration's, or one given) checked against the recording's speed.

    **Fields:** ``verdict``: ``"agrees"`` (kept), ``"parity"`` (kept, the firing revolution
    taken from the speed), ``"corrected"`` (replaced by the speed's), ``"consistent"`` (kept:
    the speed does not determine TDC but does not contradict it), ``"found"`` (no TDC was
    given: the speed's); ``given_deg`` (the TDC checked, after the gap [deg], or None);
    ``used_deg`` (the TDC used) and ``firing_parity``; ``given_unexplained`` and
    ``best_unexplained`` (1 − R² of the signature at the given TDC and at the best) [-];
    ``tooth_mismatch`` (:func:`tooth_error_mismatch`, NaN without given tooth errors) [-];
    ``fit``: the :class:`SpeedTdc`; ``message``: one line for the text output.
    """

    verdict: str
    given_deg: float | None
    used_deg: float
    firing_parity: int | None
    given_unexplained: float
    best_unexplained: float
    tooth_mismatch: float
    fit: SpeedTdc
    message: str

    @property
    def corrected(self) -> bool:
        """Whether the TDC used is not the one given."""
        return self.verdict == "corrected"

    def summary(self) -> str:
        """The verdict's line and the fit's summary."""
        return f"{self.message}\n" + self.fit.summary()

    def to_pandas(self) -> Any:
        """The fit's per-cycle table (:meth:`SpeedTdc.to_pandas`)."""
        return self.fit.to_pandas()

    def to_json_dict(self) -> dict:
        """The verdict, the TDCs, how sure (``std_deg``, ``separation_sigma``), the fit."""
        return json_safe(
            {
                "verdict": self.verdict,
                "given_tdc_after_gap_deg": self.given_deg,
                "used_tdc_after_gap_deg": self.used_deg,
                "firing_parity": self.firing_parity,
                "speed_tdc_after_gap_deg": self.fit.tdc_after_gap_deg,
                "std_deg": self.fit.std_deg,
                "separation_sigma": self.fit.separation,
                "r2": self.fit.r2,
                "given_unexplained": self.given_unexplained,
                "best_unexplained": self.best_unexplained,
                "tooth_mismatch": self.tooth_mismatch,
                "message": self.message,
                "fit": self.fit.to_json_dict(),
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """The fit's residual against the offset (:meth:`SpeedTdc.plot`), the checked TDC
        marked where one was given (:func:`rotor.plotting.diagnostics.plot_speed_tdc`)."""
        if self.given_deg is None:
            return self.fit.plot(ax=ax)
        # the fit ran on cycles cut at the given TDC: it lies at offset 0, or one revolution on
        cands = [0.0] + ([360.0] if self.fit.cycle_deg > 719.0 else [])
        at = min(cands, key=lambda c: residual_at(self.fit, c))
        return self.fit._plot(ax, at)


def check_tdc(
    fit: SpeedTdc, given_deg: float | None, *, what: str = "the calibration's", tooth_mismatch: float = float("nan")
) -> TdcCheck:
    """Check a TDC against the speed's fit, or take the speed's where none is given.

    **Arguments:** ``fit``: :func:`tdc_from_speed` on a :class:`rotor.LogAnalysis` cut at
    ``given_deg`` (so that the given TDC lies at offset 0 or one revolution, either
    firing revolution); ``given_deg``: the TDC checked, after the gap [deg], or None (find
    it); ``what``: how the messages name it; ``tooth_mismatch``: reported as is.

    **Returns:** :class:`TdcCheck`. **Raises** :class:`TdcNotDetermined` (one line, with
    the measured offset and why) where the speed cannot determine TDC and nothing given
    stands (none given, or the given one contradicted), or carries no signature of the
    engine at all (R² below :data:`R2_MIN`: a constant or noisy speed; then a given TDC
    can be neither found nor checked, and a diagnosis would be noise).
    """
    if fit.tdc_after_gap_deg is None:
        raise LogError("check_tdc: the fit must come from a rotor.LogAnalysis (a wheel's gap to count from)")
    src = f"{fit.source}: " if fit.source else ""
    sure = f"± {fit.std_deg:.1f}° (1σ), R² {fit.r2:.2f}, next best {fit.separation:.0f} σ worse"
    measured = f"{fit.tdc_after_gap_deg:.1f}° after the gap ({sure})"
    best_un = 1.0 - fit.r2
    if fit.r2 < R2_MIN:
        raise TdcNotDetermined(
            f"{src}the speed cannot determine TDC (best {measured}): {fit.reason}; "
            + (
                "give tdc_deg (--tdc-deg) or a pressure channel"
                if given_deg is None
                else f"{what} TDC {given_deg:.1f}° cannot be checked"
            )
        )
    if given_deg is None:
        if not fit.determined:
            raise TdcNotDetermined(f"{src}the speed cannot determine TDC (best {measured}): {fit.reason}")
        return TdcCheck(
            verdict="found",
            given_deg=None,
            used_deg=float(fit.tdc_after_gap_deg),
            firing_parity=fit.firing_parity,
            given_unexplained=float("nan"),
            best_unexplained=best_un,
            tooth_mismatch=tooth_mismatch,
            fit=fit,
            message=f"TDC from the speed: {measured}",
        )
    revs = round(fit.cycle_deg / 360.0)
    # the given TDC at offset 0 of the fit's frame, or one revolution on (the other firing revolution)
    cands = [0.0] + ([360.0] if revs == 2 else [])
    un = [residual_at(fit, c) for c in cands]
    j = int(np.argmin(un))
    given_un = un[j]
    dist = abs(float(_circ(fit.offset_deg - cands[j], fit.period_deg)))
    contradicted = dist > AGREE_DEG and given_un > CONTRADICT_RATIO * best_un

    def made(verdict: str, used: float, parity: int | None, message: str) -> TdcCheck:
        return TdcCheck(
            verdict=verdict,
            given_deg=float(given_deg),
            used_deg=used,
            firing_parity=parity,
            given_unexplained=given_un,
            best_unexplained=best_un,
            tooth_mismatch=tooth_mismatch,
            fit=fit,
            message=message,
        )

    if contradicted and fit.determined:
        return made(
            "corrected",
            float(fit.tdc_after_gap_deg),
            fit.firing_parity,
            f"TDC corrected: {what} {given_deg:.1f}° after the gap contradicts the recording's speed "
            f"(R² {1 - given_un:.2f} there), which puts it at {measured}: diagnosed with "
            f"{fit.tdc_after_gap_deg:.1f}°",
        )
    if contradicted:
        raise TdcNotDetermined(
            f"{src}{what} TDC {given_deg:.1f}° after the gap contradicts the recording's speed (R² "
            f"{1 - given_un:.2f} there against {fit.r2:.2f} at {fit.tdc_after_gap_deg:.1f}°), and the speed "
            f"cannot determine it ({fit.reason}): give tdc_deg (--tdc-deg) or a pressure channel"
        )
    if not fit.determined:
        return made(
            "consistent",
            float(given_deg),
            None,
            f"{what} TDC {given_deg:.1f}° after the gap is consistent with the recording's speed, which does "
            f"not determine it ({fit.reason})",
        )
    within = f"; within {AGREE_DEG:g}°" if dist <= AGREE_DEG else ""
    return made(
        "agrees",
        float(given_deg),
        fit.parity_for(float(given_deg)),
        f"{what} TDC {given_deg:.1f}° after the gap agrees with the recording's speed ({measured}{within})",
    )
