"""A streaming misfire monitor: tooth times in, one verdict per firing out, in bounded memory.

:class:`MisfireMonitor` is what an engine controller runs on the crank-tooth timing while
the engine turns: it is fed tooth edge times [s] in chunks of any size
(:meth:`MisfireMonitor.feed`) and hands back a :class:`Verdict` for each cylinder firing
as soon as that firing is decided, about a firing segment after its TDC. At the end
(:meth:`MisfireMonitor.close`) it gives what is still pending, and
:meth:`MisfireMonitor.result` a per-cylinder summary (:class:`MonitorResult`).

**The wheel.** The monitor places each edge on the wheel as it arrives. It finds the
wheel's gap on the first ``2·(N−M)+3`` edges with :func:`rotor.logs.pattern.locate_teeth`
(the same reader as ``rotor analyze``), then follows the pattern edge by edge: each
tooth period per tooth pitch must lie within a factor :data:`PERIOD_TOLERANCE` of the one
before it (the gap spans its missing pitches). An edge that breaks the pattern (a missed
or extra edge, a glitch, a hole in the data, the engine stopping) loses the wheel; this
is reported (:class:`NoteKind`) and the gap is found again on the next edges, the
revolution count carried across the loss from the last speed. Firings whose segment
falls into a loss are not judged, and are counted.

**Angles.** Cylinder 1's TDC lies ``tdc_deg`` after the gap (a recorded log states it in
its header, ``# tdc_after_gap_deg``; :func:`rotor.diagnostics.stated.stated_phase`), and
``firing_parity`` says which revolutions, counted from the first gap, hold its firing
TDC. Cycles count from 1: cycle 1 is the first that starts (cylinder 1's TDC before
intake) after the first edge placed; the firing of cylinder c in cycle k is the one at
θ_fire,c + (k − 1)·Θ as :mod:`rotor.dynamics.combustion` counts it, so that the verdicts
name the (cycle, cylinder) pairs of ``rotor simulate --misfire``.

**The index** (model-free; the same with and without an engine file). Over each firing's
segment (``segment_deg``; by default the angle to the next firing, at most 180°, so that an
uneven firing order gives each firing its own), the crank speed at the two ends (each
averaged over a window of a quarter of the segment) gives the change of kinetic energy
relative to the mean,

    e = (ω_end² − ω_start²) / ω_mean²,

the work the firing did over its segment less what the load took, per unit of kinetic
energy: a misfire loses the firing's work and e drops. **Where the segment starts**: at
TDC + (180° − segment)/8 (0° for a segment of 180°, 7.5° for 120°, 11.25° for a V8's 90°).
A firing's combustion torque is nought at its TDC, peaks 30–33° after it and fades towards
BDC (43–46 % of its work done by 45° after TDC, 82–83 % by 90°, in the combustion tables
of the 4chn15, mwm6 and v8 presets); the next firing's begins at the next TDC. Moving the
segment later gains the firing's tail and loses its start, and takes more of the next
firing. With the two speed windows weighed in, for segments of 45°–144° this start keeps
within 1.5 % of the most of the firing's own combustion work any start keeps, and lies
between that start and the later one that best sets it apart from its neighbours: on a
V8, 84 % of its own work and at most 14 % of a neighbour's (the firing before: its tail). Centred on the expansion stroke (from TDC + (180° − segment)/2)
a V8's segment held 54 % of its firing's work and 42 % of the next one's, and a misfire's
loss split between the two (``benchmarks/monitor_agreement.py``: the firing before a
misfire called on 94 of 95 V8 misfires). For a 180° segment the best start is a little
before TDC (−10°), but gains little (97.5 % at 0°). The index is e against running
robust baselines: the median m_c of the cylinder's own last :data:`OWN_HISTORY` firings
(a cylinder's e carries its own offset: the wheel's tooth errors, its place in the
firing order), less the deviation common to the firings around it: after a misfire or a
load change the speed settles over several cycles and moves every firing's e alike, which
the cylinders' medians follow only with a lag. With d = e − m_c, c is the mean d of the
next ⌊n/2⌋ firings of an n-cylinder engine (deviations beyond
±:data:`COMMON_OUTLIER`·s left out: a loss, or a gain against a baseline that a misfire in
the first cycles holds), taken off only where it stands out of its own noise:
beyond :data:`COMMON_DEAD` standard errors, by the excess (a steady run keeps every
firing's whole signal; a single cylinder has no others, and c = 0). The spread s is that of
all cylinders' last :data:`HISTORY` deviations d − c (interquartile range / 1.349, never
below ``min_spread``),

    index = (e − m_c − c) / s,

0 for a typical firing, negative for a loss; a firing is a **misfire** where
index < −``threshold``, unless a neighbouring firing lost more than twice as much (then the
loss is that firing's, spilt into this segment). Each verdict waits for the next ⌊n/2⌋ + 1
firings' segments (half a cycle and a firing; the latest, of the cycle's last firing,
about three quarters of a cycle after its cycle's end). Its uncertainty ``index_std`` is
the spread of a normal firing's index, 1 by construction, with the cylinder's median's own
uncertainty (√(1 + π/(2n)) for a median of n). The first firings wait until every
cylinder has :data:`MIN_OWN` firings (about three cycles), then are judged together: their
``decided_at_s`` says so. **The first spreads** are not trusted on their own: the first
firings' deviations go into the spread against the median of their cylinder's *other*
values (a value is not its own baseline: with three values one deviation would be 0 by
construction, and a lead-in copied from the first cycle, as ``rotor simulate --record``
writes it, made two of three 0, the spread collapsed and normal firings were called
misfires), and until :data:`HISTORY` firings have been measured against baselines before
them the spread is at least that of the last :data:`HISTORY` values of e themselves, all
cylinders together (their offsets in it: larger, so that a young baseline calls fewer
misfires, never more). A verdict still comes within a cycle of its cycle's end once warm,
and a misfire in the first cycles is still found where it stands out of that spread; one
in the run's first cycle whose copy is the lead-in is in its own baseline twice and is
missed. A deviation beyond ±:data:`COMMON_OUTLIER` spreads is left out of the common one
both ways: a loss (another misfire), and a gain (a firing against a baseline that a misfire
holds: one in a recording's first cycle, whose copy is its lead-in, gave its cylinder a
misfire's median, its next firings gains of 50 spreads, and the firings before them false
calls; an idling 4B11's weak firing was called at −10 where the firing after it gained
several spreads, −6 without that gain). How it detects over speed, load, cylinders and
wheels, against the published detectors at the same false alarms on the same runs:
``benchmarks/misfire_detection.py``.
This is the crankshaft speed-fluctuation approach of the on-board monitors (Plapp,
Klenk, Moser: "Methods of on-board misfire detection", SAE 900232; Klenk, Moser, Müller,
Wimmer: "Misfire detection by evaluating crankshaft speed — a means to comply with
OBDII", SAE 930399), with robust running baselines in place of a calibrated map.

**With an engine** (``engine=``): the engine file gives the cylinders, the strokes and
each cylinder's firing angle (an uneven firing order included), and each verdict carries
the firing's **IMEP from the engine model** (``imep_pa``, ``imep_std_pa``): the inverse of
the equation of motion over the firing's segment, from its TDC to the next firing (at most
180°). With E = ½·I(θ)·ω² the equation I(θ)·dω/dt + ½·I′(θ)·ω² = M_gas − M_load reads
dE/dθ = M_motored(θ) + Σ_c s_c·ΔM_c(θ) − M_load, so over the segment

    E(θ) = E₀ + s·∫ΔM_c + ∫(M_motored + Σ_other s_c'·ΔM_c') − L·(θ − θ_TDC),

linear in the firing's combustion scale s, the kinetic energy E₀ at its TDC and the
segment's load and friction torque L (constant over a segment: its speed changes by a
percent or two). The speed is measured over :data:`MODEL_WINDOWS` windows tiling the
segment (E = ½·J·ω², J the square of the window's mean √I(θ), so that a window's time is
read as the engine makes it), the tables (I(θ), the motored and each combustion torque)
are those of :func:`rotor.crank_train`, the other cylinders' combustion in the segment (the
tail of the firing before) is taken at their last estimated scale, and the least-squares
solution of each firing slot is precomputed: a chunk's firings cost one stacked product. The
IMEP is the cylinder's motored IMEP plus s times its combustion IMEP, and ``imep_std_pa``
the least-squares standard error of s from the fit's residual (the speed noise that is not
common to the windows; a wheel's tooth errors, the same every cycle, bias the IMEP of a
slot and are not in it). On a simulated 4chn15 recording (perfect wheel, 20 ns of timer
noise) the IMEP of each firing is within 0.1 bar of what was simulated at full and at half
fuelling, a misfire's within 0.05 bar of its motored IMEP. The misfire verdict stays on
the model-free index (it needs no calibration of the model to the engine). This is the
per-cylinder torque estimate from the crank's angular acceleration with variable inertia
(Rizzoni, "Estimate of indicated torque from crankshaft speed fluctuations: a model for
the dynamics of the IC engine", IEEE Trans. Vehicular Technology 38 (1989)), solved per
firing by least squares instead of by deconvolution. Without an engine: ``cylinders``,
``firing_order`` and ``strokes``, evenly spaced firings, and no IMEP (NaN).

**Checks** (:class:`MisfireMonitor`'s doc): a wheel with too few teeth per firing is
refused when the monitor is made; the first edges' time base (the speed they imply, the
resolution of their stamps) as ``rotor analyze`` checks a log's; with an engine, the model's
IMEP of the first firings (an engine that does not fit the log is refused); the speed's
strongest order against the engine's firing frequency (the verdicts flagged where it is
not of the firings). :class:`ToothLines` reads text in bounded memory and linear time
whatever its line ends, converts the units a header names, and refuses a sampled signal.

**Misfire rates and codes** (:mod:`rotor.diagnostics.misfire_rate`): every verdict is
counted into the windows of the OBD regulations, 200 revolutions against a catalyst-damage
rate read from a table over speed and load (the load, with an engine, the model's mean IMEP
of the window's fired firings over the file's full IMEP) and 1000 revolutions against an
emission rate, judged every 200 revolutions (``thresholds``:
:class:`rotor.diagnostics.misfire_rate.MisfireThresholds`); each window judged (its rate,
threshold, and where reached its code, P0301 … for one cylinder, P0300 for two or more) is
handed out by :meth:`MisfireMonitor.pop_windows`, the exceeded ones summarised in the result;
a stream shorter than a window is judged over what it has at :meth:`MisfireMonitor.close`.

**Memory.** The edges are kept for the current firing segment and one revolution before
it (dropped once more than two revolutions are held; a chunk longer than
:data:`SLICE_REVOLUTIONS` revolutions is taken in slices; in a run's first
:data:`FIT_CYCLES` whole cycles, until the speed's orders are read over them, from the
first of them), the baselines hold :data:`HISTORY` + :data:`OWN_HISTORY` per cylinder
numbers, the notes at most :data:`MAX_NOTES`, the windows a fixed ring of the longer
window's firings: nothing grows with the length of the stream.

**Speed.** A chunk costs a few numpy operations on all its edges at once (the wheel's
pattern checked on every tooth period, one interpolation for every time its firings need)
and a few lines of Python per firing (a handful more for the rate windows: five array
writes, and every 200 revolutions a count over the window's firings): a V8 at 8000 rpm on
a 60-2 wheel, fed a revolution at a time, with the windows and codes, runs 137× faster than
real time on one core (CPU time, median of 15 runs; 155× without the windows, measured beside
it), 92× with an engine file (the model's IMEP of every firing), by
``benchmarks/misfire_detection.py --throughput-only`` on a shared 2-core machine; the margin
moves with the machine's speed.

Hand-written, not borrowed: no library follows a trigger wheel edge by edge.
"""

from __future__ import annotations

import bisect
import collections
import dataclasses
import enum
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import EngineError, LogError
from ..results import Result
from ..units import PA_PER_BAR

__all__ = [
    "HISTORY",
    "MAX_LINE_CHARS",
    "MAX_NOTES",
    "MAX_WINDOWS_HELD",
    "MIN_TEETH_PER_SEGMENT",
    "PERIOD_TOLERANCE",
    "SLICE_REVOLUTIONS",
    "DEFAULT_THRESHOLD",
    "MisfireMonitor",
    "MonitorResult",
    "Note",
    "NoteKind",
    "ToothLines",
    "Verdict",
    "check_wheel",
]

