"""Crank-angle-resolved speed, δ and order spectra from a logged wheel signal.

The pipeline of :func:`analyze_log`:

1. tooth edges: the ``tooth_time_s`` column, or found in ``encoder_v``
   (:func:`rotor.logs.edges.find_edges`), read and placed on the wheel
   (:func:`rotor.logs.track.read_track`);
2. the crank angle (:mod:`rotor.logs.angle`): each edge's angle corrected by the wheel's
   tooth-spacing errors (estimated from the log, given, or none);
3. time as a function of angle, t(φ), a cubic spline through the edges; the speed is
   ω(φ) = 1/t'(φ) [rad/s], sampled on a uniform grid of each engine cycle;
4. the cycles: 0 = TDC of cylinder 1 at the start of intake, 360° = firing TDC (rotor's
   convention; a two-stroke cycle is one revolution from TDC). The angle from the gap
   to TDC is given or found from a pressure channel (:mod:`rotor.logs.phasing`); the
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
import os
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..checks import check_size
from ..cycles import cycle_delta, cycle_spectrum
from ..errors import LogError
from ..results import Result, json_safe
from ..units import RPM_PER_RAD_S
from .angle import CrankAngle, ToothErrorPlan, firing_run_note, pattern_angle, speed_angle, tooth_angle
from .edges import Edges
from .phasing import (
    PEAK_TO_NOISE_MIN,
    PEAK_WIDTH_MAX_DEG,
    NoCompressionPeak,
    PhaseRequest,
    PhaseSource,
    find_phase,
    tdc_from_pressure,
)
from .reader import Log, read_log
from .recording import PatternReading, ReadingRecord, read_wheel, reading_record
from .track import ChoiceSource, WheelReading
from .wheel import ToothErrors, ToothTrack, Wheel

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
ANALYSIS_ARRAYS = 8
"""Float64 arrays of (cycles × points per cycle) the analysis holds at once, for the size check."""


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

    **Wheel:** ``track`` (:class:`rotor.logs.wheel.ToothTrack`, ``None`` for a speed log
    or a catalogue pattern), ``pattern`` (:class:`rotor.logs.recording.PatternReading`, where
    the wheel is a catalogue pattern other than a missing-tooth wheel, else ``None``),
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
    pattern: PatternReading | None = None

    # ------------------------------------------------------------------ numbers
    @property
    def reading_record(self) -> ReadingRecord | None:
        """How the wheel was read (:class:`rotor.logs.recording.ReadingRecord`; None for a
        speed log): ``analyze_log(other, as_read=…)`` reads another recording the same way."""
        placed = self.pattern if self.pattern is not None else self.reading
        return None if placed is None else reading_record(placed)

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
        if self.pattern is not None:
            wheel = self.pattern.to_json_dict()
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
        if self.pattern is not None:
            pr = self.pattern
            lines.append(
                f"  wheel {pr.pattern.name} ({pr.pattern.title}): {pr.fit.t.size} edges of {pr.channel} "
                f"({pr.edges}), {pr.fit.turns:.1f} turns, {pr.fit.kept:.0%} of the edges kept"
            )
            lines.append(
                f"  read as {pr.pins()}" + (" (found from the signal; this option pins it)" if pr.found else "")
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


def _check_types(source, wheel, tdc_deg, max_order, points_per_cycle, engine, tooth_errors, denoise):
    """TypeError naming the argument of :func:`analyze_log` that has the wrong type."""
    from .recording import PatternReading
    from .track import WheelReading

    model = sys.modules.get("rotor.engine.model")  # not imported: no Engine was made, and JAX stays out

    if not isinstance(source, (str, os.PathLike, Log, WheelReading, PatternReading)):
        raise TypeError(
            f"source = {source!r}: a log file's name (str or os.PathLike) or a rotor.Log, not {type(source).__name__}"
        )
    if wheel is not None and not isinstance(wheel, (str, Wheel, int, np.integer)):
        raise TypeError(f"wheel = {wheel!r}: a spec such as '60-2' or a rotor.Wheel, not {type(wheel).__name__}")
    for key, v in (("tdc_deg", tdc_deg), ("max_order", max_order)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating))):
            raise TypeError(f"{key} = {v!r}: a number or None, not {type(v).__name__}")
    if engine is not None and (model is None or not isinstance(engine, model.Engine)):
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
    as_read: ReadingRecord | None = None,
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
    - ``as_read``: a :class:`rotor.logs.recording.ReadingRecord` (a calibration's, or
      :attr:`LogAnalysis.reading_record` of another recording of the installation): the wheel
      is read the same way (its wheel and edges), or refused naming what differs.

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
    _check_types(source, wheel, tdc_deg, max_order, points_per_cycle, engine, tooth_errors, denoise)
    if as_read is not None and not isinstance(as_read, ReadingRecord):
        raise TypeError(f"as_read: a ReadingRecord (a LogAnalysis's reading_record), not {type(as_read).__name__}")
    _check_values(strokes, cylinders, tdc_deg, max_order, points_per_cycle)
    reading, pattern_reading, log, name = _source(source, columns)
    revs = strokes // 2
    if log.kind == "speed":
        angle = speed_angle(log, name, revs)
    else:
        if reading is None and pattern_reading is None:
            placed = read_wheel(log, wheel, edge=edge, name=name, as_read=as_read)
            if isinstance(placed, PatternReading):
                pattern_reading, log = placed, placed.log
            else:
                reading = placed
        if pattern_reading is not None:
            angle = pattern_angle(pattern_reading.fit, name, strokes, pattern_reading.notes())
        else:
            assert reading is not None
            plan = ToothErrorPlan(tooth_errors, engine_orders, strokes, cylinders, engine, tdc_deg)
            angle = tooth_angle(reading, name, plan)
    max_order = _max_order(angle, max_order)
    P = _points_per_cycle(name, angle, strokes, max_order, points_per_cycle)
    request = PhaseRequest(strokes, tdc_deg, firing, edge, compression_ratio, rod_ratio)
    phase = find_phase(name, log, angle, request)
    starts = _cycle_starts(name, angle, phase.base, strokes)
    speed = _cycle_speed(angle, starts, P, max_order, revs, denoise)
    notes = [*log.notes, *angle.notes, *phase.notes]  # log.notes: e.g. a header line that was skipped
    te = angle.tooth_errors
    if te is not None and isinstance(angle.tooth_errors_asked, str) and not te.method.startswith("coast-down"):
        notes.append(firing_run_note(te, cylinders, strokes, max_order))
    return LogAnalysis(
        source=name,
        kind=log.kind,
        strokes=strokes,
        cycle_rad=TWO_PI * revs,
        order=speed.order,
        t_start_s=speed.t_start,
        mean_omega=speed.mean_omega,
        delta=speed.delta,
        amplitude_rad_s=speed.amplitude,
        phase_rad=speed.phase,
        omega=speed.omega,
        cycle_start_rad=starts,
        tdc_rad=float(phase.tdc),
        tdc_method=phase.tdc_method,
        tdc_source=phase.tdc_source,
        firing_source=phase.firing_source,
        firing_parity=phase.parity,
        firing_method=phase.parity_method,
        max_order=float(max_order),
        track=angle.track,
        tooth_errors=te,
        edges=angle.edges,
        pressure=_pressure_per_cycle(phase.pressure, starts, TWO_PI * revs),
        notes=tuple(notes),
        cylinders=int(cylinders),
        delta_weight=speed.weight,
        reading=angle.reading,
        pattern=pattern_reading,
    )


def _source(source, columns) -> tuple[WheelReading | None, PatternReading | None, Log, str]:
    """(the wheel reading given, the pattern reading given, the log, its name) of
    :func:`analyze_log`'s ``source``: a reading, a :class:`Log` or a file read here."""
    if isinstance(source, WheelReading):
        return source, None, source.log, source.source
    if isinstance(source, PatternReading):
        return None, source, source.log, source.source
    if isinstance(source, Log):
        return None, None, source, source.source
    return None, None, read_log(source, columns), os.path.basename(os.fspath(source))


