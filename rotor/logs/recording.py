"""The wheel placed once for every command: a log's wheel signal read as the wheel given, or
found, from the missing-tooth wheels and the catalogue of production patterns.

:func:`read_wheel` hands the commands a typed reading: a :class:`rotor.logs.track.WheelReading`
where the wheel is an ``N-g1-g2…`` missing-tooth wheel (its tracker repairs glitches and
missed teeth and estimates tooth errors), or a :class:`PatternReading` where it is one of
the catalogue's other patterns (:mod:`rotor.logs.catalogue`: uneven spacing, cam-speed
wheels, teeth of two widths), read by :func:`rotor.logs.patterns.decode_edges`.

**``wheel="auto"``** (the default where no wheel is named): on digital channels and tooth
times, every catalogue pattern is tried on the wheel channel, then on the cam channel
(a recording whose only placeable signal is its cam); the pattern that explains the edges
best is taken where it clearly does (:func:`rotor.logs.catalogue.best_pattern`), a
missing-tooth one through its tracker. Where no catalogue pattern fits, the missing-tooth
wheels are found from the gaps as before (:func:`rotor.logs.track.read_track`). Analog
signals go to the tracker, which finds their edges and levels.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np

from ..errors import LogError
from .catalogue import (
    CATALOGUE,
    MIN_KEPT,
    RANKING_ROWS,
    AmbiguousPattern,
    best_pattern,
    catalogue_layout,
    decode_channel,
    find_pattern,
    pattern_ways,
    rank_patterns,
)
from .edges import GLOBAL_LEVELS
from .identify import MAX_GAP_MISFIT, MIN_REVOLUTIONS
from .patterns import PatternFit, TriggerPattern, channel_edges, decode_edges, pattern_from_wheel
from .reader import Log
from .track import ChoiceSource, WheelReading, read_track
from .wheel import Wheel

__all__ = ["PatternReading", "ReadingRecord", "read_wheel", "reading_record"]

_NM = re.compile(r"^\d+(-\d+)*$")

EVEN_RATIO = 0.15
"""A wheel's edges are evenly spaced where 90 % of its neighbouring periods differ by less
than this in log [-] (a cranking engine's speed swings included)."""


@dataclasses.dataclass(frozen=True, eq=False)
class PatternReading:
    """A wheel channel read as a catalogue pattern.

    **Fields:** ``log`` (the recording), ``source`` (its name), ``fit`` (the edges placed:
    :class:`rotor.logs.patterns.PatternFit`), ``channel`` (the column read), ``edges``
    (which of its edges, in words, e.g. ``"falling (inverted)"``), ``found`` (whether the
    pattern was found from the signal rather than given), ``evidence`` (why, in words)."""

    log: Log
    source: str
    fit: PatternFit
    channel: str
    edges: str
    found: bool
    evidence: str = ""

    @property
    def pattern(self) -> TriggerPattern:
        return self.fit.pattern

    def pins(self) -> str:
        """The argument that reads the recording the same way again (``wheel='mazda-nb-cam'``;
        the command line prints it as its flag)."""
        return f"wheel={self.pattern.name!r}"

    def notes(self) -> tuple[str, ...]:
        out = []
        if self.found:
            out.append(f"wheel: {self.evidence}")
        if self.channel != "encoder_d":
            out.append(f"the wheel is read from the {self.channel} channel: the wheel channel fits no pattern")
        if self.fit.repeats > 1:
            out.append(
                f"{self.pattern.name} repeats {self.fit.repeats}× a turn: its angle is known modulo "
                f"{self.pattern.period_deg / self.fit.repeats:g}°"
            )
        for a, b in self.fit.dropped:
            out.append(f"edges from {a:.6f} to {b:.6f} s do not follow the pattern and are left out")
        return tuple(out)

    def to_json_dict(self) -> dict:
        f = self.fit
        return {
            "pattern": self.pattern.to_json_dict(),
            "channel": self.channel,
            "edges_read": self.edges,
            "found": self.found,
            "evidence": self.evidence or None,
            "edges": int(f.t.size),
            "kept_fraction": float(f.kept),
            "turns": float(f.turns),
            "log_ratio_rms": float(f.rms),
            "dropped_s": [[float(a), float(b)] for a, b in f.dropped],
            "pins": self.pins(),
        }


@dataclasses.dataclass(frozen=True)
class ReadingRecord:
    """How a recording's wheel signal was read, to read another recording of the same
    installation the same way (a calibration keeps it: :func:`read_wheel` with ``as_read``).

    **Fields:** ``wheel``: the wheel's spec or the catalogue pattern's name; ``edge``: the
    edges read (``"rising"``, ``"falling"``, a pattern's ``"falling (inverted)"``, …, or None
    for tooth times); ``channel``: the column read (``encoder_v``, ``encoder_d``, ``cam_d``,
    ``tooth_time_s``); ``levels``: how an analog signal's edges were found (``"global
    levels"``, ``"adaptive levels"``, ``"zero crossings (VR)"``), else None; ``level``: the
    fraction of the swing its edges were timed at [-] (global levels), else None."""

    wheel: str
    edge: str | None
    channel: str
    levels: str | None = None
    level: float | None = None

    def to_json_dict(self) -> dict:
        return {
            "wheel": self.wheel,
            "edge": self.edge,
            "channel": self.channel,
            "levels": self.levels,
            "level": None if self.level is None else round(float(self.level), 4),
        }

    @classmethod
    def from_json_dict(cls, d: object) -> ReadingRecord:
        """The record from its JSON (:meth:`to_json_dict`); LogError naming what is missing."""
        if not isinstance(d, dict) or not isinstance(d.get("wheel"), str) or not isinstance(d.get("channel"), str):
            raise LogError(
                f"a reading record needs the wheel and the channel read (strings); got {d!r:.120}", argument="as_read"
            )
        edge, levels, level = d.get("edge"), d.get("levels"), d.get("level")
        if not (edge is None or isinstance(edge, str)) or not (levels is None or isinstance(levels, str)):
            raise LogError(
                f"a reading record's edge and levels are strings or null; got {d!r:.120}", argument="as_read"
            )
        if level is not None and not (
            isinstance(level, (int, float)) and not isinstance(level, bool) and 0.0 < level < 1.0
        ):
            raise LogError(
                f"a reading record's level is a fraction of the swing, 0 … 1, or null; got {level!r}",
                argument="as_read",
            )
        return cls(d["wheel"], edge, d["channel"], levels, None if level is None else float(level))

    def differences(self, other: ReadingRecord) -> list[str]:
        """What ``other`` reads otherwise than this record, in words (empty where the same)."""
        out = [
            f"{what} {getattr(self, field)} there, {getattr(other, field)} here"
            for field, what in (("wheel", "wheel"), ("channel", "channel"), ("edge", "edges"), ("levels", "levels"))
            if getattr(self, field) != getattr(other, field)
        ]
        if self.level is not None and other.level is not None and abs(self.level - other.level) > 0.02:
            out.append(f"edges timed at {self.level:.0%} of the swing there, {other.level:.0%} here")
        return out


def reading_record(reading: WheelReading | PatternReading) -> ReadingRecord:
    """The :class:`ReadingRecord` of a reading."""
    if isinstance(reading, PatternReading):
        return ReadingRecord(reading.pattern.name, reading.edges, reading.channel)
    kind = reading.log.kind
    channel = {"teeth": "tooth_time_s", "digital": "encoder_d", "encoder": "encoder_v"}.get(kind, kind)
    e = reading.edges
    if e is None or kind != "encoder":
        return ReadingRecord(reading.wheel.spec, reading.edge, channel)
    swing = e.high_v - e.low_v  # low, high and level of the signal as read (negated for falling edges)
    level = (e.level_v - e.low_v) / swing if swing > 0 and e.method == GLOBAL_LEVELS else None
    return ReadingRecord(reading.wheel.spec, reading.edge, channel, e.method, level)


def _catalogue_only(spec: object) -> TriggerPattern | None:
    """The catalogue pattern ``spec`` names where it is not a missing-tooth wheel, else None."""
    if not isinstance(spec, str) or spec.strip().lower() == "auto" or spec.lower().endswith(".toml"):
        return None
    if _NM.match(spec.strip()):
        return None
    try:
        return find_pattern(spec)
    except LogError:
        return None


def _decode_given(log: Log, name: str, pattern: TriggerPattern, edge: str) -> PatternReading:
    if log.kind == "teeth":
        fit = decode_edges(log["tooth_time_s"], pattern)
        return PatternReading(log, name, fit, "tooth_time_s", pattern.read, False)
    if log.kind != "digital":
        raise LogError(
            f"{name}: the {pattern.name} pattern is read from digital channels (encoder_d) or tooth times; "
            f"this log's wheel signal is {log.kind}",
            argument="wheel",
        )
    tries = []
    for label, take, pol, inverted in _ways(pattern, edge):
        times, kinds = channel_edges(log["time"], log["encoder_d"], take)
        try:
            fit = decode_edges(times, pattern, pol, kinds=(1 - kinds if inverted else kinds) if pol == "both" else None)
        except LogError as e:
            tries.append(f"{label} edges: {e}")
            continue
        return PatternReading(log, name, fit, "encoder_d", label, False)
    raise LogError(f"{name}: the {pattern.name} pattern does not fit: " + "; ".join(tries), argument="wheel")


def _ways(pattern: TriggerPattern, edge: str):
    ways = pattern_ways(pattern)
    if edge in ("rising", "falling"):
        ways = [w for w in ways if w[1] == edge or w[1] == "both"]
    return ways


def _with_wheel_channel(log: Log, channel: str) -> Log:
    """``log`` with ``channel`` (a cam channel) read as the wheel channel."""
    cols = {k: v for k, v in log.columns.items() if k not in ("encoder_d", channel)}
    cols["encoder_d"] = log[channel]
    return Log(cols, log.lines, log.source, log.notes)


def _auto(log: Log, name: str, ranked: dict) -> PatternReading | None:
    """The catalogue pattern that clearly explains the wheel channel (or, failing it, the cam
    channel), or None where no catalogue pattern fits; ``ranked`` gets each channel's ranking
    (:func:`rotor.logs.catalogue.rank_patterns`, partial fits included), for the checks after."""
    if log.kind == "teeth":
        return None  # tooth times: the missing-tooth wheels' finder reads them
    if log.kind != "digital":
        return None
    for channel in ("encoder_d", "cam_d"):
        if channel not in log:
            continue
        ranked[channel] = rank_patterns(log["time"], log[channel], name=channel, partial=True)
        try:
            fit, label, why = best_pattern(
                log["time"], log[channel], name=channel, source=name, whole=False, ranked=ranked[channel]
            )
        except AmbiguousPattern:
            raise
        except LogError:
            continue  # no pattern fits this channel: the next, or the missing-tooth finder
        if log.rows > RANKING_ROWS and not (_NM.match(fit.pattern.name) and channel == "encoder_d"):
            fit = decode_channel(log["time"], log[channel], fit.pattern, label, name=channel)
        used = log if channel == "encoder_d" else _with_wheel_channel(log, channel)
        return PatternReading(used, name, fit, channel, label, True, why)
    return _even_wheel_by_cam(log, name)


def _even_wheel_by_cam(log: Log, name: str) -> PatternReading | None:
    """An evenly spaced wheel counted against a cam channel of one edge a cycle: the wheel's
    edges between neighbouring cam edges, the same number M (even) in nearly every cycle, give
    M/2 teeth a revolution (a cam turns once a cycle). None where that does not hold."""
    if "cam_d" not in log:
        return None
    times, _ = channel_edges(log["time"], log["encoder_d"], "rising")
    cam, _ = channel_edges(log["time"], log["cam_d"], "rising", name="cam_d")
    if times.size < 24 or cam.size < 3:
        return None
    r = np.abs(np.log(times[2:] - times[1:-1]) - np.log(times[1:-1] - times[:-2]))
    if float(np.percentile(r, 90)) > EVEN_RATIO:
        return None
    counts = np.diff(np.searchsorted(times, cam))
    if counts.size < 2:
        return None
    m = int(np.bincount(counts).argmax())
    share = float(np.mean(counts == m))
    if m < 4 or m % 2 or share < 0.8:
        return None
    teeth = m // 2
    pattern = TriggerPattern(
        f"{teeth}-tooth",
        f"{teeth} evenly spaced crank teeth, counted against a cam edge a cycle",
        360.0,
        tuple(360.0 * k / teeth for k in range(teeth)),
        (),
        "rising",
        "crank",
        "counted from the recording: evenly spaced edges, the same number between the cam's edges",
    )
    fit = decode_edges(times, pattern)
    why = (
        f"{teeth}-tooth: the wheel's edges are evenly spaced and {m} of them fall between neighbouring cam edges "
        f"in {share:.0%} of the cycles, so {teeth} a revolution (a cam turns once a cycle)"
    )
    return PatternReading(log, name, fit, "encoder_d", "rising", True, why)


def read_wheel(
    log: Log,
    wheel: str | Wheel | None,
    *,
    edge: str = "auto",
    name: str = "",
    as_read: ReadingRecord | None = None,
) -> WheelReading | PatternReading:
    """The log's wheel signal placed on its wheel, once, for every command (module doc).

    **Arguments:** ``log``; ``wheel``: a missing-tooth spec (``"60-2"``, ``"36-2-1"``), a
    wheel file, a catalogue name (``rotor wheels``), ``"auto"`` or None (the same: found);
    ``edge``: ``"auto"``, ``"rising"`` or ``"falling"``; ``name``: the recording, for messages;
    ``as_read``: the :class:`ReadingRecord` of another recording of the installation (a
    calibration's): this one is read with its wheel and edges, and refused, naming the
    difference, where it reads otherwise (another channel, other levels).

    **Returns** a :class:`rotor.logs.track.WheelReading` or a :class:`PatternReading`.
    **Raises** :class:`LogError` where the wheel does not fit, naming what was tried."""
    if as_read is not None:
        return _read_as_recorded(log, as_read, name or log.source)
    name = name or log.source
    if wheel is None:
        wheel = "auto"
    given = _catalogue_only(wheel)
    if given is not None:
        return _decode_given(log, name, given, edge)
    if isinstance(wheel, str) and wheel.strip().lower() == "auto":
        ranked: dict = {}
        found = _auto(log, name, ranked)
        if found is not None:
            spec = found.pattern.name
            if _NM.match(spec) and found.channel == "encoder_d":
                # a missing-tooth wheel: its tracker repairs and estimates tooth errors
                try:
                    reading = read_track(found.log, spec, edge=edge, name=name)
                    if reading.fit.revolutions < MIN_REVOLUTIONS or reading.fit.gap_misfit > MAX_GAP_MISFIT:
                        raise LogError(f"{name}: {spec} placed on too little of the log, or loosely")
                except LogError:
                    # the tracker does not follow it (edges too irregular for its repairs): a catalogue
                    # wheel the gaps also find is taken, else the pattern as the decoder placed it
                    try:
                        other = read_track(log, "auto", edge=edge, name=name)
                    except LogError:
                        return found
                    return other if _known_wheel(other.wheel) else found
                return dataclasses.replace(reading, notes=(*reading.notes, f"wheel: {found.evidence}"))
            return found
        reading = read_track(log, wheel, edge=edge, name=name)
        _refuse_a_half_of_a_known_wheel(reading, name)
        _refuse_a_loose_counted_wheel(reading, name)
        _refuse_where_a_pattern_explains_better(reading, name, ranked.get("encoder_d"))
        return reading
    return read_track(log, wheel, edge=edge, name=name)


def _read_as_recorded(log: Log, record: ReadingRecord, name: str) -> WheelReading | PatternReading:
    edge = record.edge if record.edge in ("rising", "falling") else "auto"
    try:
        if record.level is not None and log.kind == "encoder" and _catalogue_only(record.wheel) is None:
            reading: WheelReading | PatternReading = read_track(
                log, record.wheel, edge=edge, name=name, level=record.level
            )
        else:
            reading = read_wheel(log, record.wheel, edge=edge, name=name)
    except LogError as e:
        raise LogError(
            f"{name}: not read as the calibration's recording was ({record.wheel}, {record.edge} edges of "
            f"{record.channel}): {e}",
            argument="as_read",
        ) from None
    diff = record.differences(reading_record(reading))
    if diff:
        raise LogError(
            f"{name}: read otherwise than the calibration's recording ({'; '.join(diff)}): another installation, "
            "or another sensor; calibrate on a recording of this one",
            argument="as_read",
        )
    return reading


RIVAL_SHARE = 0.6
"""A catalogue pattern that places at least this share of what a wheel found from the gaps
places (by its own edge list) questions that wheel: both are named and the log refused [-]."""
COUNTED_MISFIT = 0.05
"""A wheel counted from the gaps that is no catalogue or standard wheel is taken only where it
fits cleanly: no repair and a gap misfit below this [-]."""


def _known_wheel(wheel: Wheel) -> bool:
    """Whether a wheel found from the gaps is a catalogue wheel (its gaps where the catalogue's
    are, read round from any tooth) or a standard one the catalogue does not list."""
    from .identify import STANDARD_WHEELS

    if wheel.spec not in CATALOGUE:
        return wheel.spec in STANDARD_WHEELS
    return catalogue_layout(wheel)


def _refuse_a_loose_counted_wheel(reading: WheelReading, name: str) -> None:
    """Refuse a wheel counted from the gaps that no catalogue names, unless its edges fit it
    cleanly: a few displaced or missed edges make the gaps of some other count. On a digital
    channel (an ECU's or logic analyser's: a production wheel) it is always refused."""
    from .identify import FitStatus

    f = reading.fit
    choice = reading.choice("wheel")
    if choice is None or choice.source is not ChoiceSource.FOUND or _known_wheel(reading.wheel):
        return
    if reading.log.kind == "digital" or f.status is not FitStatus.FITS or f.gap_misfit > COUNTED_MISFIT:
        how = (
            ""
            if reading.log.kind == "digital"
            else f", and the edges fit it only loosely (gap misfit {100 * f.gap_misfit:.1f} %, {f.status.value})"
        )
        raise LogError(
            f"{name}: the gaps suggest a {f.spec} wheel, which no catalogue pattern is{how}; give the wheel "
            f"(wheel='{f.spec}' if that is it, or a catalogue name: `rotor wheels`)",
            argument="wheel",
        )


def _refuse_where_a_pattern_explains_better(reading: WheelReading, name: str, ranked: list | None) -> None:
    """On a digital channel, a wheel found from the gaps whose own edge list does not place the
    edges, where a catalogue pattern of other geometry places part of them: the two are named
    and the log refused (the gaps can be made by the other pattern's marks)."""
    log = reading.log
    if log.kind != "digital":
        return
    own = pattern_from_wheel(reading.wheel.teeth, reading.wheel.gaps, reading.wheel.layout)
    times, _ = channel_edges(log["time"], log["encoder_d"], reading.edge or "rising")
    try:
        placed = decode_edges(times[: RANKING_ROWS // 2], own).kept
    except LogError:
        placed = 0.0
    rivals = [
        (s, f)
        for s, f, _ in (rank_patterns(log["time"], log["encoder_d"], partial=True) if ranked is None else ranked)
        if f.pattern.name != own.name and f.pattern.name != reading.wheel.spec and f.kept >= RIVAL_SHARE * placed
    ]
    if placed < MIN_KEPT or rivals:
        if not rivals:
            return  # nothing else places them either: the gaps are the evidence
        s, f = rivals[0]
        raise AmbiguousPattern(
            f"{name}: the gaps suggest a {reading.wheel.spec} wheel, but its edge list does not place the edges, and "
            f"the {f.pattern.name} pattern places {f.kept:.0%} of them; give the wheel "
            f"(wheel='{reading.wheel.spec}' or wheel='{f.pattern.name}')",
            argument="wheel",
        )


def _refuse_a_half_of_a_known_wheel(reading: WheelReading, name: str) -> None:
    """Refuse a wheel found from the gaps whose edges are, in timing, a part of a catalogue
    wheel that repeats within its turn (an ``18-2`` found where a ``36-2-2`` wheel's two equal
    halves give the same edges): the two differ in speed by the repetition, and only the
    user knows which it is."""
    w = reading.wheel
    for p in CATALOGUE.values():
        m = p.repeats()
        if m < 2 or not _NM.match(p.name):
            continue
        parts = [int(x) for x in p.name.split("-")]
        teeth, gaps = parts[0], parts[1:]
        if teeth % m or len(gaps) % m:
            continue
        unit = f"{teeth // m}" + "".join(f"-{g}" for g in gaps[: len(gaps) // m])
        if w.spec == unit:
            raise AmbiguousPattern(
                f"{name}: the edges fit a {w.spec} wheel, and in timing alike a {p.name} wheel ({p.title}), whose "
                f"speed is 1/{m} of it; give the wheel (wheel='{w.spec}' or wheel='{p.name}')",
                argument="wheel",
            )
