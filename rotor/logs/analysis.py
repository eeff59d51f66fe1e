"""Crank-angle-resolved speed, δ and order spectra from a logged wheel signal.

The pipeline of :func:`analyze_log`:

1. tooth edges: the ``tooth_time_s`` column, or found in ``encoder_v``
   (:func:`rotor.logs.edges.find_edges`);
2. each edge placed on the wheel (:func:`rotor.logs.pattern.locate_teeth`), its angle corrected
   by the wheel's tooth-spacing errors (estimated from the log, given, or none);
3. time as a function of angle, t(φ), a cubic spline through the edges; the speed is
   ω(φ) = 1/t'(φ) [rad/s], sampled on a uniform grid of each engine cycle;
4. the cycles: 0 = TDC of cylinder 1 at the start of intake, 360° = firing TDC (rotor's
   convention; a two-stroke cycle is one revolution from TDC). The angle from the gap
   to TDC is given or found from a pressure channel (:func:`tdc_from_pressure`); the
   firing revolution of a four-stroke comes from the pressure (the revolution with the
   compression peak), a cam signal, or the speed itself (the revolution in which the
   crank speeds up after TDC);
5. per cycle: the time-mean speed, the harmonics of ω by engine order (0.5, 1, 1.5, …
   for a four-stroke) with amplitude [rad/s] and phase [rad] in the convention of
   :class:`rotor.Orders` (ω = mean + Σ A·cos(order·ψ + phase), ψ the cycle angle), and
   δ = (ω_max − ω_min)/ω_mean of the speed rebuilt from its orders up to ``max_order``
   (the tooth-resolved speed carries the timer's jitter, which max − min would pick up).
   A cycle's linear trend (from the mean speeds of its neighbours) is taken out before
   the transform and δ, so a run-up or a coast-down does not leak into every order nor
   into δ: the same definition and code as a simulated run's (:mod:`rotor.cycles`).
"""

from __future__ import annotations

import dataclasses
import enum
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from jaxtyping import ArrayLike

from ..checks import check_size
from ..cycles import cycle_delta, cycle_spectrum
from ..errors import LogError
from ..results import Result, json_safe
from ..units import RPM_PER_RAD_S
from .digital import digital_edges
from .edges import Edges, find_edges
from .pattern import repairs_summary
from .plausibility import check_speed_time_base
from .reader import Log, read_log
from .track import ChoiceSource, WheelReading, named, read_track
from .wheel import ToothErrors, ToothTrack, Wheel, estimate_tooth_errors

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = [
    "LogAnalysis",
    "PhaseSource",
    "analyze_log",
    "tdc_from_pressure",
    "NoCompressionPeak",
    "PEAK_TO_NOISE_MIN",
    "PEAK_WIDTH_MAX_DEG",
]

TWO_PI = 2.0 * np.pi
PEAK_TO_NOISE_MIN = 20.0
"""A compression peak must stand this many times the signal's noise above the median of
the averaged firing revolution [-] (see :func:`tdc_from_pressure`)."""
PEAK_WIDTH_MAX_DEG = 120.0
"""… and the averaged revolution may lie above half the peak's height for at most this
much of it [deg] (a compression peak is narrow: 55–81° on the tue-4gb10 recordings, whose peaks stand
100–480 times their noise above the median)."""
ANALYSIS_ARRAYS = 8
"""Float64 arrays of (cycles × points per cycle) the analysis holds at once, for the size check."""


class NoCompressionPeak(LogError):
    """A pressure channel without a clear compression peak: not used for TDC."""