def _check_values(strokes, cylinders, tdc_deg, max_order, points_per_cycle) -> None:
    """LogError naming the argument of :func:`analyze_log` whose value cannot be used."""
    if strokes not in (2, 4):
        raise LogError(f"strokes={strokes!r}: 2 or 4", argument="strokes")
    if not (isinstance(cylinders, (int, np.integer)) and not isinstance(cylinders, bool) and cylinders >= 1):
        raise LogError(f"cylinders={cylinders!r}: a whole number, 1 or more", argument="cylinders")
    if tdc_deg is not None and not np.isfinite(float(tdc_deg)):
        raise LogError(f"tdc_deg={tdc_deg!r}: need a finite angle from the gap to TDC [deg]", argument="tdc_deg")
    if max_order is not None and not (np.isfinite(float(max_order)) and max_order > 0):
        raise LogError(f"max_order={max_order!r}: need a positive order", argument="max_order")
    if max_order is not None and max_order < 2.0 / strokes - 1e-9:
        raise LogError(
            f"max_order={max_order:g}: keeps no order: the lowest order of a {strokes}-stroke "
            f"cycle is {2.0 / strokes:g} (one per cycle); give {2.0 / strokes:g} or more",
            argument="max_order",
        )
    if points_per_cycle is not None and not (
        isinstance(points_per_cycle, (int, np.integer)) and not isinstance(points_per_cycle, bool)
    ):
        raise TypeError(f"points_per_cycle = {points_per_cycle!r}: a whole number of grid points per cycle, or None")
    if points_per_cycle is not None and points_per_cycle < 1:
        raise LogError(f"points_per_cycle={points_per_cycle!r}: 1 or more", argument="points_per_cycle")