HISTORY = 32
"""Firings in the running spread (of e − its cylinder's median, all cylinders)."""
OWN_HISTORY = 8
"""Firings of each cylinder in its own baseline (the median of its e)."""
MIN_OWN = 3
"""Firings of every cylinder before verdicts are given (the earlier firings wait for them)."""
COMMON_OUTLIER = 5.0
"""Deviations beyond this many spreads (a loss, or a gain against a baseline that a misfire
holds) are left out of the common deviation."""
COMMON_DEAD = 1.0
"""The common deviation is taken off only beyond this many of its standard errors."""
DEFAULT_THRESHOLD = 8.0
"""A misfire: index below minus this many baseline spreads."""
DEFAULT_MIN_SPREAD = 2e-4
"""The smallest baseline spread of e [-] (a noise-free run would otherwise have none)."""
PERIOD_TOLERANCE = 1.6
"""Largest factor between neighbouring tooth periods per pitch while the wheel is followed."""
SLICE_REVOLUTIONS = 4
"""A chunk is taken in slices of at most this many revolutions of edges."""
MAX_NOTES = 1000
"""Notes kept (the oldest are dropped beyond this; each is also handed out as it comes)."""
MAX_WINDOWS_HELD = 100
"""Windows judged and not yet handed out (:meth:`MisfireMonitor.pop_windows`) kept at most
(the oldest dropped: a consumer that never asks for them holds no more)."""
MODEL_WINDOWS = 8
"""Speed windows over a firing's segment for the model's IMEP (with an engine)."""
MIN_TEETH_PER_SEGMENT = 4
"""The fewest wheel teeth over a firing's segment (its speed windows a quarter of it each)."""
RESOLUTION_NOTE = 0.001
"""Time stamps that resolve more than this share of the tooth period are noted."""
RESOLUTION_REFUSE = 0.003
"""Time stamps that resolve more than this share of the tooth period are refused: stricter than
``rotor analyze`` (2 %, :data:`rotor.logs.plausibility.RESOLUTION_REFUSE`), as a firing's index
reads the speed over windows of a few teeth (a simulated 4chn15 recording on a 60-2 wheel,
its times offset to resolve 0.24 %, 0.48 % and 1 % of the tooth period: no false misfire, 2
and 6)."""
FIT_SCALE_LOW = -0.3
"""The lowest plausible combustion scale of a firing (0 a misfire), by the model (with an engine)."""
FIT_SCALE_HIGH = 3.0
"""The highest plausible combustion scale of a firing (1 the engine file's full pressure)."""
FIT_SHARE = 0.25
"""The engine does not fit where more than this share of the first firings are implausible."""
FIT_CYCLES = 3
"""Whole cycles of speed whose orders are read for the engine's firing frequency."""
FIT_Z = 6.0
"""The strongest order is read only where its mean over the cycles is this many of its
standard errors (the same in every cycle: the firings', not the noise's)."""
TWO_PI = 2.0 * math.pi


class NoteKind(enum.Enum):
    """What a :class:`Note` reports."""

    FOUND = "found"  # the wheel's gap found: edges placed from here
    LOST = "lost"  # an edge broke the wheel's pattern: the wheel is lost
    NO_WHEEL = "no_wheel"  # the edges so far do not follow the wheel: dropped, looking again
    BACKWARDS = "backwards"  # an edge time not after the one before: skipped
    NOT_TIME = "not_time"  # a value that is not a finite time: skipped
    BAD_LINE = "bad_line"  # a line of text that is not a time: skipped
    NOT_JUDGED = "not_judged"  # firings whose segment fell into a loss of the wheel
    UNITS = "units"  # the header names the times' unit: converted to seconds
    TIME_BASE = "time_base"  # the time stamps resolve the tooth period coarsely (a note)
    ENGINE_FIT = "engine_fit"  # the speed's orders do not show the engine's firings: the verdicts flagged from then


NOTE_MEANING = {
    "found": "the wheel's gap found: edges placed from there",
    "lost": "an edge broke the wheel's pattern: the wheel lost",
    "no_wheel": "edges that do not follow the wheel: dropped",
    "backwards": "edge times not after the one before: skipped",
    "not_time": "values that are not finite times: skipped",
    "bad_line": "lines that are not a time: skipped",
    "not_judged": "firings whose segment fell into a loss of the wheel",
    "units": "the times converted to seconds from the unit the header names",
    "time_base": "time stamps that resolve the tooth period coarsely",
    "engine_fit": "the speed's orders do not show the engine's firings",
}
"""What each :class:`NoteKind` reports, in words (the summary's list of notes)."""


@dataclasses.dataclass(frozen=True)
class Note:
    """Something the monitor met in the stream: ``kind``, the log time ``t_s`` [s] (None
    where not known) and the words."""

    kind: NoteKind
    t_s: float | None
    text: str

    def to_json_dict(self) -> dict:
        return {"note": self.kind.value, "t_s": self.t_s, "text": self.text}


@dataclasses.dataclass(slots=True)
class Verdict:
    """The verdict on one firing.

    ``cycle``, ``cylinder``: from 1; ``misfire``; ``index``: the firing's energy change
    against the running baseline, in baseline spreads (0 typical, negative a loss) and
    ``index_std`` its uncertainty; ``energy``: the raw e = (ω_end² − ω_start²)/ω_mean²
    [-]; ``cycle_end_s``: the log time at which the firing's cycle ends [s] (predicted
    from the last speed where the cycle had not ended when the verdict was given,
    ``cycle_end_predicted``); ``decided_at_s``: the log time of the edge with which the
    verdict was given [s]: the last edge its firing and the firings after it used (the first
    firings, which wait for every cylinder's baseline, the edge that completed them; at the
    end of the stream, the last edge measured), never before the data it needed;
    ``imep_pa``, ``imep_std_pa``: with an engine, the firing's IMEP from the engine model
    and its standard error [Pa] (NaN without one); ``swing``: the speed's rise from the
    firing's TDC to half its segment after, (ω²(TDC + Θ/2) − ω²(TDC))/ω_mean² [-] (Θ the
    segment, each speed over a window of Θ/4). With E = ½·I(θ)·ω², it is the work done about
    the TDC (the cylinder's compression given back, its combustion, less the load) over
    the kinetic energy, less the relative change of the inertia I(θ) over the same angle
    (the reciprocating masses: the same at every speed). Cranking, the compression rules:
    a cylinder that compresses slows the crank into its TDC and speeds it up after, one
    that does not (a plug out, a valve held open) has almost none (a Mitsubishi 6G75
    cranked at 150 rpm: 1.34 with its plugs in, 0.002 with them out). At speed, a
    misfire's swing falls below every fired one's. The misfire verdict does not use it.
    ``engine_doubt``: the speed's orders did not show the engine's firings (see
    :class:`MisfireMonitor`, **The engine's fit**): the verdict may be on the wrong angles.
    ``claimed_by``: ``"previous"`` or ``"next"`` where the index is below −threshold but the
    firing is not called a misfire because that neighbour lost more than twice as much (its
    index ``neighbour_index``: the loss is the neighbour's, spilt into this segment); None
    where the neighbour rule did not decide the verdict.
    """

    cycle: int
    cylinder: int
    misfire: bool
    index: float
    index_std: float
    energy: float
    cycle_end_s: float
    decided_at_s: float
    cycle_end_predicted: bool = False
    imep_pa: float = math.nan
    imep_std_pa: float = math.nan
    swing: float = math.nan
    engine_doubt: bool = False
    claimed_by: str | None = None
    neighbour_index: float = math.nan

    def to_json_dict(self) -> dict:
        return {
            "cycle": self.cycle,
            "cylinder": self.cylinder,
            "misfire": self.misfire,
            "index": _num(self.index),
            "index_std": _num(self.index_std),
            "energy": _num(self.energy),
            "cycle_end_s": _num(self.cycle_end_s),
            "cycle_end_predicted": self.cycle_end_predicted,
            "decided_at_s": _num(self.decided_at_s),
            "imep_bar": _num(self.imep_pa / PA_PER_BAR),
            "imep_std_bar": _num(self.imep_std_pa / PA_PER_BAR),
            "swing": _num(self.swing),
            "engine_doubt": self.engine_doubt,
            "claimed_by_neighbour": self.claimed_by,
            "neighbour_index": _num(self.neighbour_index),
        }

    def line(self) -> str:
        """One line for people."""
        what = "MISFIRE" if self.misfire else "fired  "
        end = f"{self.cycle_end_s:.6f} s" + (" (predicted)" if self.cycle_end_predicted else "")
        imep = (
            f"  IMEP {self.imep_pa / PA_PER_BAR:6.2f} ± {self.imep_std_pa / PA_PER_BAR:.2f} bar"
            if math.isfinite(self.imep_pa)
            else ""
        )
        return (
            f"cycle {self.cycle:5d} cylinder {self.cylinder:2d}: {what} index {self.index:+9.2f} ± "
            f"{self.index_std:.2f}{imep}  decided at {self.decided_at_s:.6f} s, cycle end {end}"
            + ("  (engine doubtful: its firings are not seen in the speed)" if self.engine_doubt else "")
            + (
                f"  (below the threshold, not called: the {self.claimed_by} firing lost more than twice as much, "
                f"index {self.neighbour_index:+.2f}: the loss is that firing's, spilt into this segment)"
                if self.claimed_by
                else ""
            )
        )


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _cell(x: float, width: int, spec: str) -> str:
    """``x`` in a column of ``width``; a dash where it is not a number (nothing measured)."""
    return f"{x:>{width}{spec}}" if math.isfinite(x) else f"{'-':>{width}}"