class PhaseSource(enum.Enum):
    """Where a recording's TDC or firing revolution came from (a typed state: decisions test
    this, never the words of ``tdc_method`` or ``firing_method``)."""

    GIVEN = "given"
    PRESSURE = "pressure"
    CAM = "cam"
    SPEED = "speed"
    UNKNOWN = "unknown"
    EVERY_REVOLUTION = "every revolution (two-stroke)"


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class LogAnalysis(Result):
    """Per-cycle speed, δ and orders of a logged recording (see :func:`analyze_log`).

    **Per cycle** (arrays with one row per complete cycle): ``t_start_s`` [s],
    ``mean_omega`` (time mean) [rad/s], ``delta`` [-], ``amplitude_rad_s`` and
    ``phase_rad`` (cycles × orders), ``omega`` (cycles × ``points_per_cycle``, the speed
    on the uniform cycle-angle grid) [rad/s]. ``order``: the engine orders [-].

    **Alignment:** ``cycle_rad``, ``strokes``, ``tdc_rad`` (angle from the gap, i.e. the
    first tooth edge after it, to TDC of cylinder 1) and ``tdc_method``;
    ``firing_parity`` (which revolutions, counted from the first gap, hold firing TDC:
    0 or 1) and ``firing_method``; ``cycle_start_rad`` (wheel angle of each cycle's start).

    **Wheel:** ``track`` (:class:`rotor.logs.wheel.ToothTrack`, ``None`` for a speed log),
    ``tooth_errors`` (:class:`rotor.logs.wheel.ToothErrors` applied, or ``None``),
    ``edges`` (:class:`rotor.logs.edges.Edges` of an analog signal, or ``None``).
    ``pressure``: (cycle angle [rad], pressure signal) of the complete cycles when a
    pressure channel was given, for the plot. ``cylinders``: as given; ``delta_weight``:
    the weight of each order in the speed whose max − min is δ (1: taken whole; see
    ``denoise`` of :func:`analyze_log`). ``reading``: the wheel signal as read
    (:class:`rotor.logs.track.WheelReading`: the edge, levels and wheel chosen, with their
    evidence, every wheel tried; ``None`` for a speed log). ``tdc_source``, ``firing_source``:
    where TDC and the firing revolution came from (:class:`PhaseSource`), beside
    ``tdc_method`` and ``firing_method`` in words.
    """

    source: str
    kind: str
    strokes: int
    cycle_rad: float
    order: np.ndarray
    t_start_s: np.ndarray
    mean_omega: np.ndarray
    delta: np.ndarray
    amplitude_rad_s: np.ndarray
    phase_rad: np.ndarray
    omega: np.ndarray
    cycle_start_rad: np.ndarray
    tdc_rad: float
    tdc_method: str
    firing_parity: int | None
    firing_method: str
    max_order: float
    track: ToothTrack | None = None
    tooth_errors: ToothErrors | None = None
    edges: Edges | None = None
    pressure: tuple | None = None
    notes: tuple = ()
    cylinders: int = 1
    delta_weight: np.ndarray | None = None
    reading: WheelReading | None = None
    tdc_source: PhaseSource = PhaseSource.UNKNOWN
    firing_source: PhaseSource = PhaseSource.EVERY_REVOLUTION

    # ------------------------------------------------------------------ numbers
    @property
    def cycles(self) -> int:
        """Complete cycles analysed."""
        return int(self.mean_omega.size)

    @property
    def mean_rpm(self) -> np.ndarray:
        """Time-mean speed of each cycle [rpm]."""
        return self.mean_omega * RPM_PER_RAD_S

    @property
    def points_per_cycle(self) -> int:
        """Samples of the uniform cycle-angle grid per cycle."""
        return int(self.omega.shape[1])

    @property
    def cycle_angle_rad(self) -> np.ndarray:
        """The uniform grid of cycle angles the speed is sampled on [rad]."""
        return np.arange(self.points_per_cycle) * self.cycle_rad / self.points_per_cycle

    def amplitude_of(self, order: float) -> np.ndarray:
        """The speed amplitude of ``order`` in each cycle [rad/s]."""
        i = np.flatnonzero(np.isclose(self.order, order))
        if i.size == 0:
            raise LogError(f"order {order:g} not analysed (orders {self.order[0]:g} … {self.order[-1]:g})")
        return self.amplitude_rad_s[:, i[0]]

    def statistics(self) -> dict:
        """Cycle-to-cycle statistics: mean, standard deviation and coefficient of variation
        of the mean speed [rpm] and δ, and the mean and standard deviation of each order's
        amplitude [rad/s]."""

        def stats(x):
            x = np.asarray(x, dtype=np.float64)
            m = float(np.mean(x))
            s = float(np.std(x, ddof=1)) if x.size > 1 else 0.0
            return {
                "mean": m,
                "std": s,
                "cov": s / m if m else float("nan"),
                "min": float(x.min()),
                "max": float(x.max()),
            }

        return {
            "cycles": self.cycles,
            "mean_rpm": stats(self.mean_rpm),
            "delta": stats(self.delta),
            "orders": [
                {
                    "order": float(o),
                    "amplitude_rad_s_mean": float(np.mean(a)),
                    "amplitude_rad_s_std": float(np.std(a, ddof=1)) if a.size > 1 else 0.0,
                }
                for o, a in zip(self.order, self.amplitude_rad_s.T)
            ],
        }

    # ------------------------------------------------------------------ people
    def to_json_dict(self, max_order: float | None = None) -> dict:
        """Plain numbers for JSON (what ``rotor analyze --json`` prints): the cycles (each
        with its number ``cycle``, from 1), the wheel
        as found, the correction applied; orders up to ``max_order`` (default the analysis's)
        [per revolution]. ``None`` where a number is undefined."""
        keep = self.order <= (self.max_order if max_order is None else max_order) + 1e-9
        cycles = [
            {
                "cycle": k,
                "t_start_s": float(t0),
                "mean_rpm": float(w * RPM_PER_RAD_S),
                "delta": float(d),
                "orders": [
                    {"order": float(o), "amplitude_rad_s": float(a), "phase_rad": float(p)}
                    for o, a, p in zip(self.order[keep], amp[keep], ph[keep])
                ],
            }
            for k, (t0, w, d, amp, ph) in enumerate(
                zip(self.t_start_s, self.mean_omega, self.delta, self.amplitude_rad_s, self.phase_rad), start=1
            )  # cycles counted from 1
        ]
        wheel = self.track.to_json_dict() if self.track is not None else None
        if wheel is not None and self.edges is not None:
            wheel["encoder"] = self.edges.to_json_dict()
        if wheel is not None and self.reading is not None:
            wheel["reading"] = self.reading.to_json_dict()
        return json_safe(
            {
                "source": self.source,
                "kind": self.kind,
                "strokes": self.strokes,
                "cylinders": self.cylinders,
                "wheel": wheel,
                "tooth_error_correction": None if self.tooth_errors is None else self.tooth_errors.to_json_dict(),
                "tdc_after_gap_deg": float(np.rad2deg(self.tdc_rad)),
                "tdc_method": self.tdc_method,
                "firing_revolution_parity": self.firing_parity,
                "firing_method": self.firing_method,
                "max_order": float(self.max_order),
                "cycles": cycles,
                "statistics": self.statistics(),
                "notes": list(self.notes),
            }
        )

    def summary(self) -> str:
        """A few lines for a terminal."""
        s = self.statistics()
        lines = [f"{self.source}: {self.cycles} complete {self.strokes}-stroke cycles ({self.kind} log)"]
        if self.track is not None:
            w = self.track.to_json_dict()
            lines.append(
                f"  wheel {w['spec']}: {w['edges']} edges, {w['complete_revolutions']} complete revolutions, "
                f"{w['edges_per_rev']} per revolution, gap period ratio {w['gap_period_ratio']:.2f}"
            )
        if self.reading is not None:
            found = [f"{c.name} {c.value}" for c in self.reading.choices if c.source is ChoiceSource.FOUND]
            lines.append(
                f"  read as {self.reading.pins()}"
                + (f" (found from the signal: {', '.join(found)}; these options pin them)" if found else "")
            )
        if self.tooth_errors is not None:
            te = self.tooth_errors
            lines.append(
                f"  tooth errors: {te.method}, rms {np.rad2deg(te.rms_rad):.3f}°, "
                f"max {np.max(np.abs(te.errors_deg)):.3f}°"
                + (f" (orders {', '.join(map(str, te.engine_orders))} left to the engine)" if te.engine_orders else "")
            )
        else:
            lines.append("  tooth errors: not corrected")
        lines.append(
            f"  TDC {np.rad2deg(self.tdc_rad):.2f}° after the gap ({self.tdc_method}); "
            f"firing revolution parity {self.firing_parity} ({self.firing_method})"
        )
        m, d = s["mean_rpm"], s["delta"]
        lines.append(
            f"  mean speed {m['mean']:10.2f} rpm  (cycles {m['min']:.2f} … {m['max']:.2f}, CoV {m['cov']:.2%})"
        )
        lines.append(
            f"  δ          {d['mean']:10.5f}      (cycles {d['min']:.5f} … {d['max']:.5f}, CoV {d['cov']:.1%})"
        )
        lines.append("  order  amplitude [rad/s] mean ± std")
        for o in s["orders"]:
            if o["order"] <= min(self.max_order, 6.0) + 1e-9:
                lines.append(f"  {o['order']:5.1f}  {o['amplitude_rad_s_mean']:10.4f} ± {o['amplitude_rad_s_std']:.4f}")
        for n in self.notes:
            lines.append(f"  note: {n}")
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """Tidy: one row per cycle and order: ``cycle`` (from 1), ``t_start_s``, ``mean_rpm``,
        ``delta`` [-], ``order`` [per revolution], ``amplitude_rad_s``, ``phase_rad``."""
        import pandas as pd

        C, K = self.amplitude_rad_s.shape
        cyc = np.repeat(np.arange(C), K)
        return pd.DataFrame(
            {
                "cycle": cyc + 1,  # counted from 1
                "t_start_s": np.asarray(self.t_start_s, dtype=np.float64)[cyc],
                "mean_rpm": np.asarray(self.mean_rpm, dtype=np.float64)[cyc],
                "delta": np.asarray(self.delta, dtype=np.float64)[cyc],
                "order": np.tile(np.asarray(self.order, dtype=np.float64), C),
                "amplitude_rad_s": np.asarray(self.amplitude_rad_s, dtype=np.float64).reshape(-1),
                "phase_rad": np.asarray(self.phase_rad, dtype=np.float64).reshape(-1),
            }
        )

    def plot(self, ax: Any = None, kind: str | None = None) -> Any:
        """The combined plot (speed over the cycle, per-cycle mean speed and δ, order
        spectrum, pressure if logged) on ``ax`` (a 2×2 array of Axes, or None for a new
        figure), or with ``kind`` (``"speed"``, ``"cycles"``, ``"orders"``, ``"signal"``)
        that panel alone on the one Axes ``ax``; see
        :func:`rotor.plotting.logs.plot_log_analysis`. Returns what it drew on."""
        from ..plotting.logs import plot_log_analysis

        return plot_log_analysis(self, ax=ax, kind=kind)


