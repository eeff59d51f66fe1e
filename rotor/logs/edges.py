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
32 % crossing sits on its rising flank like that of a full pulse (later on it, by
(32 % / its height − 32 %) of the flank's duration). A tooth too weak to cross 45 %
is looked for where the wheel's pattern says one is missing (:func:`find_weak_edges`),
and placed at 32 % of its own height. Levels, not
constants: the same defaults serve a 0.05 V and a 5 V signal, offset or inverted.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import LogError
from .windows import running

GLOBAL_LEVELS = "global levels"  # Edges.method of each way of finding the levels
ADAPTIVE_LEVELS = "adaptive levels"
VR_CROSSINGS = "zero crossings (VR)"
LEVEL_SAMPLES = 250_000
"""A signal's levels and noise are read from at most this many of its samples [-] (a fixed
random draw for the levels, contiguous blocks for the noise)."""
VR_BAND = (0.4, 0.6)
VR_TIMING = 0.65  # a VR tooth's flank is measured below where it has risen to this fraction of the swing [-]
"""A variable-reluctance signal's Schmitt trigger (off, on) as fractions from its local low to
its local high [-]: a tooth arms it where its lobe reaches a fifth of the local peak (a weak
tooth next to the gap, a third of its neighbours, still counts), as an adaptive-threshold VR
interface arms at a fraction of the recent peaks."""

__all__ = [
    "LEVEL_SAMPLES",
    "VR_BAND",
    "Edges",
    "find_edges",
    "find_weak_edges",
    "noise_rms",
    "signal_levels",
    "two_level_locally",
]


@dataclasses.dataclass(frozen=True, eq=False)
class Edges:
    """Edges found in a sampled signal.

    **Attributes:** ``times`` [s] (sub-sample, increasing); ``low_v``, ``high_v``: the
    signal's two levels [V]; ``thresholds_v``: the Schmitt trigger's (off, on) thresholds
    [V]; ``level_v``: the crossing level the times are interpolated at [V];
    ``glitches``: short runs removed as noise; ``inverted``: whether the signal was
    negated (falling edges asked for); ``repairs``: the glitches removed, one
    :class:`rotor.logs.wheel.Repair` each, where they are itemised (digital channels);
    ``method``: how the levels were found (``"global levels"``, ``"adaptive levels"``,
    ``"zero crossings"``, ``"digital"``).
    """

    times: np.ndarray
    low_v: float
    high_v: float
    thresholds_v: tuple
    level_v: float
    glitches: int
    inverted: bool
    repairs: tuple = ()
    method: str = GLOBAL_LEVELS

    def to_json_dict(self) -> dict:
        """Plain JSON: the edge count, the levels and thresholds [V], glitches removed, the
        edge, how the levels were found."""
        return {
            "edges": int(self.times.size),
            "low_v": float(self.low_v),
            "high_v": float(self.high_v),
            "thresholds_v": [float(x) for x in self.thresholds_v],
            "level_v": float(self.level_v),
            "glitches_removed": int(self.glitches),
            "edge": "falling" if self.inverted else "rising",
            "method": self.method,
        }


def signal_levels(v: ArrayLike, name: str = "encoder_v") -> tuple[float, float]:
    """(low, high) levels [V] of a two-level pulse signal, from its own statistics.

    Raises :class:`LogError` if the signal has no two distinct levels.
    """
    v = np.asarray(v, dtype=np.float64)
    if v.size < 3:
        raise LogError(f"column {name!r}: {v.size} samples; no pulses")
    if v.size > LEVEL_SAMPLES:  # the levels of a long signal from a fixed random draw of its samples
        v = v[np.sort(np.random.default_rng(0).integers(0, v.size, LEVEL_SAMPLES))]
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


def _all_finite(x: np.ndarray) -> bool:
    """Whether every element is finite: a sum first (one fast pass; finite unless an element is
    not, or the sum overflows), the elements themselves only where it is not."""
    with np.errstate(over="ignore", invalid="ignore"):
        if np.isfinite(np.sum(x)):
            return True
    return bool(np.isfinite(x).all())


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
    levels: str = "global",
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
    - ``levels``: ``"global"`` (default: the signal's two levels over the whole log),
      ``"adaptive"`` (the levels follow the signal: the running minimum and maximum over
      each tooth period and two on either side, so an amplitude that grows with speed or an offset that
      drifts is followed; a stretch whose swing is under 5 % of the largest is no tooth),
      or ``"vr"``: a variable-reluctance sensor's signal, whose amplitude grows with speed
      and changes sign on every tooth: adaptive levels, a Schmitt trigger at :data:`VR_BAND`
      (40 % / 60 %) and the edge at the mid-level, the zero crossing of a signal centred on zero (give
      ``edge="falling"`` for the positive-to-negative crossing most VR conditioners use).

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
    if t.size < 3 or not (_all_finite(t) and _all_finite(v)):
        raise LogError(
            f"{name}: {t.size} sample{'s' if t.size != 1 else ''}"
            + (" (not all finite)" if t.size >= 3 else "")
            + "; a wheel signal needs many samples per tooth"
        )
    if levels not in ("global", "adaptive", "vr"):
        raise LogError(f"levels = {levels!r}: 'global', 'adaptive' or 'vr'")
    inverted = edge == "falling"
    if levels == "global":
        return _global_edges(t, v, inverted, band, level, glitch, name)
    if inverted:
        v = -v
    method = GLOBAL_LEVELS
    off: Any
    on: Any
    lev: Any
    if levels == "global":
        low, high = signal_levels(v, name)
        amp = high - low
        off, on = low + band[0] * amp, low + band[1] * amp
        lev = low + level * amp
    else:
        if levels == "vr":
            band, level = VR_BAND, 0.5
        lo_env, hi_env = _envelope(v, name)
        amp_env = hi_env - lo_env
        off, on = lo_env + band[0] * amp_env, lo_env + band[1] * amp_env
        lev = lo_env + level * amp_env
        quiet = amp_env < 0.05 * float(np.max(amp_env))
        on = np.where(quiet, np.inf, on)
        off = np.where(quiet, -np.inf, off)
        low, high = float(np.median(lo_env)), float(np.median(hi_env))
        method = VR_CROSSINGS if levels == "vr" else ADAPTIVE_LEVELS
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
    d = v - lev
    up = np.flatnonzero((d[:-1] < 0) & (d[1:] >= 0))
    k = np.searchsorted(up, rise, side="left") - 1  # crossings with j + 1 <= rise
    ok = k >= 0
    j = up[k[ok]]
    frac = -d[j] / (d[j + 1] - d[j])
    times = t[j] + frac * (t[j + 1] - t[j])
    if levels == "vr" and j.size:
        # timed on the flank above the arming level, where a full tooth has risen to VR_TIMING of its swing
        times = _from_the_flank(t, v, _risen(v, rise[ok], lo_env + VR_TIMING * amp_env), times, lev, amp_env)
    # two rises cannot share one crossing (a glitch that survived): keep the first
    keep = np.concatenate([[True], np.diff(j) > 0]) if j.size else np.zeros(0, bool)
    if levels != "global":
        off, on, lev = (
            float(np.median(off[np.isfinite(off)])),
            float(np.median(on[np.isfinite(on)])),
            float(np.median(lev)),
        )
    return Edges(times[keep], low, high, (off, on), lev, glitches + int((~keep).sum()), inverted, (), method)


def _state_runs(above: np.ndarray, below: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(start index, state) of each run of a Schmitt trigger's state, 1 from a sample in ``above``
    on, 0 from one in ``below`` on (before the first decisive sample: the first one's state),
    from the places where the signal enters either band: no pass over the samples per state."""
    ua = np.flatnonzero(above[1:] & ~above[:-1]) + 1
    ub = np.flatnonzero(below[1:] & ~below[:-1]) + 1
    ev = np.concatenate([[0] if above[0] else [], ua, [0] if below[0] else [], ub]).astype(np.int64)
    typ = np.concatenate([np.ones(ua.size + int(above[0]), np.int8), np.zeros(ub.size + int(below[0]), np.int8)])
    order = np.argsort(ev, kind="stable")
    ev, typ = ev[order], typ[order]
    if ev.size == 0:
        return np.zeros(1, np.int64), np.zeros(1, np.int8)
    change = np.concatenate([[True], typ[1:] != typ[:-1]])
    starts, vals = ev[change], typ[change]
    starts[0] = 0
    return starts, vals


def _global_edges(t, v, inverted, band, level, glitch, name) -> Edges:
    """:func:`find_edges` with the signal's global levels, without a copy of it per polarity:
    the Schmitt trigger's state from where the signal enters its bands, the glitches removed
    run by run, each edge's crossing looked for on its own flank."""
    low, high = signal_levels(v, name)
    sign = -1.0 if inverted else 1.0
    if inverted:
        low, high = -high, -low
    amp = high - low
    off, on = low + band[0] * amp, low + band[1] * amp
    lev = low + level * amp
    if inverted:
        above, below = v < -on, v > -off
    else:
        above, below = v > on, v < off
    starts, vals = _state_runs(above, below)
    del above, below
    n = v.size
    glitches = 0
    medians: dict = {}  # of each state's run lengths, until the runs change
    for frac in (glitch / 4, glitch / 2, glitch):
        if starts.size <= 4:
            break
        lengths = np.diff(np.concatenate([starts, [n]]))
        short = np.zeros(starts.size, bool)
        inner = np.zeros(starts.size, bool)
        inner[1:-1] = True  # the first and last runs are cut by the record
        for state in (0, 1):
            m = inner & (vals == state)
            if np.any(m):
                if state not in medians:
                    medians[state] = np.median(lengths[m])
                short |= m & (lengths < frac * medians[state])
        if np.any(short):
            medians = {}
            glitches += int(short.sum())
            vals = (vals ^ short).astype(np.int8)
            keep = np.concatenate([[True], vals[1:] != vals[:-1]])
            starts, vals = starts[keep], vals[keep]
    rise = starts[1:][(vals[1:] == 1) & (vals[:-1] == 0)]  # first sample of each high state
    # the last crossing of `lev` at or before each rise (v[j] < lev <= v[j + 1], j + 1 <= rise), on its flank
    j = np.full(rise.size, -1, np.int64)
    todo = np.arange(rise.size)
    for W in (4, 32, 512):
        if todo.size == 0:
            break
        r = rise[todo]
        idx = r[:, None] - W + np.arange(W + 1)[None, :]
        valid = idx >= 0
        d = sign * np.take(v, idx, mode="clip") - lev
        up = (d[:, :-1] < 0) & (d[:, 1:] >= 0) & valid[:, :-1]
        has = up.any(axis=1)
        last = W - 1 - np.argmax(up[:, ::-1], axis=1)
        j[todo[has]] = (r - W + last)[has]
        todo = todo[~has]
    if todo.size:  # a slow flank: the crossing anywhere before the rise
        d = sign * v - lev
        upg = np.flatnonzero((d[:-1] < 0) & (d[1:] >= 0))
        k = np.searchsorted(upg, rise[todo], side="left") - 1
        j[todo] = np.where(k >= 0, upg[np.maximum(k, 0)] if upg.size else -1, -1)
    j = j[j >= 0]
    d0, d1 = sign * v[j] - lev, sign * v[j + 1] - lev
    times = t[j] + (-d0 / (d1 - d0)) * (t[j + 1] - t[j])
    keep = np.concatenate([[True], np.diff(j) > 0]) if j.size else np.zeros(0, bool)
    return Edges(times[keep], low, high, (off, on), lev, glitches + int((~keep).sum()), inverted, (), GLOBAL_LEVELS)


def _risen(v: np.ndarray, rise: np.ndarray, level: np.ndarray, reach: int = 64) -> np.ndarray:
    """Each index of ``rise`` moved on to the first sample at or above ``level`` (one per sample)
    within ``reach`` samples and before the next rise; left where the tooth does not rise that far
    (a weak tooth)."""
    step = np.arange(reach)[None, :]
    nxt = np.concatenate([rise[1:], [v.size]])
    idx = np.minimum(rise[:, None] + step, v.size - 1)
    above = (v[idx] >= level[idx]) & (step < (nxt - rise)[:, None])
    first = np.argmax(above, axis=1)
    return np.where(above.any(axis=1), rise + first, rise)


def _last_crossing(t, v, level, rise, after=None):
    """The time [s] of the last rising crossing of ``level`` (a number or one per sample)
    at or before each sample index ``rise`` (with ``after``: the first crossing at or after
    each sample index ``after`` instead), and the sample index before it; NaN (and −1) where
    there is none."""
    d = v - level
    up = np.flatnonzero((d[:-1] < 0) & (d[1:] >= 0))
    if after is None:
        k = np.searchsorted(up, rise, side="left") - 1
        found = (k >= 0) & (up.size > 0)
    else:
        k = np.searchsorted(up, after, side="left")
        found = (k < up.size) & (up.size > 0)
    j = up[np.clip(k, 0, max(up.size - 1, 0))] if up.size else np.zeros(rise.size, np.int64)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = t[j] - d[j] / (d[j + 1] - d[j]) * (t[j + 1] - t[j])
    return np.where(found, x, np.nan), np.where(found, j, -1)


def _from_the_flank(t, v, rise, times, lev, amp, lo=0.05, hi=0.12):
    """Each edge's crossing of ``lev`` extrapolated along its flank: the line through the
    last crossing of ``lev`` + ``lo`` × the local swing ``amp`` before the rise and the next
    crossing of ``lev`` + ``hi`` × it, back to ``lev``. Where the signal dwells at the crossing level before a tooth
    (a variable-reluctance signal is flat across the gap, centred on its zero crossing),
    noise there makes the last crossing of the level itself land anywhere in the dwell;
    the flank's steep part does not. Falls back to ``times`` where the line is not
    steeper than the dwell."""
    lev_a = np.broadcast_to(lev, v.shape)
    amp_a = np.broadcast_to(amp, v.shape)
    t1, _ = _last_crossing(t, v, lev_a + lo * amp_a, rise)
    t2, _ = _last_crossing(t, v, lev_a + hi * amp_a, rise)
    x = t1 - (t2 - t1) * lo / (hi - lo)
    ok = np.isfinite(x) & (t2 > t1) & (x <= t1)
    return np.where(ok, x, times)


def _envelope(v: np.ndarray, name: str, teeth: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """The running minimum and maximum of ``v`` over its tooth periods and ``teeth`` on
    either side: the periods run from one rising crossing of the signal's median to the
    next (with a small hysteresis), so the window follows the speed — at 300 rpm as at
    3000 — and a gap's period takes the levels of the teeth around it."""
    mid = float(np.median(v))
    h = 0.02 * float(np.percentile(v, 99) - np.percentile(v, 1))
    decisive = (v > mid + h) | (v < mid - h)  # a small hysteresis: noise around the median is no crossing
    idx = np.where(decisive, np.arange(v.size), -1)
    np.maximum.accumulate(idx, out=idx)
    s = v[np.maximum(idx, 0)] > mid + h
    cross = np.flatnonzero(s[1:] & ~s[:-1]) + 1
    if cross.size < 3:
        raise LogError(f"column {name!r}: no pulses found (the signal crosses its median {cross.size} times)")
    starts = np.concatenate([[0], cross])
    lengths = np.diff(np.concatenate([starts, [v.size]]))
    w = 2 * teeth + 1
    hi = running(np.maximum.reduceat(v, starts), w, np.max, "nearest")
    lo = running(np.minimum.reduceat(v, starts), w, np.min, "nearest")
    return np.repeat(lo, lengths), np.repeat(hi, lengths)


def two_level_locally(v: ArrayLike, near: float = 0.15, share: float = 0.75) -> bool:
    """Whether a signal is a pulse train whose levels may drift: at least ``share`` of its
    samples lie within ``near`` of the local swing from the local minimum or maximum (the
    running extremes over each tooth period and two either side). A variable-reluctance
    sensor's sine-like signal spends about half its time between them."""
    v = np.asarray(v, dtype=np.float64)
    try:
        lo, hi = _envelope(v, "v")
    except LogError:
        return False
    amp = hi - lo
    close = (np.abs(v - lo) < near * amp) | (np.abs(v - hi) < near * amp)
    return bool(np.mean(close[amp > 0]) >= share) if np.any(amp > 0) else False


def noise_rms(v: ArrayLike) -> float:
    """The rms of a sampled signal's noise [V], from its sample-to-sample differences (a
    robust spread, so the few samples on tooth flanks do not count): 1.4826 · median
    |Δv| / √2."""
    v = np.asarray(v, dtype=np.float64)
    if v.size > LEVEL_SAMPLES:  # 64 contiguous blocks spread over the record
        n = LEVEL_SAMPLES // 64
        starts = np.linspace(0, v.size - n, 64).astype(np.int64)
        d = np.diff(v[starts[:, None] + np.arange(n)[None, :]], axis=1).ravel()
    else:
        d = np.diff(v)
    return float(1.4826 * np.median(np.abs(d)) / np.sqrt(2.0)) if d.size else 0.0


def find_weak_edges(
    t: ArrayLike,
    v: ArrayLike,
    guess_s: ArrayLike,
    pitch_s: ArrayLike,
    low_v: float,
    high_v: float,
    *,
    inverted: bool = False,
    min_swing: float = 0.05,
    level: float = 0.32,
    reach: float = 0.35,
    noise_v: float | None = None,
    dt_s: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Look for a weak tooth (one that does not reach the Schmitt trigger's levels, or
    whose low before it does not drop below them: two teeth merged) where the wheel's
    pattern says an edge is missing.

    **Arguments:** ``t``, ``v``: the sampled signal [s], [V]; ``guess_s``: where each
    missing edge is expected [s]; ``pitch_s``: the local tooth period there [s];
    ``low_v``, ``high_v``: the signal's levels [V] (:class:`Edges`); ``inverted``: falling
    edges; ``min_swing``: a tooth must swing at least this fraction of ``high_v − low_v``
    [-] and at least 8 × the signal's noise rms (``noise_v`` [V], default
    :func:`noise_rms`); ``level``: the fraction of the tooth's own swing at which its
    edge is placed [-] (as :func:`find_edges`' ``level``); ``reach``: how far from the
    guess the edge may lie [tooth periods]; ``dt_s``: the sampling interval [s] (default: the
    median of ``t``'s, for a caller that probes many times and has it).

    The tooth's rising flank is the steepest rise (over about 1/20 of a tooth period)
    within ``reach`` of the guess; its own levels are the minimum over the half period
    before the flank and the maximum over the half period after it; the edge is the
    crossing of ``level`` between them nearest the flank, interpolated between samples.

    **Returns:** (edge times [s], NaN where no tooth swings enough; each tooth's swing as
    a fraction of ``high_v − low_v`` [-]).
    """
    t = np.asarray(t, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    sign = -1.0 if inverted else 1.0  # the samples gathered are negated, not the whole signal

    def at(i):
        return sign * v[i]

    guess = np.atleast_1d(np.asarray(guess_s, dtype=np.float64))
    pitch = np.broadcast_to(np.asarray(pitch_s, dtype=np.float64), guess.shape)
    full = abs(float(high_v) - float(low_v))
    out = np.full(guess.size, np.nan)
    swing = np.zeros(guess.size)
    if guess.size == 0 or t.size < 4 or not full > 0:
        return out, swing
    noise = noise_rms(v) if noise_v is None else float(noise_v)
    need = max(min_swing * full, 8.0 * noise)
    if dt_s is None:
        dt_s = float(np.median(np.diff(t)))
    for sl in _chunks(guess.size, pitch, dt_s):
        g, p = guess[sl], pitch[sl]
        spp = np.maximum(p / dt_s, 1.0)  # samples per pitch
        s = np.maximum(np.round(spp / 20), 1).astype(np.int64)  # the flank's rise is measured over s samples
        half = np.ceil(0.5 * spp).astype(np.int64)
        rch = np.ceil(reach * spp).astype(np.int64)
        c = np.searchsorted(t, g)
        L = int(np.max(2 * rch + 1))
        k = c[:, None] - rch[:, None] + np.arange(L)[None, :]  # candidate flank starts
        inside = (k <= (c + rch)[:, None]) & (k >= 0) & (k + s[:, None] < v.size)
        kk = np.clip(k, 0, v.size - 1)
        rise = at(np.clip(kk + s[:, None], 0, v.size - 1)) - at(kk)
        rise = np.where(inside, rise, -np.inf)
        best = np.argmax(rise, axis=1)
        f = kk[np.arange(g.size), best]  # the flank starts at sample f, ends at f + s
        ok = np.isfinite(rise[np.arange(g.size), best])
        H = int(np.max(half)) + 1
        off = np.arange(H)[None, :]
        before = np.clip(f[:, None] - off, 0, v.size - 1)
        after = np.clip(f[:, None] + s[:, None] + off, 0, v.size - 1)
        m = off <= half[:, None]
        lo = np.min(np.where(m, at(before), np.inf), axis=1)
        hi = np.max(np.where(m, at(after), -np.inf), axis=1)
        sw = hi - lo
        swing[sl] = np.where(ok, sw / full, 0.0)
        ok &= sw >= need
        lev = lo + level * sw
        # the level's up-crossing nearest the flank: search the flank and s samples either side
        W = int(np.max(3 * s)) + 2
        j = f[:, None] - s[:, None] + np.arange(W)[None, :]
        jm = (j >= 0) & (j + 1 < v.size) & (j <= (f + 2 * s)[:, None])
        jc = np.clip(j, 0, v.size - 2)
        up = jm & (at(jc) < lev[:, None]) & (at(jc + 1) >= lev[:, None])
        dist = np.where(up, np.abs(jc - f[:, None] - s[:, None] // 2), np.iinfo(np.int64).max)
        q = np.argmin(dist, axis=1)
        ok &= up[np.arange(g.size), q]
        jj = jc[np.arange(g.size), q]
        with np.errstate(divide="ignore", invalid="ignore"):  # a flat pair of samples: no crossing there (NaN)
            x = t[jj] + (lev - at(jj)) / (at(jj + 1) - at(jj)) * (t[jj + 1] - t[jj])
        ok &= np.abs(x - g) <= reach * p
        out[sl] = np.where(ok, x, np.nan)
    return out, swing


def _chunks(n: int, pitch: np.ndarray, dt_s: float, budget: int = 4_000_000):
    """Slices of ``n`` guesses whose window matrices stay within ``budget`` elements."""
    L = int(np.max(pitch) / max(dt_s, 1e-300)) + 8
    step = max(1, budget // max(L, 1))
    for a in range(0, n, step):
        yield slice(a, min(a + step, n))