@dataclasses.dataclass(repr=False)
class MonitorResult(Result):
    """What a :class:`MisfireMonitor` saw, per cylinder: ``judged`` firings, ``misfires``,
    the median and lowest ``index``; ``not_judged`` (firings lost with the wheel),
    ``edges``, ``notes`` (the last :data:`MAX_NOTES`), ``note_counts`` (per kind), the
    ``threshold`` and what the firing angles came from (``source``); with an engine,
    ``median_imep_pa``, each cylinder's median IMEP over its last :data:`HISTORY` firings
    [Pa] (None without one); ``median_swing``: each cylinder's median :attr:`Verdict.swing`
    over its last :data:`HISTORY` firings [-] (a cylinder that does not compress has about
    none)."""

    cylinders: int
    judged: np.ndarray
    misfires: np.ndarray
    median_index: np.ndarray
    min_index: np.ndarray
    misfire_list: list
    not_judged: int
    edges: int
    notes: list
    note_counts: dict
    threshold: float
    source: str
    median_imep_pa: np.ndarray | None = None
    median_swing: np.ndarray | None = None
    segments: list = dataclasses.field(default_factory=list)
    """Each firing's segment, chosen by the monitor: ``(cylinder, segment_deg,
    start_after_tdc_deg)`` in firing order (the angle to the next firing, at most 180°, from
    TDC + (180° − segment)/8, where a firing's combustion work falls: the module doc)."""
    engine_doubt: bool = False
    """The speed's orders did not show the engine's firings: the verdicts are flagged
    (:attr:`Verdict.engine_doubt`)."""
    windows: dict | None = None
    """The misfire-rate windows (:meth:`rotor.diagnostics.misfire_rate.WindowCounter.summary_dict`):
    the thresholds, the windows judged and exceeded per kind, the exceeded ones; None where
    the monitor keeps no windows."""
    after_last_cycle: int = 0
    """Firings after the log's last cycle (``last_cycle``), not judged."""
    last_cycle: int | None = None
    """The log's last cycle, where it was given."""

    def summary(self) -> str:
        lines = [
            f"misfire monitor ({self.source}): {int(self.judged.sum())} firings judged, "
            f"{int(self.misfires.sum())} misfire(s), {self.edges} tooth edges",
            f"  a misfire: index < -{self.threshold:g}, unless a neighbouring firing's index is more than twice as "
            "low (the loss is then that firing's, spilt into this segment)",
            f"  {'cylinder':>8} {'judged':>7} {'misfires':>9} {'median index':>13} {'lowest index':>13}"
            f" {'median swing':>13}" + (f" {'IMEP [bar]':>11}" if self.median_imep_pa is not None else ""),
        ]
        for c in range(self.cylinders):
            # a cylinder without a judged firing has no figures: a dash, not NaN
            imep = (
                f" {_cell(self.median_imep_pa[c] / PA_PER_BAR, 11, '.2f')}" if self.median_imep_pa is not None else ""
            )
            lines.append(
                f"  {c + 1:>8} {int(self.judged[c]):>7} {int(self.misfires[c]):>9} "
                f"{_cell(self.median_index[c], 13, '.2f')} {_cell(self.min_index[c], 13, '.2f')} "
                f"{_cell(self._swing(c), 13, '.4f')}{imep}"
            )
        if self.segments:
            kinds = sorted({(seg, start) for _, seg, start in self.segments})
            lines.append(
                "  segments: "
                + ", ".join(f"{seg:g}° from {start:g}° after TDC" for seg, start in kinds)
                + " (to the next firing, at most 180°; started where a firing does its work)"
            )
        if self.misfire_list:
            shown = ", ".join(f"{k}:{c}" for k, c in self.misfire_list[:20])
            more = f" and {len(self.misfire_list) - 20} more" if len(self.misfire_list) > 20 else ""
            lines.append(f"  misfires (cycle:cylinder): {shown}{more}")
        if self.not_judged:
            lines.append(f"  {self.not_judged} firing(s) not judged: their segments fell where the wheel was lost")
        if self.engine_doubt:
            lines.append(
                "  the engine may not fit the log: the speed's strongest order is not of its firings "
                "(the verdicts are flagged; the note 'engine_fit' says more)"
            )
        if self.after_last_cycle:
            lines.append(
                f"  {self.after_last_cycle} firing(s) after the log's last cycle ({self.last_cycle}) not judged"
            )
        lines += self._window_lines()
        if self.note_counts:
            lines.append("  notes on the stream (each also given as it came, on stderr):")
            for kind, n in self.note_counts.items():
                last = next((x.text for x in reversed(self.notes) if x.kind.value == kind), "")
                lines.append(
                    f"    {kind} ({NOTE_MEANING.get(kind, kind)}) ×{n}" + (f"; the last: {last}" if last else "")
                )
        return "\n".join(lines)

    def _window_lines(self) -> list[str]:
        w = self.windows
        if w is None:
            return []
        th = w["thresholds"]
        judged, exceeded = w["windows_judged"], w["windows_exceeded_count"]
        lines = [
            f"  misfire-rate windows: catalyst {th['catalyst_revolutions']} revolutions (its table's rate at the "
            f"window's speed and load), {judged['catalyst']} judged, {exceeded['catalyst']} exceeded; emission "
            f"{th['emission_revolutions']} revolutions ({th['emission_pct']:g} % of the firings), "
            f"{judged['emission']} judged, {exceeded['emission']} exceeded; every {th['step_revolutions']} revolutions"
        ]
        shown = w["windows_exceeded"][-20:]
        for x in shown:
            part = " (partial: the recording is shorter than the window)" if x["partial"] else ""
            lines.append(
                f"    exceeded: {x['kind']} cycles {x['first'][0]}–{x['last'][0]}: {x['rate_pct']:.2f} % > "
                f"{x['threshold_pct']:.2f} %, {x['code']}{part}"
            )
        more = sum(exceeded.values()) - len(shown)
        if more > 0:
            lines.append(f"    and {more} more exceeded (the JSON keeps the last {len(w['windows_exceeded'])})")
        return lines

    def _swing(self, c: int) -> float:
        return math.nan if self.median_swing is None else float(self.median_swing[c])

    def to_json_dict(self) -> dict:
        from ..results import json_safe

        return json_safe(
            {
                "source": self.source,
                "threshold": self.threshold,
                "edges": self.edges,
                "firings_judged": int(self.judged.sum()),
                "misfire_count": int(self.misfires.sum()),
                "misfires": [list(p) for p in self.misfire_list],
                "not_judged": self.not_judged,
                "engine_doubt": self.engine_doubt,
                "misfire_rule": f"index < -{self.threshold:g}, unless a neighbouring firing's index is more than "
                "twice as low (the loss is then that firing's)",
                "last_cycle": self.last_cycle,
                "after_last_cycle": self.after_last_cycle,
                "windows": self.windows,
                "segments": [
                    {"cylinder": c, "segment_deg": seg, "start_after_tdc_deg": start} for c, seg, start in self.segments
                ],
                "cylinders": [
                    {
                        "cylinder": c + 1,
                        "judged": int(self.judged[c]),
                        "misfires": int(self.misfires[c]),
                        "median_index": float(self.median_index[c]),
                        "min_index": float(self.min_index[c]),
                        "median_swing": self._swing(c),
                        "median_imep_bar": (
                            None if self.median_imep_pa is None else float(self.median_imep_pa[c] / PA_PER_BAR)
                        ),
                    }
                    for c in range(self.cylinders)
                ],
                "note_counts": dict(self.note_counts),
                "notes": [n.to_json_dict() for n in self.notes[-50:]],
            }
        )

    def to_pandas(self) -> Any:
        import pandas as pd

        return pd.DataFrame(
            {
                "cylinder": np.arange(1, self.cylinders + 1),
                "judged": self.judged,
                "misfires": self.misfires,
                "median_index": self.median_index,
                "min_index": self.min_index,
                "median_swing": [self._swing(c) for c in range(self.cylinders)],
                "median_imep_bar": (
                    np.full(self.cylinders, np.nan) if self.median_imep_pa is None else self.median_imep_pa / PA_PER_BAR
                ),
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """The misfires of each cylinder as bars. Returns the Axes."""
        from ..plotting.common import new_axes

        ax = new_axes(ax)
        x = np.arange(1, self.cylinders + 1)
        ax.bar(x, self.misfires, color="tab:red")
        ax.set_xlabel("cylinder")
        ax.set_ylabel("misfires")
        ax.set_xticks(x)
        ax.set_title(f"misfires per cylinder ({int(self.judged.sum())} firings judged)")
        return ax


def _firings(engine: Any, cylinders: Any, firing_order: Any, strokes: Any) -> tuple:
    """(engine, cylinders, strokes, the cycle [rad], each cylinder's firing angle within it
    [rad], where they come from): from an engine (a file or preset name loaded), else evenly
    spaced in ``firing_order``."""
    if engine is not None:
        if isinstance(engine, str):
            from ..engine.file import load_engine

            engine = load_engine(engine)
        strokes = int(engine.strokes)
        n = int(engine.cylinders)
        cycle = TWO_PI * strokes / 2
        fire = np.mod(np.asarray(engine.firing_angles_rad, dtype=np.float64), cycle)
        return (
            engine,
            n,
            strokes,
            cycle,
            fire,
            f"engine {getattr(engine, 'name', '') or 'file'}: firing angles from the model",
        )
    if strokes not in (2, 4):
        raise EngineError(f"strokes = {strokes!r}: 4 or 2")
    if not (isinstance(cylinders, (int, np.integer)) and 1 <= cylinders <= 64):
        raise EngineError(f"cylinders = {cylinders!r}: a whole number 1 … 64 (or give engine=)")
    n = int(cylinders)
    order = list(range(1, n + 1)) if firing_order is None else [int(c) for c in firing_order]
    if sorted(order) != list(range(1, n + 1)):
        raise EngineError(f"firing_order = {order!r}: each cylinder 1 … {n} once")
    cycle = TWO_PI * strokes / 2
    first = TWO_PI if strokes == 4 else 0.0
    fire = np.zeros(n)
    for j, c in enumerate(order):
        fire[c - 1] = math.fmod(first + j * cycle / n, cycle)
    return None, n, strokes, cycle, fire, f"{n} cylinders, firing order {','.join(map(str, order))}, evenly spaced"


def _segments(fire: np.ndarray, cycle: float, segment_deg: Any) -> np.ndarray:
    """Each firing's segment [rad] (the firing angles ``fire`` sorted): to the next firing's
    TDC (an uneven firing order gives each its own), at most 180°; or ``segment_deg``."""
    n = fire.size
    if segment_deg is None:
        gaps = np.diff(np.concatenate([fire, [fire[0] + cycle]])) if n > 1 else np.array([cycle])
        return np.minimum(np.where(gaps > 0, gaps, cycle), math.pi)
    seg = math.radians(float(segment_deg)) if math.isfinite(float(segment_deg)) else math.nan
    if not (0 < seg <= cycle):
        raise EngineError(f"segment_deg = {segment_deg!r}: a positive angle up to one cycle")
    return np.full(n, seg)


def _check_teeth(wheel: Any, segs: np.ndarray, n: int, strokes: int) -> float:
    """The wheel's teeth over the shortest segment; a :class:`rotor.LogError` below
    :data:`MIN_TEETH_PER_SEGMENT`."""
    per_segment = wheel.edges_per_rev * float(segs.min()) / TWO_PI
    if per_segment < MIN_TEETH_PER_SEGMENT:
        raise LogError(
            f"wheel {wheel.spec}: its {wheel.edges_per_rev} teeth a revolution give {per_segment:.3g} "
            f"{'tooth' if per_segment == 1 else 'teeth'} over a "
            f"firing's segment of {math.degrees(float(segs.min())):.4g}° ({n} cylinder(s), {strokes}-stroke); the "
            f"monitor needs at least {MIN_TEETH_PER_SEGMENT} teeth per firing (its speed windows are a quarter of a "
            "segment each): a wheel with more teeth (e.g. 60-2, 36-1)"
        )
    return per_segment


def check_wheel(
    wheel: Any,
    *,
    engine: Any = None,
    cylinders: int | None = None,
    firing_order: Sequence[int] | None = None,
    strokes: int = 4,
    segment_deg: float | None = None,
) -> float:
    """What :class:`MisfireMonitor` checks of the wheel and the firings before it reads
    an edge, without building the engine's model: a wheel with a gap and at least
    :data:`MIN_TEETH_PER_SEGMENT` teeth over the shortest firing segment (its teeth over
    it returned), valid cylinders and firing order; a :class:`rotor.LogError` or
    :class:`rotor.EngineError` naming what is wrong."""
    from ..logs.wheel import parse_wheel

    w = parse_wheel(wheel)
    if w.needs_index:
        raise LogError(f"wheel {w.spec}: the monitor follows a wheel with a gap (e.g. 60-2, 36-1)")
    _, n, strokes, cycle, fire, _ = _firings(engine, cylinders, firing_order, strokes)
    return _check_teeth(w, _segments(np.sort(fire), cycle, segment_deg), n, strokes)


class MisfireMonitor:
    """A streaming misfire monitor on tooth edge times (see the module's doc).

    **Arguments:** ``wheel``: a wheel spec with a gap (``"60-2"``, ``"36-1"``, ``"36-2-1"``)
    or a :class:`rotor.logs.wheel.Wheel`; ``tdc_deg``: cylinder 1's TDC after the gap
    [deg]; ``engine``: an :class:`rotor.Engine` (or a file or preset name) giving cylinders,
    strokes and firing angles; else ``cylinders``, ``firing_order`` (cylinders from 1, in
    the order they fire; default 1, 2, …) and ``strokes`` (4 or 2); ``firing_parity``:
    which revolutions from the first gap hold cylinder 1's firing TDC (0 or 1, four-stroke);
    ``threshold``: a misfire where the index is below −threshold; ``segment_deg``: the
    firing segment [deg] (default the angle to the next firing, at most 180°), from TDC +
    (180° − segment)/8 (``segment_rad``, ``offset_rad``: per firing in the order of the
    firing angles); ``min_spread``: the smallest baseline spread of e; ``check_fit``: refuse
    an engine whose model IMEP does not fit the log, and flag the verdicts where the speed
    does not show the engine's firings (below; default True); ``log_name``: the log's name,
    for the messages; ``thresholds``: the misfire-rate windows and their thresholds (a
    :class:`rotor.diagnostics.misfire_rate.MisfireThresholds`; default its defaults),
    ``windows``: keep them (default True; :meth:`pop_windows`); ``last_cycle``: the log's last
    cycle (from 1), the firings after it not judged but counted (a recorded run's lead-out;
    default None: every firing).

    **The wheel's teeth.** Each firing's index takes the speed over windows of a quarter of
    its segment at the segment's ends: a wheel with fewer than
    :data:`MIN_TEETH_PER_SEGMENT` teeth over the shortest segment (a 3-1 or 12-10 wheel on a
    four-cylinder engine: one tooth per 180°) leaves those windows inside one tooth period,
    and is refused when the monitor is made (a noise-free simulated 4chn15 run on a 4-1
    wheel missed a misfire, on 3-1 and 12-10 wheels called normal firings misfires; 6-1 and
    up found them all; the detection map of ``benchmarks/misfire_detection.py`` holds 8 and
    more teeth per segment).

    **The time base.** The first edges on which the wheel is looked for are checked as
    ``rotor analyze`` checks a log (:mod:`rotor.logs.plausibility`): a tooth period that
    implies a mean speed under 10 or over 30,000 rpm (times in milliseconds or
    microseconds read as seconds: named in the message), and time stamps that resolve more
    than :data:`RESOLUTION_REFUSE` (0.3 %) of the tooth period (times offset far from 0,
    e.g. by 1e12 s, where a float64 holds only 1.2e-4 s; a coarse timer), are refused
    (:class:`rotor.LogError` from :meth:`feed`); a resolution above
    :data:`RESOLUTION_NOTE` (0.1 %) is noted (:attr:`NoteKind.TIME_BASE`).

    **The engine's fit.** With an engine, when the first firings are judged together (every
    cylinder's baseline filled, about three cycles), the model's combustion scale of each of
    them (s: 0 a misfire, 1 the engine file's full pressure) is checked: where more than
    :data:`FIT_SHARE` (a quarter) of them lie below :data:`FIT_SCALE_LOW` or above
    :data:`FIT_SCALE_HIGH` (a firing doing negative work, or several times the file's; not
    widened by the fit's standard error, which a model that does not fit makes large), the
    engine does not fit the log (its cylinders or firing order, the TDC, the time unit), and
    :meth:`feed` refuses it (:class:`rotor.LogError`) before any verdict is given: the
    4chn15's recording read with the v8 preset gives s = −0.5 for every firing, with the mwm6
    preset −1.9; the mwm6's read with the 4chn15 preset 7.7; a 4chn15 whose cylinder 2 never
    fires keeps s = 0 for it and fits. With or without an engine, once the wheel has been
    followed over :data:`FIT_CYCLES` whole cycles, the speed's orders over them are read
    (each cycle's trend off): the strongest order of the angular acceleration (each order's
    speed amplitude, averaged over the cycles, times the order: a dead cylinder's missing
    pulse adds every order, weakly against the firings' own) must be a multiple of the
    engine's firing frequency (its cylinders/2 a revolution for an evenly firing
    four-stroke; an uneven firing order repeats once a cycle, and every order fits). Where
    it is not (a four-cylinder log monitored as a six), a note says so
    (:attr:`NoteKind.ENGINE_FIT`) and every verdict given from then on (from the edge that
    ends those cycles) carries ``engine_doubt``: a wheel's tooth errors at high speed can put
    the strongest order elsewhere, so that this is a warning, not a refusal. Nothing is said
    where that order is not the same in every cycle (its mean under :data:`FIT_Z` of its
    standard errors over the cycles: timer noise, a run at exactly constant speed). A log
    whose firing frequency is a multiple of the engine's (a V8 monitored as a four-cylinder)
    fits the orders, and so does a four-cylinder monitored as a V8 where its fourth order is
    its strongest (the 4chn15's: it is a V8 whose every other cylinder is dead): only the
    model's IMEP tells these, with an engine file.
    """

    def __init__(
        self,
        wheel: Any,
        *,
        tdc_deg: float,
        engine: Any = None,
        cylinders: int | None = None,
        firing_order: Sequence[int] | None = None,
        strokes: int = 4,
        firing_parity: int = 0,
        threshold: float = DEFAULT_THRESHOLD,
        segment_deg: float | None = None,
        min_spread: float = DEFAULT_MIN_SPREAD,
        check_fit: bool = True,
        log_name: str | None = None,
        thresholds: Any = None,
        windows: bool = True,
        last_cycle: int | None = None,
    ) -> None:
        from ..logs.wheel import parse_wheel
        from .misfire_rate import MisfireThresholds, WindowCounter

        self.log_name = log_name
        self.check_fit = bool(check_fit)
        self.wheel = parse_wheel(wheel)
        if self.wheel.needs_index:
            raise LogError(f"wheel {self.wheel.spec}: the monitor follows a wheel with a gap (e.g. 60-2, 36-1)")
        if not (isinstance(tdc_deg, (int, float)) and math.isfinite(tdc_deg)):
            raise EngineError(f"tdc_deg = {tdc_deg!r}: cylinder 1's TDC after the gap [deg], a finite number")
        if firing_parity not in (0, 1):
            raise EngineError(f"firing_parity = {firing_parity!r}: 0 or 1")
        if not (math.isfinite(threshold) and threshold > 0):
            raise EngineError(f"threshold = {threshold!r}: a positive number of baseline spreads")
        if not (math.isfinite(min_spread) and min_spread > 0):
            raise EngineError(f"min_spread = {min_spread!r}: a positive number")
        engine, n, strokes, cycle, fire, self.source = _firings(engine, cylinders, firing_order, strokes)
        self.cylinders, self.strokes, self.cycle_rad = n, strokes, cycle
        self.threshold, self.min_spread = float(threshold), float(min_spread)
        by_angle = np.argsort(fire, kind="stable")
        self._fire = fire[by_angle]  # firing angles within a cycle, sorted
        self._fire_list = [float(f) for f in self._fire]
        self._fire_cyl = [int(c) + 1 for c in by_angle]  # their cylinders, from 1
        segs = _segments(self._fire, cycle, segment_deg)
        self.segment_rad = segs  # per firing slot (firing angles sorted)
        _check_teeth(self.wheel, segs, n, strokes)
        self._model = None if engine is None else _ModelIndex(engine, self._fire, self._fire_cyl)
        if last_cycle is not None and not (
            isinstance(last_cycle, (int, np.integer)) and not isinstance(last_cycle, bool) and last_cycle >= 1
        ):
            raise EngineError(f"last_cycle = {last_cycle!r}: the log's last cycle, a whole number from 1")
        self.last_cycle = None if last_cycle is None else int(last_cycle)
        self._after_last = 0
        if thresholds is not None and not isinstance(thresholds, MisfireThresholds):
            raise EngineError(f"thresholds = {thresholds!r}: a rotor.diagnostics.misfire_rate.MisfireThresholds")
        full = None
        if self._model is not None:
            full = float(np.mean([m + c for m, c, _ in self._model.figures]))
        self._windows = WindowCounter(n, strokes, thresholds, full) if windows else None
        self._new_windows: list = []
        # the firing pattern repeats this many times a cycle: the speed's orders that fit it
        self._pattern = _pattern_repeats(self._fire, cycle)
        # from TDC + (180° − segment)/8: where the most of the firing's own combustion work
        # falls into its segment (see the module doc, **The index**)
        self.offset_rad = np.maximum(0.0, (math.pi - segs) / 8)
        self.window_rad = segs / 4
        self._seg_list = [float(x) for x in segs]
        self._off_list = [float(x) for x in self.offset_rad]
        self._win_list = [float(x) for x in self.window_rad]
        self._trim_back = float((self.window_rad - self.offset_rad).max())
        self.tdc_rad = math.radians(float(tdc_deg))
        self.parity = firing_parity
        E = self.wheel.edges_per_rev
        self._E = E
        self._acquire_edges = 2 * E + 3
        self._slice = SLICE_REVOLUTIONS * E
        self._trim_above = 2 * E  # edges held before the ones no firing needs are dropped
        # stream state
        self._raw = np.empty(0)  # edges not yet placed (looking for the wheel)
        self._t = np.empty(0)  # placed edges of the current run, and their angles
        self._th = np.empty(0)
        self._locked = False
        self._g = 0  # running tooth count of the last placed edge
        self._phase0 = 0.0  # θ of tooth count 0 [rad]
        self._ang = np.empty(0)  # tooth angles on the wheel
        self._span = np.empty(0)  # pitches from the previous tooth to each tooth
        self._span_t = np.empty(0)  # the same, and the angles from tooth 0, over several revolutions
        self._ang_t = np.empty(0)
        self._rev_t = np.empty(0)
        self._p_last = math.nan  # last tooth period per pitch
        self._last_t = -math.inf  # last edge time accepted
        self._last_theta = math.nan
        self._last_omega = math.nan
        self._last_t_locked = math.nan
        self._ever_locked = False
        self._time_checked = False  # the time base checked on the first edges
        # the speed's orders: read once over the first FIT_CYCLES whole cycles of a run (their
        # edges kept until then)
        self._orders_pending = self.check_fit
        self._orders_t = math.inf  # the log time at which they were read
        self._orders_k: int | None = None  # the next whole cycle of the run to read
        self._orders_x: list[np.ndarray] = []  # the spectra of the cycles read
        self._orders_h = max(3 * n, 16)  # harmonics of the cycle read
        self._orders_n = max(256, 8 * self._orders_h)  # points a cycle
        self._doubt = False  # the speed's orders did not show the engine's firings
        self._doubt_t = math.inf  # the verdicts given from this log time on are flagged
        self._no_wheel = ""  # why the wheel was not found, the last time
        self._next: tuple[int, int] | None = None  # (cycle index k, firing slot j) to judge next
        self._run_start = math.nan
        self._history = _Baseline(HISTORY)  # the firings' deviations from their cylinders' medians
        self._raw_e = _Baseline(HISTORY)  # the last values of e, all cylinders: the spread's floor while it is young
        self._measured = 0  # deviations in the spread measured against a baseline before them
        # the common deviation: from the next half cycle's firings (none with one cylinder,
        # whose own median is all there is)
        self._ahead = n // 2
        self._pending: collections.deque = collections.deque()  # measured, waiting for the firings after them
        self._wsum, self._wcnt = 0.0, 0  # the pending deviations that are not losses: their sum and count
        self._s_now = min_spread
        self._finished = 0
        self._last_t_dec = math.nan
        self._dead_of = [0.0] + [COMMON_DEAD / math.sqrt(m) for m in range(1, n + 2)]
        self._own = [_Baseline(OWN_HISTORY) for _ in range(n)]  # each cylinder's last values of e
        self._warm = False
        self._ends: dict[int, float] = {}  # while the first firings wait: the times at which cycles ended
        self._ends_next = -(2**62)  # the next cycle boundary to note
        self._held: tuple | None = None  # the last firing judged, until the next one is measured
        self._prev_index = math.nan
        self._waiting: list = []  # firings measured, not yet judged: [k, j, e, t_dec, cycle end, predicted, in the baseline]
        self._notes: collections.deque = collections.deque(maxlen=MAX_NOTES)
        self._new_notes: list[Note] = []
        self._note_counts: collections.Counter = collections.Counter()
        self._edges = 0
        self._skipping_back = 0
        self._not_judged = 0
        self._judged = [0] * n
        self._misfires = [0] * n
        self._min_index = [math.inf] * n
        # a normal firing's index spread, with that of its cylinder's median of n values
        self._index_std = [math.sqrt(1.0 + math.pi / (2 * max(m, 1))) for m in range(OWN_HISTORY + 1)]
        self._index_sketch: list[collections.deque] = [collections.deque(maxlen=HISTORY) for _ in range(n)]
        self._imep_sketch: list[collections.deque] = [collections.deque(maxlen=HISTORY) for _ in range(n)]
        self._swing_sketch: list[collections.deque] = [collections.deque(maxlen=HISTORY) for _ in range(n)]
        self._misfire_list: collections.deque = collections.deque(maxlen=MAX_NOTES)
        self._closed = False

    # ------------------------------------------------------------------ public
    @property
    def buffer_length(self) -> int:
        """Edges held now (placed and not yet placed): bounded whatever the stream's length."""
        return int(self._t.size + self._raw.size)

    def pop_notes(self) -> list[Note]:
        """The notes (:class:`Note`) since the last call."""
        out, self._new_notes = self._new_notes, []
        return out

    def pop_windows(self) -> list:
        """The misfire-rate windows judged since the last call
        (:class:`rotor.diagnostics.misfire_rate.MisfireWindow`, in the order judged, the last
        :data:`MAX_WINDOWS_HELD`; none where the monitor was made with ``windows=False``)."""
        out, self._new_windows = self._new_windows, []
        return out

    def feed(self, times: Any) -> list[Verdict]:
        """Take the next tooth edge times [s] (any number, in order) and return the verdicts
        decided by them. A value that is not a finite number, or an edge not after the one
        before, is skipped and noted (:meth:`pop_notes`)."""
        if self._closed:
            raise LogError("the monitor is closed: make a new one for another stream")
        t = np.asarray(times, dtype=np.float64).ravel()
        if t.size <= self._slice:
            return self._feed_slice(t)
        out: list[Verdict] = []
        for s in range(0, t.size, self._slice):
            out.extend(self._feed_slice(t[s : s + self._slice]))
        return out

    def nothing_judged_reason(self) -> str | None:
        """Why no firing has been judged, in words (None where some were): the wheel never
        found, too few edges to look for it, or a log that ends before a firing's segment."""
        if sum(self._judged):
            return None
        spec = self.wheel.spec
        if not self._ever_locked:
            if self._edges < self._acquire_edges:
                return (
                    f"no firing judged: {self._edges} tooth edge(s), fewer than the {self._acquire_edges} (two "
                    f"revolutions of the {spec} wheel) in which the monitor looks for its gap"
                )
            why = f" (the last try: {self._no_wheel})" if self._no_wheel else ""
            return (
                f"no firing judged: the {spec} wheel was not found in {self._edges} tooth edges{why}; is the wheel "
                "right, and are these tooth edge times?"
            )
        return (
            f"no firing judged: the {spec} wheel was found, but the log ends before a firing's segment was measured "
            f"({self._edges} tooth edges, {self._edges / self._E:.1f} revolutions)"
        )

    def close(self) -> list[Verdict]:
        """End of the stream: the verdicts still waiting for their baseline (judged on what
        there is), and the monitor closed."""
        self._end_backwards()
        out = self._release_waiting(force=True)
        if self._windows is not None and not self._closed:
            self._new_windows += self._windows.close()
        self._closed = True
        return out

    def result(self) -> MonitorResult:
        """Per-cylinder counts and indices so far (:class:`MonitorResult`)."""
        med = np.array([float(np.median(d)) if d else math.nan for d in self._index_sketch])
        mins = np.array([x if math.isfinite(x) else math.nan for x in self._min_index])
        return MonitorResult(
            cylinders=self.cylinders,
            judged=np.array(self._judged, dtype=np.int64),
            misfires=np.array(self._misfires, dtype=np.int64),
            median_index=med,
            min_index=mins,
            misfire_list=list(self._misfire_list),
            not_judged=self._not_judged,
            edges=self._edges,
            notes=list(self._notes),
            note_counts={k.value: v for k, v in self._note_counts.items()},
            threshold=self.threshold,
            source=self.source,
            median_swing=np.array([float(np.median(d)) if d else math.nan for d in self._swing_sketch]),
            median_imep_pa=(
                None
                if self._model is None
                else np.array([float(np.median(d)) if d else math.nan for d in self._imep_sketch])
            ),
            segments=[
                (c, round(math.degrees(seg), 6), round(math.degrees(off), 6))
                for c, seg, off in zip(self._fire_cyl, self._seg_list, self._off_list)
            ],
            engine_doubt=self._doubt,
            windows=None if self._windows is None else self._windows.summary_dict(),
            after_last_cycle=self._after_last,
            last_cycle=self.last_cycle,
        )

    # ------------------------------------------------------------------ notes
    def _note(self, kind: NoteKind, t_s: float | None, text: str) -> None:
        n = Note(kind, None if t_s is None or not math.isfinite(t_s) else float(t_s), text)
        self._notes.append(n)
        self._new_notes.append(n)
        if len(self._new_notes) > MAX_NOTES:
            del self._new_notes[0]
        self._note_counts[kind] += 1

    def _end_backwards(self) -> None:
        if self._skipping_back:
            self._note(
                NoteKind.BACKWARDS,
                self._last_t,
                f"{self._skipping_back} edge time(s) not after {self._last_t:.9g} s: skipped",
            )
            self._skipping_back = 0

    # ------------------------------------------------------------------ edges
    def _feed_slice(self, t: np.ndarray) -> list[Verdict]:
        if t.size == 0:
            return []
        # the usual case in one test: every edge finite and after the one before (a NaN
        # fails every comparison; an infinite time can only be the last)
        if not (t[0] > self._last_t and math.isfinite(t[-1]) and (t.size == 1 or bool((t[1:] > t[:-1]).all()))):
            t = self._clean(t)
            if t.size == 0:
                return []
        elif self._skipping_back:
            self._end_backwards()
        self._last_t = float(t[-1])
        self._edges += int(t.size)
        verdicts: list[Verdict] = []
        while t.size:
            if self._locked:
                t = self._follow(t)
            else:
                t = self._acquire(t)
            verdicts.extend(self._judge())
        return verdicts

    def _clean(self, t: np.ndarray) -> np.ndarray:
        """The edges of ``t`` that are finite times after every edge before them; the others
        noted (a run of edges not after the last one once, when it ends)."""
        finite = np.isfinite(t)
        if not finite.all():
            bad = t[~finite]
            self._note(NoteKind.NOT_TIME, self._last_t, f"{bad.size} value(s) that are not finite times: skipped")
            t = t[finite]
            if t.size == 0:
                return t
        prev = np.maximum.accumulate(np.concatenate([[self._last_t], t]))[:-1]
        ok = t > prev
        if ok.all():
            self._end_backwards()
            return t
        out_t = []
        for i in range(t.size):
            if ok[i]:
                self._end_backwards()
                out_t.append(t[i])
                self._last_t = t[i]
            else:
                self._skipping_back += 1
        return np.asarray(out_t, dtype=np.float64)

    def _check_time_base(self, t: np.ndarray) -> None:
        """The first edges' time base, as ``rotor analyze`` checks a log's: the mean speed
        they imply and the resolution of their stamps (see the class doc, **The time
        base**); a :class:`rotor.LogError` where they cannot be tooth times in seconds."""
        from ..logs.plausibility import MAX_RPM, MIN_RPM, time_resolution_s

        self._time_checked = True
        d = np.diff(t)
        d = d[d > 0]
        if d.size == 0:
            return
        dt = float(np.median(d))
        rpm = 60.0 / (dt * self.wheel.teeth)
        if not MIN_RPM <= rpm <= MAX_RPM:
            self._closed = True
            units = (("milliseconds", 1e3, "tooth_time_ms"), ("microseconds", 1e6, "tooth_time_us"))
            hint = next(
                (
                    f"are they in {unit} ({rpm * f:.4g} rpm if so)? give seconds, or name the column {name!r} "
                    "in a header line above the times"
                    for unit, f, name in units
                    if MIN_RPM <= rpm * f <= MAX_RPM
                ),
                "are these tooth edge times in seconds, and is the wheel right?",
            )
            raise LogError(
                f"{self._where()}the tooth times imply {rpm:.3g} rpm (a tooth period of {dt:.4g} s on a "
                f"{self.wheel.spec} wheel), outside {MIN_RPM:g} … {MAX_RPM:,.0f} rpm; {hint}"
            )
        # from the first time on (exact): the step's tolerance scales with the times' size
        q = time_resolution_s(t - t[0])
        ratio = q / dt
        if ratio <= RESOLUTION_NOTE:
            return
        big = float(np.max(np.abs(t)))
        spacing = float(np.spacing(big))
        far = (
            f" (a float64 near {big:.4g} s resolves only {spacing:.2g} s: the times lie far from 0)"
            if spacing >= 0.5 * q
            else ""
        )
        text = f"the tooth times resolve {q:.3g} s, {ratio:.1%} of the tooth period {dt:.4g} s{far}"
        if ratio > RESOLUTION_REFUSE:
            self._closed = True
            raise LogError(
                f"{self._where()}{text}: too coarse to measure the speed by; give the times with more digits, "
                "or as offsets from the start of the log"
            )
        self._note(NoteKind.TIME_BASE, float(t[0]), f"{text}: the indices and IMEPs carry some of the rounding")

    def _acquire(self, t: np.ndarray) -> np.ndarray:
        """Look for the wheel on the first edges not placed; the edges left over."""
        from ..logs.pattern import locate_teeth

        need = self._acquire_edges
        take = min(t.size, need - self._raw.size)
        self._raw = np.concatenate([self._raw, t[:take]])
        rest = t[take:]
        if self._raw.size < need:
            return rest
        window = self._raw
        if not self._time_checked:
            self._check_time_base(window)
        try:
            track = locate_teeth(window, self.wheel)
        except LogError as e:
            self._no_wheel = str(e)
            drop = self._E // 2
            self._note(
                NoteKind.NO_WHEEL,
                float(window[0]),
                f"the edges from {window[0]:.6f} s do not follow a {self.wheel.spec} wheel ({e}); "
                f"{drop} edges dropped, looking again",
            )
            self._raw = self._raw[drop:]
            return np.concatenate([self._raw[:0], rest]) if rest.size else rest
        w = track.wheel
        E = self._E
        pos = np.asarray(w.positions, dtype=np.int64)
        self._ang = TWO_PI * pos / w.teeth
        self._span = np.mod(pos - np.roll(pos, 1), w.teeth).astype(np.float64)
        self._span[self._span == 0] = w.teeth
        reps = SLICE_REVOLUTIONS + 2  # a slice of edges from any tooth, read off without a modulo
        self._span_t = np.tile(self._span, reps)
        self._ang_t = np.tile(self._ang, reps)
        self._rev_t = np.repeat(np.arange(reps, dtype=np.float64), E)
        g = track.rev.astype(np.int64) * E + track.tooth.astype(np.int64)
        phi = TWO_PI * (g // E) + self._ang[g % E]
        phase0 = -self.tdc_rad + TWO_PI * (1 - self.parity) if self.strokes == 4 else -self.tdc_rad + TWO_PI
        theta = phi + phase0
        t0 = float(window[0])
        if self._ever_locked and math.isfinite(self._last_omega):
            pred = self._last_theta + self._last_omega * (t0 - self._last_t_locked)
            shift = TWO_PI * round((pred - theta[0]) / TWO_PI)
            phase0 += shift
            theta = theta + shift
            hole = t0 - self._last_t_locked
            revs = self._last_omega * hole / TWO_PI
            doubt = (
                "; over so long a loss the speed may have changed (the engine stopped?): the cycle count "
                "from here may be off by a revolution, and cylinders with it"
                if revs > 2
                else ""
            )
            self._note(
                NoteKind.FOUND,
                t0,
                f"the wheel found again at {t0:.6f} s, {hole:.4f} s ({revs:.1f} revolutions at the last speed) "
                f"after it was lost; the revolutions counted on at the last speed{doubt}",
            )
        else:
            self._note(NoteKind.FOUND, t0, f"the {w.spec} wheel found: edges placed from {t0:.6f} s")
        self._phase0 = phase0
        self._g = int(g[-1])
        self._t, self._th = window.copy(), theta
        self._p_last = float((window[-1] - window[-2]) / self._span[g[-1] % E])
        self._locked = True
        self._ever_locked = True
        self._raw = np.empty(0)
        self._run_start = float(theta[0])
        self._start_run()
        return rest

    def _follow(self, t: np.ndarray) -> np.ndarray:
        """Place the edges ``t`` that follow the wheel's pattern; the rest (from the first
        that breaks it) go back to looking for the wheel."""
        E = self._E
        m = t.size
        g0 = self._g + 1
        r0, tooth0 = divmod(g0, E)
        dt = np.empty(m)
        dt[0] = t[0] - self._t[-1]
        np.subtract(t[1:], t[:-1], out=dt[1:])
        p = dt / self._span_t[tooth0 : tooth0 + m]
        p0 = p[0] / self._p_last
        tol = PERIOD_TOLERANCE
        n_ok = m
        if p0 > tol or p0 < 1.0 / tol:
            n_ok = 0
        elif m > 1:
            ratio = p[1:] / p[:-1]
            if ratio.max() > tol or ratio.min() < 1.0 / tol:
                n_ok = 1 + int(np.flatnonzero((ratio > tol) | (ratio < 1.0 / tol))[0])
        if n_ok:
            sl = slice(tooth0, tooth0 + n_ok)
            theta = self._phase0 + TWO_PI * (r0 + self._rev_t[sl]) + self._ang_t[sl]
            self._t = np.concatenate([self._t, t[:n_ok]])
            self._th = np.concatenate([self._th, theta])
            self._g = g0 + n_ok - 1
            self._p_last = float(p[n_ok - 1])
        if n_ok == m:
            return t[:0]
        # the wheel is lost at edge n_ok
        i = n_ok
        self._note(
            NoteKind.LOST,
            float(t[i]),
            f"the wheel lost at {t[i]:.6f} s: a tooth period {(p0 if i == 0 else ratio[i - 1]):.2f}× the one before where the "
            f"{self.wheel.spec} wheel gives 1× (a missed or extra edge, a hole in the data or the engine stopping); "
            "looking for the gap again",
        )
        self._lose()
        return t[i:]

    def _lose(self) -> None:
        # the speed and angle of the run's end carry the revolution count across the loss
        self._last_theta = float(self._th[-1])
        self._last_t_locked = float(self._t[-1])
        self._last_omega = self._omega_now()
        self._raw = np.empty(0)
        self._t, self._th = np.empty(0), np.empty(0)
        self._locked = False
        # the speed's orders read afresh in the next run
        self._orders_k, self._orders_x = None, []

    def _omega_now(self) -> float:
        th, t = self._th, self._t
        j = int(np.searchsorted(th, th[-1] - TWO_PI))
        if j >= th.size - 1:
            j = 0
        return float((th[-1] - th[j]) / (t[-1] - t[j])) if t[-1] > t[j] else math.nan

    # ------------------------------------------------------------------ firings
    def _firing_theta(self, k: int, j: int) -> float:
        return k * self.cycle_rad + float(self._fire[j])

    def _start_run(self) -> None:
        """The first firing to judge in a new run of placed edges: the first whose segment
        lies after the run's first edge; those skipped since the last run are counted."""
        off, win = self._off_list, self._win_list
        nf = self._fire.size
        k = math.floor(self._run_start / self.cycle_rad) - 1
        j = 0
        while self._firing_theta(k, j) + off[j] - win[j] / 2 < self._run_start:
            j += 1
            if j == nf:
                k, j = k + 1, 0
        if self._next is not None:
            k0, j0 = self._next
            skipped = (k - k0) * nf + (j - j0)
            reported = sum(1 for kk, jj in _slots(k0, j0, k, j, nf) if kk >= 1 and self._firing_theta(kk, jj) >= 0)
            if skipped > 0:
                self._not_judged += reported
                if reported:
                    self._note(
                        NoteKind.NOT_JUDGED,
                        float(self._t[0]),
                        f"{reported} firing(s) not judged (cycle {k0}, … cycle {k}): the wheel was lost over them",
                    )
        self._next = (k, j)

    def _judge(self) -> list[Verdict]:
        th = self._th
        if not self._locked or self._next is None or th.size < 2:
            return []
        if self._orders_pending:
            self._read_orders()
        if not self._warm:
            self._note_cycle_ends()
        segs, offs, wins = self._seg_list, self._off_list, self._win_list
        cyc = self.cycle_rad
        fire = self._fire_list
        nf = len(fire)
        th_last = float(th[-1])
        k, j = self._next
        starts: list[float] = []
        slots: list[tuple[int, int]] = []
        x = k * cyc + fire[j] + offs[j]
        while x + segs[j] + wins[j] / 2 <= th_last:
            starts.append(x)
            slots.append((k, j))
            j += 1
            if j == nf:
                k, j = k + 1, 0
            x = k * cyc + fire[j] + offs[j]
        if not slots:
            return []
        self._next = (k, j)
        tt = self._t
        # the log times at the ends of each firing's two speed windows, at its segment's
        # ends, at its cycle's end and at the ends of the swing's windows (at its TDC and
        # half its segment after): one interpolation for them all
        query: list[float] = []
        for (kk, jj), xa in zip(slots, starts):
            xb = xa + segs[jj]
            half = wins[jj] / 2
            tz = kk * cyc + fire[jj]
            tm = tz + segs[jj] / 2
            query += (xa - half, xa + half, xb - half, xb + half, xa, xb, (kk + 1) * cyc)
            query += (tz - half, tz + half, tm - half, tm + half)
        model = self._model
        nq = len(query)
        if model is not None:
            # and the ends of the model's windows over each segment
            spans = model.span_list
            for kk, jj in slots:
                tz = kk * cyc + fire[jj]
                query += [tz + x for x in spans[jj]]
        tq = np.interp(query, th, tt)
        tp = tq[:nq].tolist()
        if model is not None:
            js = [jj for _, jj in slots]
            imeps = model.estimate(js, [self._fire_cyl[jj] - 1 for jj in js], tq[nq:].reshape(len(slots), -1))
        last_i = np.searchsorted(th, [xa + segs[jj] + wins[jj] / 2 for (_, jj), xa in zip(slots, starts)]).tolist()
        n_edges = th.size
        E = self._E
        out: list[Verdict] = []
        for i, (kk, jj) in enumerate(slots):
            t0, t1, t2, t3, t4, t5, t6, z0, z1, m0, m1 = tp[11 * i : 11 * i + 11]
            seg, w = segs[jj], wins[jj]
            mean2 = ((t5 - t4) / seg) ** 2
            e = mean2 * ((w / (t3 - t2)) ** 2 - (w / (t1 - t0)) ** 2)
            swing = mean2 * ((w / (m1 - m0)) ** 2 - (w / (z1 - z0)) ** 2)
            # everything about a firing comes from the edges up to the last one it uses, so
            # that the verdicts do not depend on how the stream was cut into chunks; its
            # cycle's end is measured where those edges reach it, else predicted at the
            # speed of the revolution up to that edge
            last = min(last_i[i], n_edges - 1)
            t_dec = float(tt[last])
            th_dec = float(th[last])
            ce = (kk + 1) * cyc
            predicted = ce > th_dec
            if predicted:
                back = max(last - E, 0)
                omega = (th_dec - float(th[back])) / (t_dec - float(tt[back]))
                end_s = t_dec + (ce - th_dec) / omega
            else:
                end_s = t6
            figures = (math.nan, math.nan, swing) if model is None else (*imeps[i], swing)
            self._raw_e.append(e)
            if self._warm:
                self._decide(kk, jj, e, t_dec, end_s, predicted, False, 0.0, figures, out)
            else:
                self._waiting.append([kk, jj, e, t_dec, end_s, predicted, False, 0.0, figures])
                out.extend(self._release_waiting(force=False))
        self._trim()
        return out

    def _note_cycle_ends(self) -> None:
        """While the first firings wait: the log time of each cycle's end that the edges
        pass (by the edges about it, the same however the stream is cut), so that a verdict
        given after its cycle ended says when it did, not when it was predicted to."""
        th, cyc = self._th, self.cycle_rad
        last = math.floor(th[-1] / cyc)
        for b in range(max(math.ceil(th[0] / cyc), self._ends_next), last + 1):
            self._ends[b] = float(np.interp(b * cyc, th, self._t))
        self._ends_next = max(self._ends_next, last + 1)

    def _release_waiting(self, force: bool) -> list[Verdict]:
        out: list[Verdict] = []
        own, pool = self._own, self._history
        if not self._warm:
            # the first firings wait until every cylinder has a baseline of its own; each
            # goes into its cylinder's baseline as it is measured (an item: k, j, e, t_dec,
            # cycle end, predicted, in the baselines, its deviation, its IMEP, σ and swing)
            item = self._waiting[-1] if self._waiting and not self._waiting[-1][6] else None
            if item is not None:
                own[int(self._fire_cyl[item[1]]) - 1].append(item[2])
                item[6] = True
            if not force and min(len(b) for b in own) < MIN_OWN:
                return out
            self._check_imep()
            self._warm = True
            for item in self._waiting:
                # the verdict against the median of all the cylinder's values (robust to a
                # misfire among them); the spread against the median of its other values: a
                # value is not its own baseline (with three values one deviation would be 0
                # by construction, and a lead-in cycle copied from the first would make two 0)
                c = int(self._fire_cyl[item[1]]) - 1
                item[7] = item[2] - own[c].median()
                pool.append(item[2] - own[c].median_without(item[2]))
        if self._waiting:
            # given now, with the edge that completed the baselines (the last measured): the
            # time each was decided, not the earlier one of its own last edge
            t_given = self._waiting[-1][3]
            ends = self._ends
            for k, j, e, _, es, pr, fed, r, figures in self._waiting:
                if pr and ends.get(k + 1, math.inf) <= t_given:  # its cycle has ended by now: measured
                    es, pr = ends[k + 1], False
                self._decide(k, j, e, t_given, es, pr, fed, r if fed else 0.0, figures, out)
            self._waiting = []
            self._ends = {}
        if force:
            self._finish(out, self._last_t_dec, force=True)
            if self._held is not None:
                out.append(self._verdict(self._held, math.nan, max(self._held[8], self._last_t_dec)))
                self._held = None
        return out

    def _check_imep(self) -> None:
        """With an engine: refuse it where the model's IMEP of the first firings (those that
        waited for the baselines) is implausible in more than :data:`FIT_SHARE` of them
        (see the class doc, **The engine's fit**)."""
        model = self._model
        if model is None or not self.check_fit:
            return
        measured, bad = 0, []
        for item in self._waiting:
            imep = item[8][0]
            motored, comb, size = model.figures[self._fire_cyl[item[1]] - 1]
            if not (math.isfinite(imep) and size > 0):
                continue
            # not widened by the fit's standard error: a model that does not fit has a large one
            scale = (imep - motored) / comb
            measured += 1
            if not FIT_SCALE_LOW <= scale <= FIT_SCALE_HIGH:
                bad.append(imep)
        if measured < self.cylinders or len(bad) <= FIT_SHARE * measured:
            return
        self._closed = True
        motored = float(np.median([f[0] for f in model.figures])) / PA_PER_BAR
        full = float(np.median([f[0] + f[1] for f in model.figures])) / PA_PER_BAR
        raise LogError(
            f"{self._where()}the engine does not fit the log: the model's IMEP of {len(bad)} of the first "
            f"{measured} firings is {min(bad) / PA_PER_BAR:.3g} … {max(bad) / PA_PER_BAR:.3g} bar, where a firing "
            f"of this engine gives {motored:.3g} bar (a misfire) to about {full:.3g} bar (its file's full pressure): "
            "check the engine (its cylinders and firing order), cylinder 1's TDC after the gap (the log's "
            "'# tdc_after_gap_deg') and that the times are in seconds"
        )

    def _where(self) -> str:
        return f"{self.log_name}: " if self.log_name else ""

    def _decide(
        self,
        k: int,
        j: int,
        e: float,
        t_dec: float,
        end_s: float,
        predicted: bool,
        fed: bool,
        d: float,
        figures: tuple[float, float, float],
        out: list,
    ) -> None:
        """Measure one firing against its cylinder's baseline (``fed``: its values are in
        the baselines already, its deviation ``d``; ``figures``: its IMEP and the IMEP's
        standard deviation from the model [Pa], NaN without an engine, and its swing) and judge the firings whose neighbours
        are measured; their verdicts (each held until the next is judged) go to ``out``."""
        c0 = self._fire_cyl[j] - 1
        own = self._own[c0]
        n_own = len(own.order)
        if not fed:
            d = e - own.median() if n_own else 0.0
            own.append(e)
        # a loss (another misfire) or a gain of as many spreads (a firing against a baseline a
        # misfire holds) is not part of the deviation common to its neighbours
        inlier = abs(d) < COMMON_OUTLIER * self._s_now
        self._pending.append((k, c0, d, e, end_s, predicted, figures, n_own, fed, inlier))
        if inlier:
            self._wsum += d
            self._wcnt += 1
        self._last_t_dec = t_dec
        if len(self._pending) > self._ahead:
            self._finish(out, t_dec, force=False)

    def _finish(self, out: list, t_dec: float, force: bool) -> None:
        """Judge the pending firings that have :attr:`_ahead` firings measured after them
        (all of them with ``force``): the deviation common to the firings after each (the
        speed settling after a misfire or a load change moves every firing's e alike, and
        the cylinders' medians lag it) is taken off, and the rest is the index. The sum
        and count of the pending deviations are kept as they change."""
        pending, pool = self._pending, self._history
        dead_of = self._dead_of
        ahead = self._ahead
        wsum, wcnt = self._wsum, self._wcnt
        while len(pending) > ahead or (force and pending):
            k, c0, d, e, end_s, predicted, figures, n_own, fed, inlier = pending.popleft()
            r = d
            s = pool.spread() if pool.order else 0.0
            if self._measured < HISTORY:
                # a young spread is not trusted: at least that of the last values of e
                # themselves, all cylinders together (their own offsets in it: larger)
                s_raw = self._raw_e.spread()
                if s < s_raw:
                    s = s_raw
            if s < self.min_spread:
                s = self.min_spread
            self._s_now = s
            if ahead:
                if inlier:  # out of the window: the others are the pending, all after it
                    wsum -= d
                    wcnt -= 1
                if wcnt:
                    # their mean, less its own noise (taken off only where it stands out of
                    # it: a steady run keeps every firing's full signal)
                    c = wsum / wcnt
                    dead = s * dead_of[wcnt]
                    if c > dead:
                        r -= c - dead
                    elif c < -dead:
                        r -= c + dead
                self._finished += 1
                if self._finished % 4096 == 0:  # the running sum summed afresh now and then
                    ys = [item[2] for item in pending if item[9]]
                    wsum, wcnt = math.fsum(ys), len(ys)
            index = r / s
            if not fed:
                pool.append(r)
                self._measured += 1
            held = self._held
            if held is not None:
                out.append(self._verdict(held, index, t_dec))
            prev, self._prev_index = self._prev_index, index
            # held until the next firing is judged: a loss that is mostly a neighbour's (the
            # tail of its expansion stroke in this segment) is not this firing's misfire; a
            # firing before cycle 1 only feeds the baselines
            after = self.last_cycle is not None and k > self.last_cycle
            if after:
                self._after_last += 1
            self._held = (
                (k, c0 + 1, index, self._index_std[n_own], e, end_s, predicted, prev, t_dec, figures)
                if k >= 1 and not after
                else None
            )
        self._wsum, self._wcnt = wsum, wcnt

    def _verdict(self, held: tuple, next_index: float, t_dec: float) -> Verdict:
        k, c, index, index_std, e, end_s, predicted, prev, _, (imep, imep_std, swing) = held
        # a loss that a neighbour has more than twice over is that neighbour's
        side, lowest = None, math.nan
        if math.isfinite(prev) and not (math.isfinite(next_index) and next_index < prev):
            side, lowest = "previous", prev
        elif math.isfinite(next_index):
            side, lowest = "next", next_index
        spill = side is not None and index > 0.5 * lowest
        below = index < -self.threshold
        misfire = below and not spill
        doubt = t_dec >= self._doubt_t
        v = Verdict(k, c, misfire, index, index_std, e, end_s, t_dec, predicted, imep, imep_std, swing, doubt)
        if below and spill:
            v.claimed_by, v.neighbour_index = side, lowest
        if self._windows is not None:
            judged = self._windows.add(k, c, misfire, end_s, imep)
            if judged:
                self._new_windows += judged
                if len(self._new_windows) > MAX_WINDOWS_HELD:  # not popped: the oldest dropped
                    del self._new_windows[: len(self._new_windows) - MAX_WINDOWS_HELD]
        c0 = c - 1
        self._judged[c0] += 1
        self._index_sketch[c0].append(index)
        self._swing_sketch[c0].append(swing)
        if self._model is not None:
            self._imep_sketch[c0].append(imep)
        if index < self._min_index[c0]:
            self._min_index[c0] = index
        if misfire:
            self._misfires[c0] += 1
            self._misfire_list.append((k, c))
        return v

    def _trim(self) -> None:
        """Drop the edges no firing to come needs (keep a revolution before the next one),
        and none of the whole cycle whose speed's orders are to be read next."""
        if self._next is None or self._th.size <= self._trim_above:
            return
        k, j = self._next
        keep_from = self._firing_theta(k, j) - self._trim_back - TWO_PI
        if self._orders_pending and self._orders_k is not None:
            keep_from = min(keep_from, self._orders_k * self.cycle_rad)
        i = int(np.searchsorted(self._th, keep_from)) - 1
        if i > 0:
            self._t = self._t[i:]
            self._th = self._th[i:]

    def _read_orders(self) -> None:
        """The spectra of the speed over the whole cycles of the run that the edges now
        reach (each cycle's trend off), until :data:`FIT_CYCLES` of them are read; then the
        strongest order of the acceleration: where it stands out of the cycles' scatter and is
        not a multiple of the firing frequency, a note, and the verdicts given from the edge
        that ended those cycles flagged (see the class doc, **The engine's fit**). What is read
        depends on the edges alone, not on how the stream was cut."""
        th, t = self._th, self._t
        cyc, per = self.cycle_rad, self._orders_n
        if self._orders_k is None:
            self._orders_k = math.ceil(th[0] / cyc)
        x = np.arange(per) - 0.5 * (per - 1)
        while (self._orders_k + 1) * cyc <= th[-1]:
            grid = self._orders_k * cyc + (cyc / per) * np.arange(per + 1)
            w = (cyc / per) / np.diff(np.interp(grid, th, t))
            w = w - w.mean() - (w @ x / (x @ x)) * x
            self._orders_x.append(np.fft.rfft(w)[1 : self._orders_h + 1])
            self._orders_k += 1
            if len(self._orders_x) == FIT_CYCLES:
                end = self._orders_k * cyc
                self._orders_t = float(t[int(np.searchsorted(th, end))])
                self._orders_pending = False
                self._judge_orders(end)
                return

    def _judge_orders(self, end: float) -> None:
        spectra = np.asarray(self._orders_x)
        self._orders_x = []
        mean = spectra.mean(axis=0)
        se = np.sqrt((np.abs(spectra - mean) ** 2).sum(axis=0) / (FIT_CYCLES * (FIT_CYCLES - 1)))
        acc = np.abs(mean) * np.arange(1, mean.size + 1)  # the acceleration's orders
        best = int(np.argmax(acc))
        if not abs(mean[best]) > FIT_Z * se[best] or (best + 1) % self._pattern == 0:
            return
        self._doubt, self._doubt_t = True, self._orders_t
        revs = self.cycle_rad / TWO_PI
        start = end - FIT_CYCLES * self.cycle_rad
        self._note(
            NoteKind.ENGINE_FIT,
            self._orders_t,
            f"the speed's strongest order is {(best + 1) / revs:g} a revolution (over {FIT_CYCLES} cycles from "
            f"{float(np.interp(start, self._th, self._t)):.6f} s), where the engine ({self.cylinders} cylinder(s), "
            f"{self.strokes}-stroke) fires {self._pattern / revs:g} times a revolution (its orders: multiples of "
            "that): the cylinders, firing order or strokes may not fit the log (or the wheel's tooth errors outweigh "
            "the firings); every verdict from here is flagged (engine_doubt)",
        )


def _pattern_repeats(fire: np.ndarray, cycle: float) -> int:
    """How many times a cycle the firing angles ``fire`` (sorted, within the cycle) repeat
    themselves: the number of cylinders for an even firing order, 1 for an uneven one."""
    n = fire.size
    for m in range(n, 1, -1):
        if n % m:
            continue
        shifted = np.sort(np.mod(fire + cycle / m, cycle))
        gap = np.abs(shifted - fire)
        if float(np.minimum(gap, cycle - gap).max()) < 1e-6:
            return m
    return 1


class _ModelIndex:
    """Each firing's IMEP from the speed over its segment, through the engine's equation of
    motion (see the module doc, **With an engine**): per firing slot, the least-squares
    solution for (E₀, s, L) is precomputed, so that a chunk's firings cost a few products."""

    def __init__(self, engine: Any, fire: np.ndarray, fire_cyl: list[int], windows: int = MODEL_WINDOWS) -> None:
        from ..dynamics.crank_train import COL_COMBUSTION, COL_I, COL_MOTORED, crank_train

        train = crank_train(engine)
        vals = np.asarray(train.values, dtype=np.float64)
        cyc = float(train.cycle_rad)
        npts = vals.shape[0]
        h = cyc / npts
        n = vals.shape[1] - COL_COMBUSTION
        # the tables over two cycles, and the running integrals of the torques (trapezoids
        # on the 0.25° nodes) from angle 0
        nodes = np.arange(2 * npts + 1) * h
        v2 = np.concatenate([vals, vals, vals[:1]])
        torques = v2[:, [COL_MOTORED, *range(COL_COMBUSTION, COL_COMBUSTION + n)]]
        cum = np.concatenate([np.zeros((1, n + 1)), np.cumsum(0.5 * h * (torques[1:] + torques[:-1]), axis=0)])
        root_i = np.sqrt(v2[:, COL_I])
        self.imep_motored = np.asarray(train.imep_motored_pa, dtype=np.float64)
        self.imep_combustion = np.asarray(train.imep_combustion_pa, dtype=np.float64)
        self.windows = K = windows
        self.cylinders = n
        nf = fire.size
        self.span = []
        self.pinv: list[np.ndarray] = []
        self.cov: list[np.ndarray] = []
        self.design: list[np.ndarray] = []
        self.inertia: list[np.ndarray] = []
        self.known: list[np.ndarray] = []
        self.others: list[np.ndarray] = []
        sub = 16  # points a window for its means
        for j in range(nf):
            gap = (fire[(j + 1) % nf] - fire[j]) % cyc if nf > 1 else cyc
            seg = min(gap if gap > 0 else cyc, math.pi)
            th0 = float(fire[j])
            edges = th0 + seg * np.arange(K + 1) / K
            u = th0 + seg * (np.arange(K)[:, None] + (np.arange(sub)[None, :] + 0.5) / sub) / K
            c0 = fire_cyl[j] - 1
            mean_cols = np.stack([np.interp(u, nodes, cum[:, m]).mean(axis=1) for m in range(n + 1)], axis=1)
            mean_cols -= np.stack([np.interp(th0, nodes, cum[:, m]) for m in range(n + 1)])
            J = np.interp(u, nodes, root_i).mean(axis=1) ** 2
            centre = 0.5 * (edges[1:] + edges[:-1]) - th0
            A = np.stack([np.ones(K), mean_cols[:, 1 + c0], -centre], axis=1)
            if not np.ptp(mean_cols[:, 1 + c0]) > 1e-12 * max(float(np.max(np.abs(mean_cols))), 1e-300):
                raise EngineError(
                    f"engine {engine.name!r}: its cylinder {c0 + 1} does no combustion work in the model (no [pressure] "
                    "section, or a motored one): the monitor's model weighs each firing by its combustion torque; "
                    "give an engine file with the engine's cycle, or none"
                )
            AtA_inv = np.linalg.inv(A.T @ A)
            self.span.append(edges - th0)
            self.pinv.append(AtA_inv @ A.T)
            self.cov.append(AtA_inv)
            self.design.append(A)
            self.inertia.append(0.5 * J)
            self.known.append(mean_cols[:, 0])
            other = mean_cols[:, 1:].copy()
            other[:, c0] = 0.0
            self.others.append(other)
        self.scales = [1.0] * n  # each cylinder's last estimated combustion scale
        # the same stacked by slot for a chunk's firings at once: y = ½·J·w²/Δt² − known −
        # others·scales; s = pinv₁·y; the residual r = M·y (M = 1 − A·pinv), its square
        # |M·y₀|² − 2·g·scales + scalesᵀ·H·scales with y₀ the part without the others
        # (g = (M·O)ᵀ·M·y₀, H = (M·O)ᵀ·(M·O)); only the cylinders whose combustion reaches
        # a slot's segment (near) enter its sums
        self.span_list = [[float(x) for x in sp] for sp in self.span]
        proj = [np.eye(K) - self.design[j] @ self.pinv[j] for j in range(nf)]
        mo = [proj[j] @ self.others[j] for j in range(nf)]
        # all of s₀, M·y₀ and g are linear in z = 1/Δt² (y₀ = w2i·z − known): one operator
        # a slot, rows [s₀; M·y₀ (K); g (n)], and its constant
        ops, consts = [], []
        for j in range(nf):
            w2i = self.inertia[j] * np.diff(self.span[j]) ** 2
            lin = np.vstack([self.pinv[j][1:2], proj[j], mo[j].T @ proj[j]])
            ops.append(lin * w2i[None, :])
            consts.append(lin @ self.known[j])
        self.op = np.stack(ops)
        self.const = np.stack(consts)
        # the operator doubled over the slots, so that a chunk's consecutive slots are a view
        self.op2 = np.concatenate([self.op, self.op])
        self.const2 = np.concatenate([self.const, self.const])
        # a slot's plan: its near cylinders with b and g's place in the row, and the
        # quadratic's terms (c, c', H_cc' counted twice off the diagonal), cov₁₁/(K − 3)
        self.plan: list[tuple[tuple[tuple[int, float, int], ...], tuple[tuple[int, int, float], ...], float]] = []
        for j in range(nf):
            o = self.others[j]
            size = np.abs(o).max(axis=0)
            near = [c for c in range(n) if size[c] > 1e-9 * max(float(size.max()), 1e-300)]
            hj = mo[j].T @ mo[j]
            linear = tuple((c, float(self.pinv[j][1] @ o[:, c]), K + 1 + c) for c in near)
            quad = tuple(
                (c, c2, float(hj[c, c2]) * (1.0 if a == q else 2.0))
                for a, c in enumerate(near)
                for q, c2 in enumerate(near)
                if q >= a
            )
            self.plan.append((linear, quad, float(self.cov[j][1, 1]) / (K - 3)))
        self.figures = [
            (float(m), float(c), abs(float(c))) for m, c in zip(self.imep_motored, self.imep_combustion, strict=True)
        ]

    def estimate(self, slots: list[int], cyls: list[int], times: np.ndarray) -> list[tuple[float, float]]:
        """(IMEP, its standard deviation) [Pa] of each firing, in slots ``slots`` of
        cylinders ``cyls`` (from 0), from the log times at its windows' edges (one row a
        firing; NaN where they are not all measured), in firing order: each takes the
        scales of the firings before it."""
        dt = times[:, 1:] - times[:, :-1]
        ok = [True] * len(slots) if dt.min() > 0.0 else (dt > 0).all(axis=1).tolist()
        if not all(ok):
            dt[~np.asarray(ok)] = 1.0
        j0, m = slots[0], len(slots)
        if m <= len(self.plan) and slots[-1] == (j0 + m - 1) % len(self.plan):  # consecutive: a view
            op, const = self.op2[j0 : j0 + m], self.const2[j0 : j0 + m]
        else:
            op, const = self.op[slots], self.const[slots]
        R = (np.matmul(op, (1.0 / (dt * dt))[:, :, None])[..., 0] - const).tolist()
        K1 = self.windows + 1
        sc = self.scales
        plan, figures = self.plan, self.figures
        out = []
        for row, j, c0, good in zip(R, slots, cyls, ok, strict=True):
            if not good:
                out.append((math.nan, math.nan))
                continue
            s = row[0]
            rss = 0.0
            for x in row[1:K1]:
                rss += x * x
            linear, quad, cov = plan[j]
            for c, b, g in linear:
                x = sc[c]
                s -= b * x
                rss -= 2.0 * row[g] * x
            for c, c2, h in quad:
                rss += h * sc[c] * sc[c2]
            sc[c0] = min(max(s, 0.0), 2.0)
            motored, comb, size = figures[c0]
            out.append((motored + s * comb, math.sqrt(max(rss, 0.0) * cov) * size))
        return out


_bisect_left, _insort = bisect.bisect_left, bisect.insort


class _Baseline:
    """The last ``size`` values, kept in arrival order (``order``) and sorted: the median and
    the spread (interquartile range / 1.349, the standard deviation of a normal
    distribution) read off the sorted list without sorting it again."""

    __slots__ = ("size", "order", "sorted")

    def __init__(self, size: int) -> None:
        self.size = size
        self.order: collections.deque = collections.deque()
        self.sorted: list[float] = []

    def __len__(self) -> int:
        return len(self.order)

    def append(self, x: float) -> None:
        order = self.order
        if len(order) == self.size:
            y = self.sorted
            del y[_bisect_left(y, order.popleft())]
        order.append(x)
        _insort(self.sorted, x)

    def median(self) -> float:
        return _median(self.sorted)

    def spread(self) -> float:
        y = self.sorted
        n = len(y)
        return (y[(3 * n) // 4] - y[n // 4]) / 1.349

    def median_without(self, x: float) -> float:
        """The median of the values other than one equal to ``x`` (that one if it is the only one)."""
        y = self.sorted
        if len(y) < 2:
            return y[0] if y else 0.0
        i = _bisect_left(y, x)
        return _median(y[:i] + y[i + 1 :] if i < len(y) and y[i] == x else y)

    def median_spread(self) -> tuple[float, float]:
        return self.median(), self.spread()


def _median(y: list[float]) -> float:
    """The median of the sorted values ``y`` (at least one)."""
    n = len(y)
    return y[n // 2] if n % 2 else 0.5 * (y[n // 2 - 1] + y[n // 2])


def _slots(k0: int, j0: int, k1: int, j1: int, nf: int):
    k, j = k0, j0
    while (k, j) < (k1, j1):
        yield k, j
        j += 1
        if j == nf:
            k, j = k + 1, 0


MAX_LINE_CHARS = 1_000_000
"""The longest line :class:`ToothLines` takes [characters]: a longer one (a file without
line ends, a binary file) is refused, so that the text held stays bounded."""
TOOTH_COLUMNS = {"tooth_time_s": 1.0, "tooth_time_ms": 1e3, "tooth_time_us": 1e6}
"""The column names of tooth edge times, and what each is divided by for seconds (as
:data:`rotor.logs.reader.UNIT_COLUMNS` reads them)."""


class ToothLines:
    """Tooth edge times from text as it arrives: one time per line, ``#`` comment lines (the
    header's ``# tdc_after_gap_deg: DEG`` and ``# firing_parity: 0|1`` kept in ``stated``),
    a column-name line before the first time. :meth:`feed` takes text (a line may be split
    between calls) and returns the times [s] and the notes on lines that are not a time
    (each named by its line number).

    **Line ends**: LF, CRLF and CR alike, a CRLF split between two calls included. The text
    held for a line not yet ended is bounded: a line longer than ``max_line`` characters
    (:data:`MAX_LINE_CHARS`; a file without line ends, a binary file), or a NUL byte, is
    refused (:class:`rotor.LogError` naming the line), and the work is linear in the text
    whatever its line ends (lines of one number are converted together, by NumPy).

    **Columns and units**: the column-name line may name the tooth times' column and their
    unit: ``tooth_time_s``, ``tooth_time_ms`` or ``tooth_time_us`` (among other columns:
    that column is read); a lone column ``time_ms`` or ``time_us`` is read in that unit; the
    times are converted to seconds and a note (:attr:`NoteKind.UNITS`) says so. A name line
    of a sampled signal's columns without a tooth-time column (``time, encoder_v``, a logic
    analyser's ``Time[s], Channel 0``), and a first row of several numbers without a name
    line for them, are refused: the monitor reads tooth edge times. Other names are skipped
    (the times then one a line, in seconds). ``skipped`` counts the lines
    that are not a time. ``name`` (the log's, for the messages) prefixes every error."""

    def __init__(self, max_line: int = MAX_LINE_CHARS, name: str | None = None) -> None:
        if not (isinstance(max_line, int) and max_line > 0):
            raise EngineError(f"max_line = {max_line!r}: a positive number of characters")
        self.max_line = max_line
        self.name = name
        self.stated: dict[str, str] = {}
        self.skipped = 0
        self.column: str | None = None  # the column named in the header, if any
        self._divisor = 1.0  # times as given, divided by this: seconds
        self._col = 0  # the field that holds the time
        self._columns = 1  # fields a row has, by the header (1: one time a line)
        self.restart()

    def restart(self) -> None:
        """A new file (one followed was replaced or truncated): its lines counted from 1, a
        header line read again (the columns and unit of the last one kept where it has none),
        the text held dropped."""
        self.line_no = 0
        self._pieces: list[str] = []
        self._held = 0
        self._cr = False  # the last text ended in CR: an LF that starts the next belongs to it
        self._seen_time = False
        self._header = False

    def _error(self, text: str) -> LogError:
        return LogError(f"{self.name}: {text}" if self.name else text)

    def feed(self, text: str, final: bool = False) -> tuple[np.ndarray, list[Note]]:
        if self._cr:
            text = "\r" + text
            self._cr = False
        if not final and text.endswith("\r"):
            text = text[:-1]
            self._cr = True
        if "\0" in text:
            before = text[: text.index("\0")].replace("\r\n", "\n")
            n = self.line_no + 1 + before.count("\n") + before.count("\r")
            raise self._error(f"line {n}: a NUL byte: a binary or zero-filled file, not tooth times as text")
        if not final and "\n" not in text and "\r" not in text:
            if text:  # no line end yet: held (bounded), not joined again at every call
                self._pieces.append(text)
                self._held += len(text)
                if self._held > self.max_line:
                    raise self._too_long(self.line_no + 1)
            return np.empty(0), []
        if self._pieces:
            text = "".join(self._pieces) + text
            self._pieces, self._held = [], 0
        if "\r" in text:
            text = text.replace("\r\n", "\n").replace("\r", "\n")
        lines = text.split("\n")
        rest = "" if final else lines.pop()
        if len(text) > self.max_line:
            longest = max(range(len(lines)), key=lambda i: len(lines[i]), default=0)
            if lines and len(lines[longest]) > self.max_line:
                raise self._too_long(self.line_no + 1 + longest)
            if len(rest) > self.max_line:
                raise self._too_long(self.line_no + 1 + len(lines))
        if rest:
            self._pieces, self._held = [rest], len(rest)
        first = self.line_no + 1
        self.line_no += len(lines)
        if not lines:
            return np.empty(0), []
        if self._seen_time and self._columns == 1:
            # the usual case: a number a line, converted together (no Python a line)
            try:
                x = np.array(lines, dtype=np.float64)
            except ValueError:  # an empty line, a comment, a bad line: line by line
                x = None
            if x is not None and bool(np.isfinite(x).all()):
                return (x / self._divisor if self._divisor != 1.0 else x), []
        return self._lines(lines, first)

    def _too_long(self, n: int) -> LogError:
        return self._error(
            f"line {n}: longer than {self.max_line:,} characters without a line end: not tooth times, one a "
            "line (a binary file, or one without line ends?)"
        )

    def _lines(self, lines: list[str], first: int) -> tuple[np.ndarray, list[Note]]:
        from .stated import PHASE_KEYS

        times: list[float] = []
        notes: list[Note] = []
        for i, raw in enumerate(lines):
            s = raw.strip()
            if not s:
                continue
            if s.startswith("#"):
                key, sep, value = s[1:].partition(":")
                if sep and key.strip() in PHASE_KEYS and not self._seen_time:
                    self.stated[key.strip()] = value.strip()
                continue
            fields = _fields(s)
            try:
                x = float(fields[self._col])
            except (ValueError, IndexError):
                if not self._seen_time and not self._header:
                    self._read_header(fields, first + i, notes)  # the column names
                    continue
                self.skipped += 1
                shown = s if len(s) <= 40 else s[:37] + "..."
                notes.append(Note(NoteKind.BAD_LINE, None, f"line {first + i}: {shown!r} is not a time: skipped"))
                continue
            if not self._seen_time and self._columns == 1 and len(fields) > 1 and _is_number(fields[1]):
                shown = s if len(s) <= 40 else s[:37] + "..."
                raise self._error(
                    f"line {first + i}: {len(fields)} columns of numbers ({shown!r}) and no header line naming them: "
                    "the monitor reads tooth edge times, one a line, or the column a header line names "
                    "'tooth_time_s' ('tooth_time_ms', 'tooth_time_us'); a sampled signal is read by `rotor analyze`"
                )
            if not math.isfinite(x):
                self.skipped += 1
                notes.append(Note(NoteKind.BAD_LINE, None, f"line {first + i}: {s!r} is not a finite time: skipped"))
                continue
            times.append(x)
            self._seen_time = True
        t = np.asarray(times, dtype=np.float64)
        return (t / self._divisor if self._divisor != 1.0 else t), notes

    def _read_header(self, fields: list[str], n: int, notes: list[Note]) -> None:
        """The column-name line ``fields`` (line ``n``): which column holds the times, in
        which unit; a sampled signal's columns (without a tooth-time column) refused."""
        from ..logs.reader import UNIT_COLUMNS

        self._header = True
        names = [f.strip().lower() for f in fields]
        tooth = [i for i, f in enumerate(names) if f in TOOTH_COLUMNS]
        if tooth:
            col, name, divisor = tooth[0], names[tooth[0]], TOOTH_COLUMNS[names[tooth[0]]]
        elif len(names) == 1 and names[0] in UNIT_COLUMNS:
            col, name, divisor = 0, names[0], float(round(1.0 / UNIT_COLUMNS[names[0]][1]))
        else:
            signal = [f.strip() for f, low in zip(fields, names, strict=True) if _signal_column(low)]
            if signal and len(names) > 1:
                shown = ", ".join(repr(f) for f in signal[:6]) + (", …" if len(signal) > 6 else "")
                raise self._error(
                    f"line {n}: the columns {shown} are a sampled signal, not tooth edge times: the monitor reads one "
                    "time a line, or the column a header line names 'tooth_time_s' ('tooth_time_ms', "
                    "'tooth_time_us'); `rotor analyze` reads a sampled signal"
                )
            col, name, divisor = 0, None, 1.0  # names of its own: the times in seconds, a number a line
            names = names[:1]
        self._col, self._columns, self.column, self._divisor = col, len(names), name, float(divisor)
        if divisor != 1.0:
            notes.append(
                Note(NoteKind.UNITS, None, f"line {n}: column {name!r} read as tooth times in seconds (÷ {divisor:g})")
            )


def _signal_column(name: str) -> bool:
    """Whether the column name ``name`` (lower case) is one of a sampled signal: a reader's
    column other than the tooth times (``time``, ``encoder_v``, …), or a logic analyser's
    (``Time[s]``, ``Channel 0``)."""
    from ..logs.reader import COLUMN_NAMES, UNIT_COLUMNS

    if name in TOOTH_COLUMNS or name == "-":
        return False
    return name in COLUMN_NAMES or name in UNIT_COLUMNS or name.startswith(("time[", "channel"))


def _fields(s: str) -> list[str]:
    """The fields of a row: separated by commas, semicolons, tabs or blanks."""
    for sep in (",", ";", "\t"):
        if sep in s:
            return [f.strip() for f in s.split(sep)]
    return s.split()


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True