# ---------------------------------------------------------------------- alignment
def _volume_ratio(x, compression_ratio, rod_ratio):
    """V(x)/V_c of a central crank mechanism, x the angle from TDC [rad]."""
    lam = rod_ratio
    s = (1 - np.cos(x)) + (1 - np.sqrt(1 - (lam * np.sin(x)) ** 2)) / lam
    return 1 + 0.5 * (compression_ratio - 1) * s


def tdc_from_pressure(
    phi: ArrayLike,
    p: ArrayLike,
    *,
    compression_ratio: float | None = None,
    rod_ratio: float | None = None,
    window_deg: tuple[float, float] = (-90.0, -10.0),
) -> tuple[float, int, str]:
    """TDC of the compression from a pressure signal sampled at wheel angles.

    **Arguments:** ``phi``: wheel angle of each sample [rad]; ``p``: the pressure signal
    (any unit, gain or offset: only its shape is used); ``compression_ratio`` and
    ``rod_ratio`` (crank radius / rod length): the engine's, for the polytropic fit;
    ``window_deg``: the compression window of the fit, from TDC [deg].

    The compression peaks once every second revolution: the revolutions (windows of one
    revolution centred on the peak's angle) with the higher peaks are the firing ones,
    and their traces are averaged on a 0.25° grid. With the compression ratio and rod
    ratio, TDC comes from a polytropic fit of the compression before ignition,
    log(p + p₀) = c − n·log V(φ − φ_TDC), with φ_TDC, n, c and the signal's offset p₀
    free (the sensor's gain and offset need not be known). Without them, TDC is the
    averaged trace's peak, which combustion puts some degrees late (a motored cycle's
    peak is within a degree of TDC).

    **A clear compression peak** is needed, or :class:`NoCompressionPeak` (a
    :class:`LogError`) is raised and no TDC is given: the averaged firing revolution's peak
    must stand :data:`PEAK_TO_NOISE_MIN` (20) times the signal's noise above its median
    (the noise: the median absolute sample-to-sample difference of the raw signal / 0.954,
    the standard deviation of white noise), and the revolution may lie above half the
    peak's height for at most :data:`PEAK_WIDTH_MAX_DEG` (120°). A flat channel, pure
    noise, or a periodic signal that is not a pressure (a wheel signal) fails.

    **Returns:** (TDC wheel angle modulo 2π [rad], firing parity 0 or 1 of the
    revolutions counted from wheel angle 0 that hold it, the method in words).
    """
    from scipy.optimize import least_squares

    phi = np.asarray(phi, dtype=np.float64)
    p = np.asarray(p, dtype=np.float64)
    if phi.size < 100:
        raise LogError("pressure channel: too few samples within the tooth edges to find TDC")
    i_pk = int(np.argmax(p))
    centre = float(np.mod(phi[i_pk], TWO_PI))
    win = np.floor((phi - centre + np.pi) / TWO_PI).astype(int)  # window k: centre + 2πk ± π
    ks = np.unique(win)
    peaks = np.array([p[win == k].max() for k in ks])
    full = np.array(
        [
            (phi[win == k].min() <= centre + TWO_PI * k - 0.9 * np.pi)
            and (phi[win == k].max() >= centre + TWO_PI * k + 0.9 * np.pi)
            for k in ks
        ]
    )
    ks, peaks = ks[full], peaks[full]
    even, odd = peaks[ks % 2 == 0], peaks[ks % 2 == 1]
    if even.size == 0 or odd.size == 0:
        raise LogError("pressure channel: need at least one whole even and one whole odd revolution")
    parity_win = int(np.mean(odd) > np.mean(even))
    fire = ks[ks % 2 == parity_win]
    step = np.deg2rad(0.25)
    grid = np.arange(-np.pi, np.pi, step)
    sel = np.isin(win, fire)
    x = phi[sel] - centre - TWO_PI * win[sel]
    b = np.clip(np.floor((x + np.pi) / step).astype(int), 0, grid.size - 1)
    sums = np.bincount(b, weights=p[sel], minlength=grid.size)
    cnt = np.bincount(b, minlength=grid.size)
    ok = cnt > 0
    if ok.sum() < grid.size // 4:
        raise LogError("pressure channel: too few samples in the firing revolutions")
    x = grid + step / 2
    avg = np.interp(x, x[ok], sums[ok] / cnt[ok])
    _check_compression_peak(p, avg, step)
    j = int(np.argmax(avg))
    jj = int(np.clip(j, 1, avg.size - 2))
    y0, y1, y2 = avg[jj - 1 : jj + 2]
    curv = y0 - 2 * y1 + y2
    peak = x[jj] + (0.5 * (y0 - y2) / curv * step if curv < 0 else 0.0)
    if compression_ratio is None:
        tdc_rel, method = peak, "pressure: the averaged firing cycle's peak (late by the combustion)"
    else:
        if not (compression_ratio > 1 and rod_ratio is not None and 0 < rod_ratio < 1):
            raise LogError(
                f"compression_ratio = {compression_ratio!r}, rod_ratio = {rod_ratio!r}: need a "
                f"compression ratio > 1 and a rod ratio (crank radius / rod length) between 0 and 1"
            )
        lo_w, hi_w = np.deg2rad(window_deg)
        tdc_rel = peak - np.deg2rad(10.0)
        for _ in range(10):
            m = (x - tdc_rel >= lo_w) & (x - tdc_rel <= hi_w)
            floor = avg[m].min()
            span = avg.max() - floor

            def res(q):
                t0, n, c, off = q
                return np.log(avg[m] - floor + off * span) - (
                    c - n * np.log(_volume_ratio(x[m] - t0, compression_ratio, rod_ratio))
                )

            q0 = [tdc_rel, 1.3, np.log(span), 0.1]
            sol = least_squares(res, q0, bounds=([tdc_rel - 0.35, 1.0, -50, 1e-4], [tdc_rel + 0.35, 1.7, 50, 10.0]))
            moved = abs(sol.x[0] - tdc_rel)
            tdc_rel = float(sol.x[0])
            if moved < np.deg2rad(0.01):
                break
        method = (
            f"pressure: polytropic fit of the compression ({window_deg[0]:g}…{window_deg[1]:g}° from TDC, "
            f"compression ratio {compression_ratio:g}, rod ratio {rod_ratio:.4g}, exponent {sol.x[1]:.3f})"
        )
    tdc_abs = centre + TWO_PI * int(fire[0]) + tdc_rel
    parity = int(np.floor(tdc_abs / TWO_PI)) % 2
    return float(np.mod(tdc_abs, TWO_PI)), parity, method