def _max_order(angle: CrankAngle, max_order: float | None) -> float:
    """The highest order reported: the default of the wheel (or speed log), or the one
    given, below half the wheel's teeth per revolution."""
    if max_order is None:
        return angle.default_max_order
    w = None if angle.track is None else angle.track.wheel
    if w is not None and max_order >= w.teeth / 2:
        raise LogError(
            f"max_order={max_order:g}: a {w.spec} wheel resolves orders below {w.teeth / 2:g} "
            f"(half its teeth per revolution)",
            argument="max_order",
        )
    return max_order


MIN_POINTS_PER_CYCLE = 16
"""The fewest points of a cycle's uniform angle grid by default [-] (a cam pattern of four
edges gives eight a cycle at two a pitch; the identification of a diagnosis needs 16)."""


def _points_per_cycle(name, angle: CrankAngle, strokes, max_order, points_per_cycle) -> int:
    """The grid's points per cycle: given (enough for ``max_order``), or two per tooth pitch
    and 8 per period of ``max_order``, at least :data:`MIN_POINTS_PER_CYCLE`; checked against
    the memory budget."""
    revs = strokes // 2
    need = int(np.ceil(8 * max_order * revs))
    if points_per_cycle:
        P = int(points_per_cycle)
        if P < need:
            raise LogError(
                f"points_per_cycle={P}: orders up to {max_order:g} need at least {need}, or a lower order limit (max_order=)",
                argument="points_per_cycle",
            )
    else:
        P = max(angle.pitch_points * revs, need + need % 2, MIN_POINTS_PER_CYCLE)
    fine_est = max(16 * int(np.floor(max_order * revs + 1e-9)), P)
    cycles_est = int(np.ceil((angle.phi_hi - angle.phi_lo) / (TWO_PI * revs))) + 1
    check_size(
        float(cycles_est) * float(fine_est) * 8.0 * ANALYSIS_ARRAYS,
        f"{name}: {cycles_est} cycles at {P} points per cycle" + (f" (δ on {fine_est})" if fine_est > P else ""),
        "give fewer points per cycle (points_per_cycle=; default 2 per tooth pitch) or a lower order limit (max_order=)",
        error=LogError,
    )
    return P


