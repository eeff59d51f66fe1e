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
from .catalogue import RANKING_ROWS, AmbiguousPattern, best_pattern, decode_channel, find_pattern, pattern_ways
from .patterns import PatternFit, TriggerPattern, channel_edges, decode_edges
from .reader import Log
from .track import WheelReading, read_track
from .wheel import Wheel

__all__ = ["PatternReading", "read_wheel"]

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
        """The options that read the recording the same way again."""
        return f"--wheel {self.pattern.name}"

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


def _auto(log: Log, name: str) -> PatternReading | None:
    """The catalogue pattern that clearly explains the wheel channel (or, failing it, the cam
    channel), or None where no catalogue pattern fits."""
    if log.kind == "teeth":
        return None  # tooth times: the missing-tooth wheels' finder reads them
    if log.kind != "digital":
        return None
    for channel in ("encoder_d", "cam_d"):
        if channel not in log:
            continue
        try:
            fit, label, why = best_pattern(log["time"], log[channel], name=channel, source=name, whole=False)
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
    log: Log, wheel: str | Wheel | None, *, edge: str = "auto", name: str = ""
) -> WheelReading | PatternReading:
    """The log's wheel signal placed on its wheel, once, for every command (module doc).

    **Arguments:** ``log``; ``wheel``: a missing-tooth spec (``"60-2"``, ``"36-2-1"``), a
    wheel file, a catalogue name (``rotor wheels``), ``"auto"`` or None (the same: found);
    ``edge``: ``"auto"``, ``"rising"`` or ``"falling"``; ``name``: the recording, for messages.

    **Returns** a :class:`rotor.logs.track.WheelReading` or a :class:`PatternReading`.
    **Raises** :class:`LogError` where the wheel does not fit, naming what was tried."""
    name = name or log.source
    if wheel is None:
        wheel = "auto"
    given = _catalogue_only(wheel)
    if given is not None:
        return _decode_given(log, name, given, edge)
    if isinstance(wheel, str) and wheel.strip().lower() == "auto":
        found = _auto(log, name)
        if found is not None:
            spec = found.pattern.name
            if _NM.match(spec) and found.channel == "encoder_d":
                # a missing-tooth wheel: its tracker repairs and estimates tooth errors
                try:
                    reading = read_track(found.log, spec, edge=edge, name=name)
                except LogError:
                    return found
                return dataclasses.replace(reading, notes=(*reading.notes, f"wheel: {found.evidence}"))
            return found
    return read_track(log, wheel, edge=edge, name=name)