def _check_compression_peak(p, avg, step):
    """Raise NoCompressionPeak unless ``avg`` (the averaged firing revolution on a grid of
    ``step`` [rad]) has a clear, narrow peak above the noise of the raw signal ``p``."""
    noise = float(np.median(np.abs(np.diff(p)))) / 0.954  # white noise: median |Δ| = 0.954 σ
    med = float(np.median(avg))
    height = float(np.max(avg)) - med
    if not height > PEAK_TO_NOISE_MIN * noise or not height > 1e-9 * max(abs(med), 1e-300):
        raise NoCompressionPeak(
            f"pressure channel: no clear compression peak (the averaged firing revolution peaks "
            f"{height:.3g} above its median, the signal's noise is {noise:.3g}; {PEAK_TO_NOISE_MIN:g}× the "
            f"noise is needed): not used for TDC"
        )
    width = float(np.count_nonzero(avg > med + 0.5 * height)) * np.rad2deg(step)
    if width > PEAK_WIDTH_MAX_DEG:
        raise NoCompressionPeak(
            f"pressure channel: no clear compression peak (the averaged firing revolution lies above half "
            f"its peak's height for {width:.0f}°, a compression peak for under {PEAK_WIDTH_MAX_DEG:g}°: is it "
            f"the pressure column?): not used for TDC"
        )


def _speed_parity(omega_of, phi0, phi1, tdc):
    """Firing parity from the speed: the revolution after whose TDC the crank speeds up more."""
    r0 = int(np.ceil((phi0 - tdc) / TWO_PI))
    r1 = int(np.floor((phi1 - tdc - np.pi) / TWO_PI))
    if r1 - r0 < 1:
        return 0, 0.0
    revs = np.arange(r0, r1 + 1)
    x = tdc + TWO_PI * revs[:, None] + np.linspace(0, np.pi, 61)[None, :]
    w = omega_of(x)
    rise = w.max(axis=1) - w[:, 0]
    even, odd = rise[revs % 2 == 0], rise[revs % 2 == 1]
    if even.size == 0 or odd.size == 0:
        return 0, 0.0
    parity = int(np.mean(odd) > np.mean(even))
    sep = abs(np.mean(odd) - np.mean(even)) / (np.std(rise) + 1e-300)
    return parity, float(sep)


def _cam_parity(name, log, edge, t_of, phi_of, phi_lo, phi_hi, tdc, required, notes):
    """The firing parity from the cam channel (analog ``cam_v`` or digital ``cam_d``): the
    firing TDC is the first TDC after each rising cam edge. ``None`` (and a
    note) where the cam edges do not fall once per cycle and the cam is not ``required``."""
    if "cam_d" in log:
        cam = named(name, digital_edges, log["time"], log["cam_d"], name="cam_d").times
    else:
        cam = find_edges(log["time"], log["cam_v"], name="cam_v").times
    cam_phi = phi_of(cam[(cam >= t_of(phi_lo)) & (cam <= t_of(phi_hi))])
    why = ""
    if cam_phi.size == 0:
        why = "no cam edge within the tooth edges"
    else:
        r = np.ceil((cam_phi - tdc) / TWO_PI)
        parities = np.mod(r, 2).astype(int)
        if np.any(parities != parities[0]) or np.any(np.diff(r) < 2):
            why = "the cam edges do not fall once per cycle (their revolutions alternate irregularly)"
    if why:
        if required:
            raise LogError(f"{name}: {why}")
        notes.append(f"cam channel not used for the firing revolution: {why}")
        return None
    return int(parities[0])