def _cycle_starts(name, angle: CrankAngle, base: float, strokes: int) -> np.ndarray:
    """The wheel angle of each complete cycle's start, the cycles ``base`` + k·cycle inside
    the recording."""
    revs = strokes // 2
    cycle = TWO_PI * revs
    k0 = int(np.ceil((angle.phi_lo - base) / cycle - 1e-12))
    k1 = int(np.floor((angle.phi_hi - base) / cycle + 1e-12)) - 1
    if k1 < k0:
        span = (angle.phi_hi - angle.phi_lo) / TWO_PI
        raise LogError(
            f"{name}: no complete {strokes}-stroke cycle: the edges span {span:.2f} revolutions and a "
            f"cycle ({revs} revolution{'s' if revs > 1 else ''}) starting at TDC must lie inside"
        )
    return base + cycle * np.arange(k0, k1 + 1)


@dataclasses.dataclass(frozen=True)
class _CycleSpeed:
    """Each cycle's speed on its grid, start time, mean speed, orders and δ (with the weight
    of each order in δ)."""

    omega: np.ndarray
    t_start: np.ndarray
    mean_omega: np.ndarray
    order: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    delta: np.ndarray
    weight: np.ndarray


def _cycle_speed(angle: CrankAngle, starts, P: int, max_order: float, revs: int, denoise: bool) -> _CycleSpeed:
    """The speed on the uniform grid of each cycle, its harmonics by engine order and δ."""
    cycle = TWO_PI * revs
    C = starts.size
    psi = np.arange(P) * cycle / P
    grid = starts[:, None] + psi[None, :]
    omega = np.asarray(angle.omega_of(grid))
    ends_t = angle.t_of(np.concatenate([starts, [starts[-1] + cycle]]))
    mean_omega = cycle / np.diff(ends_t)
    # each cycle's harmonics with its linear trend (from its neighbours' mean speeds) removed: the same code as
    # a simulated run's (rotor.cycles), so that logged and simulated orders and δ compare
    X = cycle_spectrum(omega, mean_omega, cycle)
    kmax = int(np.floor(max_order * revs + 1e-9))
    k = np.arange(1, kmax + 1)
    # δ of the speed rebuilt from its orders up to max_order, each weighted by its signal-to-noise ratio, on
    # an 8× finer grid
    gain = np.ones(kmax + 1)
    if denoise and angle.teeth is not None:
        gain[1:], _ = _wiener_gain(X, revs, angle.teeth, kmax)
    fine = max(16 * kmax, P)
    Xf = np.zeros((C, fine // 2 + 1), complex)
    Xf[:, : kmax + 1] = X[:, : kmax + 1] * gain[None, :] * (fine / 2.0)
    Xf[:, 0] = np.real(X[:, 0]) / 2.0 * fine
    smooth = np.fft.irfft(Xf, n=fine, axis=1)  # detrended, as δ is defined (rotor.cycles)
    return _CycleSpeed(
        omega=omega,
        t_start=ends_t[:-1],
        mean_omega=mean_omega,
        order=k / revs,
        amplitude=np.abs(X[:, 1 : kmax + 1]),
        phase=np.angle(X[:, 1 : kmax + 1]),
        delta=cycle_delta(smooth.max(axis=1), smooth.min(axis=1), mean_omega),
        weight=gain[1:],
    )


def _pressure_per_cycle(pressure, starts, cycle) -> tuple | None:
    """The pressure samples of the complete cycles: (cycle angle [rad], signal, cycle index)."""
    if pressure is None:
        return None
    ph, pv = pressure
    rel = ph - starts[0]
    inside = (rel >= 0) & (rel < cycle * starts.size)
    return (np.mod(rel[inside], cycle), pv[inside], np.floor(rel[inside] / cycle).astype(int))


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
