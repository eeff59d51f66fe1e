"""Tooth edges of a sampled (analog) trigger-wheel signal.

The signal's two levels come from its own statistics, not from constants: the samples
between the 1st and 99th percentiles are split at their midpoint, and the median of
each half is that level (robust to the duty cycle, to spikes, to any gain or offset).
A Schmitt trigger with thresholds at ``band`` (fractions of the way from the low to the
high level, default 20 % and 45 %) turns the signal into one state per sample; runs of a
state much shorter than that state's typical run (``glitch`` × its median run length)
are noise and are removed, so a noisy pulse counts once and a narrow pulse next to the
gap still counts (it is short, but not that short). Each remaining low→high transition
is placed, to a fraction of a sample, at the last crossing of the ``level`` (default
32 %) before it, by linear interpolation between the two samples around the crossing.
A pulse that is low (reaches only half of the high level) still crosses 45 %, and the
32 % crossing sits on its rising flank like that of a full pulse. Levels, not
constants: the same defaults serve a 0.05 V and a 5 V signal, offset or inverted.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from jaxtyping import ArrayLike

from ..errors import LogError

__all__ = ["Edges", "find_edges", "signal_levels"]


@dataclasses.dataclass(frozen=True, eq=False)
class Edges:
    """Edges found in a sampled signal.

    **Attributes:** ``times`` [s] (sub-sample, increasing); ``low_v``, ``high_v``: the
    signal's two levels [V]; ``thresholds_v``: the Schmitt trigger's (off, on) thresholds
    [V]; ``level_v``: the crossing level the times are interpolated at [V];
    ``glitches``: short runs removed as noise; ``inverted``: whether the signal was
    negated (falling edges asked for).
    """

    times: np.ndarray
    low_v: float
    high_v: float
    thresholds_v: tuple
    level_v: float
    glitches: int
    inverted: bool

    def to_json_dict(self) -> dict:
        """Plain JSON: the edge count, the levels and thresholds [V], glitches removed, the edge."""
        return {
            "edges": int(self.times.size),
            "low_v": float(self.low_v),
            "high_v": float(self.high_v),
            "thresholds_v": [float(x) for x in self.thresholds_v],
            "level_v": float(self.level_v),
            "glitches_removed": int(self.glitches),
            "edge": "falling" if self.inverted else "rising",
        }


def signal_levels(v: ArrayLike, name: str = "encoder_v") -> tuple[float, float]:
    """(low, high) levels [V] of a two-level pulse signal, from its own statistics.

    Raises :class:`LogError` if the signal has no two distinct levels.
    """
    v = np.asarray(v, dtype=np.float64)
    if v.size < 3:
        raise LogError(f"column {name!r}: {v.size} samples; no pulses")
    p1, p99 = np.percentile(v, [1.0, 99.0])
    mid = 0.5 * (p1 + p99)
    core = v[(v >= p1) & (v <= p99)]
    lo_part, hi_part = core[core < mid], core[core >= mid]
    if lo_part.size < 0.005 * v.size or hi_part.size < 0.005 * v.size or not p99 > p1:
        raise LogError(
            f"column {name!r}: no pulses found (the signal sits at one level, "
            f"{p1:.4g} … {p99:.4g} between its 1st and 99th percentiles)"
        )
    low, high = float(np.median(lo_part)), float(np.median(hi_part))
    # a pulse train spends most of its time near its two levels; noise or a ramp does not
    near = np.mean((np.abs(v - low) < 0.15 * (high - low)) | (np.abs(v - high) < 0.15 * (high - low)))
    if not (high > low and near >= 0.6):
        raise LogError(
            f"column {name!r}: no clear pulses (levels {low:.4g} and {high:.4g} V, but only "
            f"{near:.0%} of the samples lie near them)"
        )
    return low, high


def _samples(x: ArrayLike, what: str) -> np.ndarray:
    """``x`` as a 1-d float64 array; a TypeError naming ``what`` otherwise."""
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"find_edges({what}): an array of numbers, not {type(x).__name__} {x!r:.40}") from None
    if a.ndim != 1:
        raise LogError(f"find_edges({what}): a 1-d array, got shape {a.shape}")
    return a


def _runs(s):
    """Start index, length and value of each run of equal values in s."""
    change = np.flatnonzero(np.diff(s)) + 1
    starts = np.concatenate([[0], change])
    lengths = np.diff(np.concatenate([starts, [s.size]]))
    return starts, lengths, s[starts]


def find_edges(
    t: ArrayLike,
    v: ArrayLike,
    *,
    edge: str = "rising",
    band: tuple[float, float] = (0.2, 0.45),
    level: float = 0.32,
    glitch: float = 0.2,
    name: str = "encoder_v",
) -> Edges:
    """Times [s] of the tooth edges of a sampled wheel signal.

    **Arguments:**
    - ``t``: sample times [s], increasing; ``v``: the signal [V] (any gain, offset, sign).
    - ``edge``: ``"rising"`` (default) or ``"falling"`` (the signal is negated first).
    - ``band``: the Schmitt trigger's (off, on) thresholds as fractions from the low to
      the high level [-].
    - ``level``: the fraction at which each edge's crossing is interpolated [-].
    - ``glitch``: runs shorter than this fraction of the median run of the same state
      are removed as noise [-].

    **Returns:** :class:`Edges`.
    """
    if edge not in ("rising", "falling"):
        raise LogError(f"edge = {edge!r}: 'rising' or 'falling'")
    if not (0 < band[0] < level < band[1] < 1):
        raise LogError(f"band = {band!r}, level = {level!r}: need 0 < off < level < on < 1")
    t = _samples(t, "t")
    v = _samples(v, "v")
    if t.shape != v.shape:
        raise LogError(f"{name}: {v.size} samples but {t.size} sample times; give one time per sample")
    if t.size < 3 or not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise LogError(
            f"{name}: {t.size} sample{'s' if t.size != 1 else ''}"
            + (" (not all finite)" if t.size >= 3 else "")
            + "; a wheel signal needs many samples per tooth"
        )
    inverted = edge == "falling"
    if inverted:
        v = -v
    low, high = signal_levels(v, name)
    amp = high - low
    off, on = low + band[0] * amp, low + band[1] * amp
    lev = low + level * amp
    # Schmitt trigger: 1 above `on`, 0 below `off`, else the last decisive state
    decisive = (v > on) | (v < off)
    idx = np.where(decisive, np.arange(v.size), -1)
    np.maximum.accumulate(idx, out=idx)
    first = int(np.argmax(decisive))
    idx[idx < 0] = first
    s = (v[idx] > on).astype(np.int8)
    # remove glitches: runs much shorter than the typical run of their state, the shortest first
    glitches = 0
    for frac in (glitch / 4, glitch / 2, glitch):
        starts, lengths, vals = _runs(s)
        if starts.size <= 4:
            break
        short = np.zeros(starts.size, bool)
        inner = np.zeros(starts.size, bool)
        inner[1:-1] = True  # the first and last runs are cut by the record
        for state in (0, 1):
            m = inner & (vals == state)
            if np.any(m):
                short |= m & (lengths < frac * np.median(lengths[m]))
        if np.any(short):
            glitches += int(short.sum())
            s = np.where(np.repeat(short, lengths), 1 - s, s).astype(np.int8)
    rise = np.flatnonzero(np.diff(s) == 1) + 1  # first sample of each high state
    # the last crossing of `lev` at or before each rise: v[j] < lev <= v[j + 1]
    up = np.flatnonzero((v[:-1] < lev) & (v[1:] >= lev))
    k = np.searchsorted(up, rise, side="left") - 1  # crossings with j + 1 <= rise
    ok = k >= 0
    j = up[k[ok]]
    frac = (lev - v[j]) / (v[j + 1] - v[j])
    times = t[j] + frac * (t[j + 1] - t[j])
    # two rises cannot share one crossing (a glitch that survived): keep the first
    keep = np.concatenate([[True], np.diff(j) > 0]) if j.size else np.zeros(0, bool)
    return Edges(times[keep], low, high, (off, on), lev, glitches + int((~keep).sum()), inverted)