def _wiener_gain(X, revs, teeth, kmax):
    """Weights of the harmonics 1 … kmax of the cycles' speed X (cycles × harmonics) by their
    signal-to-noise ratio, S/(S + N). Timer jitter and edge noise are white in the time of
    each edge, so the speed's noise grows in proportion to the order: N_m = c²·m², c² the
    median of |X_m|²/m² over the orders teeth/6 … teeth/3 (which an engine hardly reaches);
    S_m = max(mean |X_m|² − N_m, 0) over the cycles."""
    m_lo, m_hi = int(np.ceil(teeth / 6 * revs)), int(np.floor(teeth / 3 * revs))
    m_hi = min(m_hi, X.shape[1] - 1)
    power = np.mean(np.abs(X) ** 2, axis=0)
    m = np.arange(X.shape[1])
    if m_hi <= m_lo:
        return np.ones(kmax), 0.0
    c2 = float(np.median(power[m_lo : m_hi + 1] / m[m_lo : m_hi + 1] ** 2))
    noise = c2 * m[1 : kmax + 1] ** 2
    signal = np.maximum(power[1 : kmax + 1] - noise, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        g = np.where(signal > 0, signal / (signal + noise), 0.0)
    return g, c2


def _firing_run_note(te, cylinders, strokes, max_order, teeth):
    """What a tooth-error estimate from a firing run leaves out, and what it may cost δ."""
    ks = [k for k in te.engine_orders]
    if ks:
        shown = ", ".join(map(str, ks)) if len(ks) <= 6 else f"{ks[0]}, {ks[1]}, … {ks[-1]}"
        s = (
            f"tooth errors estimated from this firing run: the wheel's errors at orders {shown} were left to the "
            f"engine (a firing run cannot tell them from the engine's fluctuation) and stay in the speed"
        )
        if te.order_rms_rad is not None:
            kk = np.array([k for k in ks if k <= max_order + 1e-9], dtype=float)
            u = 2.0 * te.order_rms_rad * float(np.sqrt(np.sum(kk**2)))
            s += (
                f"; at the other orders the wheel's errors are {np.rad2deg(te.order_rms_rad):.3f}° rms per order, "
                f"which at these would change δ by about ±{u:.2g}"
            )
    else:
        s = "tooth errors estimated from this firing run: no order stood out as the engine's, so none was left to it"
    s += (
        "; a calibration saved from a coast-down or motored run (tooth_errors=FILE, --tooth-errors FILE) gives the "
        "full wheel pattern"
    )
    if cylinders == 1 and not (strokes == 4 and len(ks) > 0):
        s += (
            "; for an engine of several cylinders give cylinders (--cylinders N), or its fluctuation at the firing "
            "orders may be taken for the wheel's errors"
        )
    return s


class _Lazy:
    """``cls(*args)``, built on its first call."""

    def __init__(self, cls, *args):
        self._make, self._f = (lambda: cls(*args)), None

    def __call__(self, x):
        if self._f is None:
            self._f = self._make()
        return self._f(x)


def _check_types(source, wheel, tdc_deg, max_order, points_per_cycle, engine, tooth_errors, denoise):
    """TypeError naming the argument of :func:`analyze_log` that has the wrong type."""
    from ..engine.model import Engine
    from .track import WheelReading

    if not isinstance(source, (str, os.PathLike, Log, WheelReading)):
        raise TypeError(
            f"source = {source!r}: a log file's name (str or os.PathLike) or a rotor.Log, not {type(source).__name__}"
        )
    if wheel is not None and not isinstance(wheel, (str, Wheel, int, np.integer)):
        raise TypeError(f"wheel = {wheel!r}: a spec such as '60-2' or a rotor.Wheel, not {type(wheel).__name__}")
    for key, v in (("tdc_deg", tdc_deg), ("max_order", max_order)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating))):
            raise TypeError(f"{key} = {v!r}: a number or None, not {type(v).__name__}")
    if engine is not None and not isinstance(engine, Engine):
        raise TypeError(
            f"engine = {engine!r}: a rotor.Engine (e.g. rotor.load_engine('4chn15')) or None, not {type(engine).__name__}"
        )
    if tooth_errors is not None and not isinstance(tooth_errors, (str, os.PathLike, ToothErrors)):
        raise TypeError(
            f"tooth_errors = {tooth_errors!r}: 'estimate', 'none', None, a rotor.ToothErrors or a JSON file's "
            f"name, not {type(tooth_errors).__name__}"
        )
    if not isinstance(denoise, (bool, np.bool_)):
        raise TypeError(f"denoise = {denoise!r}: True or False")


# ---------------------------------------------------------------------- analysis
def analyze_log(
    source: str | os.PathLike | Log,
    wheel: str | Wheel | None = None,
    *,
    columns: str | Sequence[str] | None = None,
    strokes: int = 4,
    cylinders: int = 1,
    tdc_deg: float | None = None,
    firing: str | int = "auto",
    tooth_errors: str | os.PathLike | ToothErrors | None = "estimate",
    engine_orders: str | Sequence[int] = "auto",
    max_order: float | None = None,
    points_per_cycle: int | None = None,
    edge: str = "auto",
    compression_ratio: float | None = None,
    rod_ratio: float | None = None,
    denoise: bool = True,
    engine: Engine | None = None,
) -> LogAnalysis:
    """Per-cycle mean speed, δ and order spectrum of a logged recording.

    **Arguments:**
    - ``source``: a file (read by :func:`rotor.logs.reader.read_log` with ``columns``) or a
      :class:`rotor.logs.reader.Log` (e.g. ``Log.from_arrays(tooth_time_s=edges)``).
    - ``wheel``: ``"60-2"``, ``"36-1"``, … or a :class:`rotor.logs.wheel.Wheel`; needed
      unless the log is a speed series (``rpm``).
    - ``strokes``: 4 (default) or 2.
    - ``cylinders``: of the engine, evenly firing (default 1). With more than one, the
      tooth-error estimate from this log leaves every whole multiple of the firing order
      to the engine (:func:`rotor.logs.wheel.firing_orders`): a firing run cannot tell the
      wheel's errors at those orders from the engine's fluctuation.
    - ``tdc_deg``: angle from the gap (the first tooth edge after it) to TDC of
      cylinder 1 [deg]; default: from the pressure channel if there is one, else 0
      (the cycles then start at the gap). For a speed log: the angle from the first
      sample to TDC.
    - ``firing``: which revolutions hold firing TDC (four-stroke): ``"auto"`` (pressure,
      else cam, else speed), ``"pressure"``, ``"cam"``, ``"speed"``, or 0/1 (the parity
      of the revolutions counted from the first gap).
    - ``tooth_errors``: ``"estimate"`` (from this log, :func:`rotor.logs.wheel.estimate_tooth_errors`),
      ``None`` (no correction), a :class:`rotor.logs.wheel.ToothErrors` or the path of one
      saved as JSON.
    - ``engine_orders``: passed to the estimate (``"auto"``, a list, or ``()``).
    - ``engine``: a :class:`rotor.Engine`: the speed ripple of its varying reduced
      inertia is removed before the tooth errors are estimated (needs ``tdc_deg``), which
      makes the engine's own fuel-cut coast-down a wheel calibration.
    - ``max_order``: highest order reported and used for δ (default: a quarter of the
      teeth per revolution, 15 for a 60-tooth wheel; 12 for a speed log); below half the
      teeth per revolution.
    - ``points_per_cycle``: samples of the uniform angle grid per cycle (default two per
      tooth pitch, or 8 per period of ``max_order`` if that is more).
    - ``denoise``: δ from the orders weighted by their signal-to-noise ratio (a Wiener
      weight; the noise of each order, which timer jitter makes grow in proportion to
      the order, is measured on the orders from teeth/6 to teeth/3); ``False``: δ from
      all orders up to ``max_order`` unweighted. The orders reported are never weighted.
    - ``edge``: ``"rising"`` or ``"falling"`` edges of an analog or digital signal.
      An analog signal that is no two-level pulse train (a variable-reluctance sensor's,
      whose amplitude grows with speed) is read at its zero crossings
      (:func:`rotor.logs.edges.find_edges` with ``levels="vr"``).
    - ``wheel``: also ``"N-g1-g2…"`` (``"36-2-1"``), a wheel file (``*.toml``) or
      ``"auto"`` (found from the log, :func:`rotor.logs.identify.find_wheel`; a note says
      what). Edges that do not fit are repaired where the pattern proves how
      (:mod:`rotor.logs.pattern`; each repair in ``track.repairs`` and the JSON).
    - ``compression_ratio``, ``rod_ratio`` (crank radius / rod length): the engine's,
      for TDC from the pressure by a polytropic fit (:func:`tdc_from_pressure`);
      without them TDC is the pressure peak, some degrees late when the engine fires.

    **Plausibility** (:mod:`rotor.logs.plausibility`): a time base that implies under 10 or
    over 30,000 rpm (a time column in ms or µs), and time stamps too coarse for the tooth
    period (float32), are refused; a ``max_order`` below the cycle's lowest order (0.5 for
    a four-stroke, 1 for a two-stroke) keeps no order and is refused; ``points_per_cycle``
    is checked against the memory budget (:func:`rotor.checks.check_size`) before the grid
    is allocated. A pressure channel without a clear compression peak is not used for TDC
    (:func:`tdc_from_pressure`; TDC is then unknown, and a note says why). Where the
    wheel does not fit the rising edges of an analog signal but fits its falling ones, the
    error says to give ``edge="falling"``.

    **Returns:** :class:`LogAnalysis`. Raises :class:`rotor.logs.reader.LogError` with the
    file, row, column or time of anything that cannot be analysed, and ``TypeError`` for an
    argument of the wrong type.
    """
    from scipy.interpolate import CubicSpline, PchipInterpolator

    _check_types(source, wheel, tdc_deg, max_order, points_per_cycle, engine, tooth_errors, denoise)
    if strokes not in (2, 4):
        raise LogError(f"strokes = {strokes!r}: 2 or 4")
    if not (isinstance(cylinders, (int, np.integer)) and not isinstance(cylinders, bool) and cylinders >= 1):
        raise LogError(f"cylinders = {cylinders!r}: a whole number, 1 or more")
    if tdc_deg is not None and not np.isfinite(float(tdc_deg)):
        raise LogError(f"tdc_deg = {tdc_deg!r}: need a finite angle from the gap to TDC [deg]")
    if max_order is not None and not (np.isfinite(float(max_order)) and max_order > 0):
        raise LogError(f"max_order = {max_order!r}: need a positive order")
    if max_order is not None and max_order < 2.0 / strokes - 1e-9:
        raise LogError(
            f"max_order = {max_order:g} (--max-order) keeps no order: the lowest order of a {strokes}-stroke "
            f"cycle is {2.0 / strokes:g} (one per cycle); give {2.0 / strokes:g} or more"
        )
    if points_per_cycle is not None and not (
        isinstance(points_per_cycle, (int, np.integer)) and not isinstance(points_per_cycle, bool)
    ):
        raise TypeError(f"points_per_cycle = {points_per_cycle!r}: a whole number of grid points per cycle, or None")
    if points_per_cycle is not None and points_per_cycle < 1:
        raise LogError(f"points_per_cycle = {points_per_cycle!r} (--points-per-cycle): 1 or more")
    reading: WheelReading | None = source if isinstance(source, WheelReading) else None
    if reading is not None:
        log, name = reading.log, reading.source
    else:
        log = source if isinstance(source, Log) else read_log(source, columns)
        name = log.source if isinstance(source, Log) else os.path.basename(os.fspath(source))
    revs = strokes // 2
    cycle = TWO_PI * revs
    notes = list(log.notes)  # e.g. a header line that was skipped
    track = te = edges = None
    if log.kind == "speed":
        t = log["time"]
        check_speed_time_base(t, log["rpm"], name)
        omega_s = log["rpm"] / RPM_PER_RAD_S
        phi_s = np.concatenate([[0.0], np.cumsum(0.5 * (omega_s[1:] + omega_s[:-1]) * np.diff(t))])
        t_of = CubicSpline(phi_s, t)
        w_spline = CubicSpline(phi_s, omega_s)
        omega_of = w_spline
        phi_of = PchipInterpolator(t, phi_s)
        phi_lo, phi_hi = float(phi_s[0]), float(phi_s[-1])
        if max_order is None:
            max_order = 12.0
        pitch_pts = 2 * 60  # grid default as for a 60-tooth wheel
        if phi_hi - phi_lo < TWO_PI:
            raise LogError(
                f"{name}: the speed log covers {np.rad2deg(phi_hi - phi_lo) / 360:.2f} revolutions; "
                f"a cycle needs {revs}"
            )
        tooth_errors = None
    else:
        if reading is None:
            if wheel is None:
                raise LogError(f"{name}: a wheel is needed for tooth edges (e.g. wheel='60-2', --wheel 60-2)")
            reading = read_track(log, wheel, edge=edge, name=name)
        track, edges = reading.track, reading.edges
        notes += list(reading.notes)
        wheel_choice = reading.choice("wheel")
        if wheel_choice is not None and wheel_choice.source is ChoiceSource.FOUND:
            notes.append(wheel_choice.evidence)
        edge_choice = reading.choice("edge")
        if edge_choice is not None and edge_choice.source is ChoiceSource.FOUND:
            notes.append(f"edge: {edge_choice.value} ({edge_choice.evidence})")
        if track.repairs:
            notes.append(f"edges repaired to follow the {track.wheel.spec} wheel: {repairs_summary(track.repairs)}")
        w = track.wheel
        span_rev = float((track.t.size - 1) / w.edges_per_rev)
        if span_rev < revs:
            raise LogError(
                f"{name}: the {track.t.size} tooth edges span about {span_rev:.2f} revolutions; a "
                f"{strokes}-stroke cycle needs {revs} (a longer log)"
            )
        if isinstance(tooth_errors, str) and tooth_errors == "estimate" and w.angles_deg is not None:
            measured = np.deg2rad(np.asarray(w.angles_deg)) - w.tooth_angles_rad
            te = ToothErrors(w.spec, measured, "measured (the wheel file's tooth angles)")
            tooth_errors = te
        if isinstance(tooth_errors, str) and tooth_errors == "estimate":
            if engine is not None and tdc_deg is None:
                raise LogError(
                    "engine given to take its inertia ripple out of the tooth-error estimate: give tdc_deg "
                    "as well (the angle from the gap to cylinder 1's TDC [deg])"
                )
            te = estimate_tooth_errors(
                track,
                engine_orders=engine_orders,
                strokes=strokes,
                cylinders=cylinders,
                source=name,
                engine=engine,
                tdc_deg=tdc_deg,
            )
        elif tooth_errors is None or (isinstance(tooth_errors, str) and tooth_errors == "none"):
            te = None
        elif isinstance(tooth_errors, ToothErrors):
            te = tooth_errors
        else:
            te = ToothErrors.load(tooth_errors)
        phi_e = te.angles(track) if te is not None else track.nominal_angle
        t_of = CubicSpline(phi_e, track.t)
        dt_dphi = t_of.derivative()

        def omega_of(x):
            return 1.0 / dt_dphi(x)

        phi_of = _Lazy(PchipInterpolator, track.t, phi_e)  # built only where a pressure or cam channel needs it
        phi_lo, phi_hi = float(phi_e[0]), float(phi_e[-1])
        if max_order is None:
            max_order = w.teeth / 4
        elif max_order >= w.teeth / 2:
            raise LogError(
                f"max_order = {max_order:g}: a {w.spec} wheel resolves orders below {w.teeth / 2:g} "
                f"(half its teeth per revolution)"
            )
        pitch_pts = 2 * w.teeth
    need = int(np.ceil(8 * max_order * revs))
    if points_per_cycle:
        P = int(points_per_cycle)
        if P < need:
            raise LogError(
                f"points_per_cycle = {P}: orders up to {max_order:g} need at least {need} "
                f"(--points-per-cycle), or a lower max_order (--max-order)"
            )
    else:
        P = max(pitch_pts * revs, need + need % 2)
    fine_est = max(16 * int(np.floor(max_order * revs + 1e-9)), P)
    cycles_est = int(np.ceil((phi_hi - phi_lo) / cycle)) + 1
    check_size(
        float(cycles_est) * float(fine_est) * 8.0 * ANALYSIS_ARRAYS,
        f"{name}: {cycles_est} cycles at {P} points per cycle" + (f" (δ on {fine_est})" if fine_est > P else ""),
        "give fewer points per cycle (--points-per-cycle, points_per_cycle=; default 2 per tooth pitch) or a "
        "lower max_order (--max-order)",
        error=LogError,
    )

    # --- TDC and the firing revolution
    pressure = None
    if "pressure_v" in log and log.kind != "teeth":
        t_s, p_s = log["time"], log["pressure_v"]
        inside = (t_s >= t_of(phi_lo)) & (t_s <= t_of(phi_hi))
        pressure = (phi_of(t_s[inside]), p_s[inside])
    parity_method = "two-stroke: every revolution"
    tdc_source, firing_source = PhaseSource.UNKNOWN, PhaseSource.EVERY_REVOLUTION
    parity = None
    pressure_ok = pressure is not None
    no_peak = ""
    if tdc_deg is not None:
        tdc = float(np.deg2rad(tdc_deg))
        tdc_method, tdc_source = "given", PhaseSource.GIVEN
    elif pressure is not None:
        try:
            tdc, p_parity, tdc_method = tdc_from_pressure(
                *pressure, compression_ratio=compression_ratio, rod_ratio=rod_ratio
            )
            tdc_source = PhaseSource.PRESSURE
        except NoCompressionPeak as e:
            no_peak = str(e)
            tdc, pressure_ok = 0.0, False
            tdc_method = "unknown: the pressure channel has no clear compression peak; cycles start at the gap"
            notes.append(f"{no_peak}; TDC not known: the orders' phases are relative to the gap (give tdc_deg)")
        if compression_ratio is None and pressure_ok:
            notes.append(
                "TDC is the pressure peak, which combustion puts late (13–27° on the tue-4gb10 "
                "recordings): the orders' phases and the cycle start are late by as much; give the "
                "compression ratio and rod ratio (--compression-ratio, --rod-ratio) for a fit of the "
                "compression, or tdc_deg"
            )
    else:
        tdc = 0.0
        tdc_method = (
            "unknown: cycles start at the gap" if log.kind != "speed" else "unknown: cycles start at the first sample"
        )
        notes.append(
            "TDC not known: the orders' phases are relative to the gap, not to TDC (give tdc_deg or a pressure channel)"
        )
    if strokes == 4 and tdc_deg is not None and pressure is not None and firing in ("auto", "pressure"):
        try:
            _, p_parity, _ = tdc_from_pressure(*pressure)
        except NoCompressionPeak as e:
            no_peak, pressure_ok = str(e), False
            notes.append(f"{no_peak}: the firing revolution comes from elsewhere")
    if strokes == 4:
        if firing in (0, 1):
            parity, parity_method, firing_source = int(firing), "given", PhaseSource.GIVEN
        elif firing == "pressure" and pressure is not None and not pressure_ok:
            raise LogError(f"{name}: firing='pressure': {no_peak}; give firing=0 or 1 (--firing), or a cam channel")
        elif firing in ("auto", "pressure") and pressure_ok and pressure is not None:
            # p_parity: the revolutions holding the TDC found from the pressure (a given TDC lies in the same
            # compression)
            parity, parity_method = p_parity, "pressure: revolutions with the compression peak"
            firing_source = PhaseSource.PRESSURE
        elif (
            firing in ("auto", "cam")
            and ("cam_v" in log or "cam_d" in log)
            and (cam_parity := _cam_parity(name, log, edge, t_of, phi_of, phi_lo, phi_hi, tdc, firing == "cam", notes))
            is not None
        ):
            parity, parity_method = cam_parity, "cam: the first TDC after each cam edge"
            firing_source = PhaseSource.CAM
        elif firing in ("auto", "speed"):
            parity, sep = _speed_parity(omega_of, phi_lo, phi_hi, tdc)
            parity_method = f"speed: the revolution that speeds up more after TDC (separation {sep:.1f} σ)"
            firing_source = PhaseSource.SPEED
            if sep < 1.0:
                notes.append(
                    "the firing revolution is uncertain from the speed alone: the half orders' phases may be off by π"
                )
        else:
            raise LogError(
                f"firing = {firing!r}: 'auto', 'pressure', 'cam', 'speed', 0 or 1"
                + (" (no such channel in the log)" if firing in ("pressure", "cam") else "")
            )
        # firing TDC at 2π·r + tdc for r of this parity; the cycle starts 2π before
        base = tdc + TWO_PI * parity - TWO_PI
    else:
        base = tdc
    k0 = int(np.ceil((phi_lo - base) / cycle - 1e-12))
    k1 = int(np.floor((phi_hi - base) / cycle + 1e-12)) - 1
    if k1 < k0:
        span = (phi_hi - phi_lo) / TWO_PI
        raise LogError(
            f"{name}: no complete {strokes}-stroke cycle: the edges span {span:.2f} revolutions and a "
            f"cycle ({revs} revolution{'s' if revs > 1 else ''}) starting at TDC must lie inside"
        )
    starts = base + cycle * np.arange(k0, k1 + 1)
    C = starts.size

    # --- the speed on the uniform grid of each cycle
    psi = np.arange(P) * cycle / P
    grid = starts[:, None] + psi[None, :]
    omega = np.asarray(omega_of(grid))
    ends_t = t_of(np.concatenate([starts, [starts[-1] + cycle]]))
    t_start = ends_t[:-1]
    mean_omega = cycle / np.diff(ends_t)
    # each cycle's harmonics with its linear trend (from its neighbours' mean speeds) removed: the same code as
    # a simulated run's (rotor.cycles), so that logged and simulated orders and δ compare
    X = cycle_spectrum(omega, mean_omega, cycle)
    kmax = int(np.floor(max_order * revs + 1e-9))
    k = np.arange(1, kmax + 1)
    orders = k / revs
    amp, phase = np.abs(X[:, 1 : kmax + 1]), np.angle(X[:, 1 : kmax + 1])
    # δ of the speed rebuilt from its orders up to max_order, each weighted by its signal-to-noise ratio, on
    # an 8× finer grid
    gain = np.ones(kmax + 1)
    if denoise and track is not None:
        gain[1:], _ = _wiener_gain(X, revs, track.wheel.teeth, kmax)
    fine = max(16 * kmax, P)
    Xf = np.zeros((C, fine // 2 + 1), complex)
    Xf[:, : kmax + 1] = X[:, : kmax + 1] * gain[None, :] * (fine / 2.0)
    Xf[:, 0] = np.real(X[:, 0]) / 2.0 * fine
    smooth = np.fft.irfft(Xf, n=fine, axis=1)  # detrended, as δ is defined (rotor.cycles)
    delta = cycle_delta(smooth.max(axis=1), smooth.min(axis=1), mean_omega)
    if te is not None and isinstance(tooth_errors, str) and not te.method.startswith("coast-down"):
        notes.append(_firing_run_note(te, cylinders, strokes, max_order, w.teeth))
    press = None
    if pressure is not None:
        ph, pv = pressure
        rel = ph - starts[0]
        inside = (rel >= 0) & (rel < cycle * C)
        press = (np.mod(rel[inside], cycle), pv[inside], np.floor(rel[inside] / cycle).astype(int))
    return LogAnalysis(
        source=name,
        kind=log.kind,
        strokes=strokes,
        cycle_rad=cycle,
        order=orders,
        t_start_s=t_start,
        mean_omega=mean_omega,
        delta=delta,
        amplitude_rad_s=amp,
        phase_rad=phase,
        omega=omega,
        cycle_start_rad=starts,
        tdc_rad=float(tdc),
        tdc_method=tdc_method,
        tdc_source=tdc_source,
        firing_source=firing_source,
        firing_parity=parity,
        firing_method=parity_method,
        max_order=float(max_order),
        track=track,
        tooth_errors=te,
        edges=edges,
        pressure=press,
        notes=tuple(notes),
        cylinders=int(cylinders),
        delta_weight=gain[1:],
        reading=reading,
    )
