"""Trigger patterns as lists of edges: any production wheel, crank or cam speed.

A :class:`TriggerPattern` states where the edges of a trigger signal sit over one turn
of its wheel: the angle of every rising and every falling edge [deg of crankshaft], over
360° (a wheel on the crankshaft) or 720° (a wheel on the camshaft, or a crank pattern
that repeats only once a cycle), and which polarity carries the position. The
``N-g1-g2-…`` missing-tooth forms are shorthand for such a list
(:func:`pattern_from_wheel`); the named production patterns are in
:mod:`rotor.logs.catalogue`.

**Angle 0** of a pattern is the angle its published description counts from; a cam
pattern's angles are crankshaft degrees (twice the cam's own).

**Reading edges as a pattern** (:func:`decode_edges`): the time between neighbouring
edges, divided by the angle between them, is the local speed; where the speed changes
smoothly, the ratio of neighbouring periods equals the ratio of their angles. Each
placement of the edges on the pattern (which edge of the pattern the first edge is) is
scored by the log of these ratios against the pattern's, robustly (a residual counts at
most :data:`CLIP`), over windows; stretches that fit one placement are joined across
what breaks them (a glitch, a missed edge, a stop) where the time between them tells how
many edges are missing. A pattern that repeats within its turn (two equal halves) is read
modulo its repetition: the speed is right, the half is not known from this signal.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..errors import LogError
from .digital import digital_edges

__all__ = [
    "TriggerPattern",
    "PatternFit",
    "channel_edges",
    "decode_edges",
    "pattern_from_wheel",
]

GLITCH = 0.02
"""A digital channel's state shorter than this fraction of the median duration of that
state is a glitch [-] (a fraction of a microsecond against teeth of milliseconds); the
short dips some sensors give between two teeth (a few per cent) are kept."""

CLIP = 0.35
"""The most one period's log-ratio residual counts in a placement's score [-] (about a
40 % error in a period ratio): a glitch or a missed edge costs this much, not more."""

FIT_RMS = 0.12
"""A stretch fits a placement where the RMS of its scaled log-ratio residuals is below this [-]."""

BAD_RATIO = 0.33
"""A single scaled log-ratio residual beyond this breaks a stretch [-] (a missed or extra
edge gives about log 2 = 0.69; a production wheel's edges, as captured while cranking,
stray by up to about 0.3 from their description) ..."""

BAD_SPREAD = 2.5
"""... or beyond this many times its window's RMS residual, where that is more [-]: a sensor
whose every period jitters by a fifth (a noisy wheel signal) breaks only at a residual that
no jitter of its own explains."""

SAME_SPACING = 0.02
"""Two edge spacings that differ by less than this fraction of the mean spacing are taken as
one [-] (a pattern whose halves differ by less repeats within its turn)."""

LOOSE_RMS = 0.25
"""... or below this, where the best placement is clearly ahead (:data:`CLEAR_AHEAD`) [-]
(a crank speed that swings within a turn while cranking distorts a sparse pattern's ratios)."""

CLEAR_AHEAD = 0.4
"""... clearly ahead: the best placement's mean square is below this share of the next best's [-] ..."""

SPARSE_DEG = 180.0
CLEAR_AHEAD_SPARSE = 0.6
"""... or of this share for a pattern whose edges are :data:`SPARSE_DEG` or more apart on the
mean [deg] (a cam wheel of four teeth or fewer): each of its periods spans a compression of a
cranking engine, whose speed swings distort every ratio by up to 0.4 in log, and its window
holds a few ratios only [-]."""


@dataclasses.dataclass(frozen=True)
class TriggerPattern:
    """The edges of a trigger wheel over one turn.

    **Fields:** ``name``: the catalogue's name (lower case, e.g. ``"mazda-nb-crank"``) or a
    shorthand (``"36-2-1"``); ``title``: the pattern in words (engine, maker); ``period_deg``:
    360 (crank speed) or 720 (cam speed) [deg of crankshaft]; ``rising_deg``,
    ``falling_deg``: the angles of the rising and of the falling edges in
    ``[0, period_deg)`` [deg] (either may be empty where the description gives only one);
    ``read``: the polarity that carries the position, ``"rising"``, ``"falling"`` or
    ``"both"`` (tooth widths carry it); ``kind``: ``"crank"`` or ``"cam"`` (where the sensor
    sits); ``source``: the published description (author and title); ``aliases``: other
    names (e.g. an ECU's trigger type).
    """

    name: str
    title: str
    period_deg: float
    rising_deg: tuple[float, ...] = ()
    falling_deg: tuple[float, ...] = ()
    read: str = "rising"
    kind: str = "crank"
    source: str = ""
    aliases: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.period_deg not in (360.0, 720.0):
            raise LogError(f"pattern {self.name}: period_deg = {self.period_deg!r}; 360 (crank) or 720 (cam)")
        if self.read not in ("rising", "falling", "both"):
            raise LogError(f"pattern {self.name}: read = {self.read!r}; 'rising', 'falling' or 'both'")
        if self.kind not in ("crank", "cam"):
            raise LogError(f"pattern {self.name}: kind = {self.kind!r}; 'crank' or 'cam'")
        for what in ("rising_deg", "falling_deg"):
            a = tuple(float(x) % self.period_deg for x in getattr(self, what))
            if len(set(a)) != len(a):
                raise LogError(f"pattern {self.name}: two {what} edges at one angle")
            object.__setattr__(self, what, tuple(sorted(a)))
        if len(self.angles_deg()) < 1:
            raise LogError(f"pattern {self.name}: no {self.read} edges")
        if self.read == "both" and (len(self.rising_deg) != len(self.falling_deg)):
            raise LogError(f"pattern {self.name}: rising and falling edges must alternate to be read together")

    def angles_deg(self, polarity: str | None = None) -> np.ndarray:
        """The angles [deg] of the edges of ``polarity`` (default: the one that carries the
        position; ``"both"``: rising and falling together), ascending."""
        polarity = polarity or self.read
        if polarity == "rising":
            return np.asarray(self.rising_deg)
        if polarity == "falling":
            return np.asarray(self.falling_deg)
        return np.sort(np.asarray(self.rising_deg + self.falling_deg))

    def kinds(self, polarity: str | None = None) -> np.ndarray:
        """Each edge's kind, aligned with :meth:`angles_deg`: 1 rising, 0 falling."""
        polarity = polarity or self.read
        if polarity != "both":
            return np.full(self.angles_deg(polarity).size, 1 if polarity == "rising" else 0, dtype=np.int8)
        a = np.concatenate([self.rising_deg, self.falling_deg])
        k = np.concatenate([np.ones(len(self.rising_deg), np.int8), np.zeros(len(self.falling_deg), np.int8)])
        return k[np.argsort(a, kind="stable")]

    @property
    def evenly_spaced(self) -> bool:
        """Whether timing alone cannot tell this pattern from others: its edges that carry
        the position are evenly spaced, or (read on both edges) one tooth repeated round the
        turn, whose only mark is its width (any pulse train of that duty cycle fits, at any
        tooth count)."""
        k, r = self.edges_per_turn, self.repeats()
        return r == k or (self.read == "both" and k // r <= 2)

    def intervals_deg(self, polarity: str | None = None) -> np.ndarray:
        """The angle from each edge to the next [deg] (the last to the first of the next turn)."""
        a = self.angles_deg(polarity)
        return np.diff(np.concatenate([a, [a[0] + self.period_deg]]))

    def repeats(self, polarity: str | None = None) -> int:
        """How many times the edge spacing repeats within one turn (1: every edge is told
        apart; 2: two equal halves, e.g. a wheel with two equal gaps 180° apart). Spacings
        within :data:`SAME_SPACING` of the mean interval are the same: timing cannot tell them
        apart."""
        d = self.intervals_deg(polarity)
        k = d.size
        tol = SAME_SPACING * float(np.mean(d))
        for m in range(k, 1, -1):
            if k % m == 0 and np.allclose(d, np.roll(d, k // m), atol=tol):
                return m
        return 1

    @property
    def edges_per_turn(self) -> int:
        return int(self.angles_deg().size)

    def describe(self) -> str:
        """The pattern in one line: its edges, turn and sync."""
        n = self.edges_per_turn
        speed = "cam speed (720°)" if self.period_deg == 720 else "crank speed (360°)"
        rep = self.repeats()
        sym = f", repeats {rep}× a turn" if rep > 1 else ""
        return f"{self.title}: {n} {self.read} edges a turn, {speed}{sym}"

    def to_json_dict(self) -> dict:
        return {
            "name": self.name,
            "title": self.title,
            "kind": self.kind,
            "period_deg": self.period_deg,
            "read": self.read,
            "rising_deg": list(self.rising_deg),
            "falling_deg": list(self.falling_deg),
            "repeats": self.repeats(),
            "source": self.source or None,
            "aliases": list(self.aliases),
        }


def pattern_from_wheel(
    teeth: int, gaps: Sequence[int] = (), layout: Sequence[int] | None = None, *, duty: float = 0.5
) -> TriggerPattern:
    """The edge list of an ``N-g1-g2-…`` wheel: ``teeth`` positions at 360/N°, the gaps'
    missing teeth (``gaps``) after runs of ``layout`` teeth (default: the teeth spread as
    evenly as the gaps allow, gap 1 followed by the most). Rising edges at the positions,
    falling edges ``duty`` of a pitch later [-]."""
    teeth = int(teeth)
    gaps = tuple(int(g) for g in gaps)
    if teeth < 1 or any(g < 1 for g in gaps):
        raise LogError(f"wheel {teeth}{''.join(f'-{g}' for g in gaps)}: need teeth ≥ 1 and gaps ≥ 1")
    present = teeth - sum(gaps)
    if gaps and layout is None:
        base, extra = divmod(present, len(gaps))
        layout = tuple(base + (1 if i < extra else 0) for i in range(len(gaps)))
    pitch = 360.0 / teeth
    pos: list[int] = []
    if gaps:
        assert layout is not None
        if sum(layout) != present or len(layout) != len(gaps):
            raise LogError(f"wheel {teeth}{''.join(f'-{g}' for g in gaps)}: layout {tuple(layout)} does not fit")
        p = 0
        for run, gap in zip(layout, gaps[1:] + gaps[:1]):
            pos.extend(range(p, p + run))
            p += run + gap
    else:
        pos = list(range(teeth))
    rising = tuple(pitch * np.asarray(pos))
    falling = tuple((pitch * (np.asarray(pos) + duty)) % 360.0)
    spec = f"{teeth}" + "".join(f"-{g}" for g in gaps)
    return TriggerPattern(spec, f"{spec} wheel", 360.0, rising, falling, "rising", "crank", "")


@dataclasses.dataclass(frozen=True)
class PatternFit:
    """Edges read as a :class:`TriggerPattern`.

    **Fields:** ``pattern``, ``polarity`` (of the edges read); ``t`` [s]: the edges kept;
    ``angle_rad``: each one's crankshaft angle [rad], counted from the pattern's angle 0
    of the turn before the first kept edge (continuous across the turns); ``index``: each
    edge's place in the pattern (0 … edges a turn − 1); ``rms``: the RMS log-ratio
    residual of the kept edges [-]; ``kept``: the fraction of the edges kept [-];
    ``dropped``: time spans [s] whose edges fit no placement (a stop, an irregular
    stretch); ``joined``: how many breaks were bridged by the time between them;
    ``repeats``: the pattern's repetition within a turn (its angle is known modulo
    ``period_deg / repeats``); ``evidence``: how much better the pattern explains the kept
    edges' period ratios than evenly spaced edges do, per edge [-] (the mean clipped
    squared log-ratio of evenly spaced edges minus the pattern's: 0 for an evenly spaced
    pattern, which any regular signal fits).
    """

    pattern: TriggerPattern
    polarity: str
    t: np.ndarray
    angle_rad: np.ndarray
    index: np.ndarray
    rms: float
    kept: float
    dropped: tuple[tuple[float, float], ...]
    joined: int
    repeats: int
    evidence: float = 0.0

    @property
    def turns(self) -> float:
        """Pattern turns the kept edges span [-]."""
        return float((self.angle_rad[-1] - self.angle_rad[0]) / math.radians(self.pattern.period_deg))

    @property
    def revolutions(self) -> float:
        """Crankshaft revolutions the kept edges span [-]."""
        return float((self.angle_rad[-1] - self.angle_rad[0]) / (2 * math.pi))

    def rpm_per_turn(self) -> tuple[np.ndarray, np.ndarray]:
        """The mean crankshaft speed [rev/min] over each whole turn of the pattern that ends
        at a kept edge and starts at one: (end times [s], rpm)."""
        period = math.radians(self.pattern.period_deg)
        a = self.angle_rad
        j = np.clip(np.searchsorted(a, a - period - 1e-6), 0, a.size - 1)
        ok = np.abs(a[j] - (a - period)) < 1e-6
        end = np.flatnonzero(ok)
        dt = self.t[end] - self.t[j[ok]]
        return self.t[end], 60.0 * (period / (2 * math.pi)) / dt

    def tooth_times(self, teeth: int = 60, missing: int = 2) -> np.ndarray:
        """The times [s] the teeth of an ``teeth``-``missing`` wheel would pass, its first tooth
        after the gap at the pattern's angle 0 (a cam pattern's: of the turn of two
        revolutions), the angle between two kept edges taken as linear in time: the pattern as
        a missing-tooth wheel's tooth times, within the kept edges (for a reader that follows
        such wheels, e.g. the streaming monitor)."""
        pitch = 2 * math.pi / teeth
        a = self.angle_rad
        k = np.arange(math.ceil(a[0] / pitch - 1e-9), math.floor(a[-1] / pitch + 1e-9) + 1)
        k = k[np.mod(k, teeth) < teeth - missing]
        return np.interp(k * pitch, a, self.t)


def channel_edges(
    t: ArrayLike, v: ArrayLike, polarity: str, *, name: str = "encoder_d"
) -> tuple[np.ndarray, np.ndarray]:
    """The edges of a digital (0/1) channel given at its transitions (``t`` [s], ``v`` its
    level after each row): ``"rising"``, ``"falling"`` or ``"both"``, glitches
    (:data:`GLITCH`) removed (:func:`rotor.logs.digital.digital_edges`): (times [s], kind
    of each: 1 rising, 0 falling)."""
    if polarity == "both":
        r = digital_edges(t, v, edge="rising", glitch=GLITCH, name=name).times
        f = digital_edges(t, v, edge="falling", glitch=GLITCH, name=name).times
        times = np.concatenate([r, f])
        kinds = np.concatenate([np.ones(r.size, np.int8), np.zeros(f.size, np.int8)])
        order = np.argsort(times, kind="stable")
        return times[order], kinds[order]
    times = digital_edges(t, v, edge=polarity, glitch=GLITCH, name=name).times
    return times, np.full(times.size, 1 if polarity == "rising" else 0, dtype=np.int8)


def _log_ratios(dt: np.ndarray) -> np.ndarray:
    return np.log(dt[1:] / dt[:-1])


def _placement_costs(d: np.ndarray, ia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(log-ratios, K) robust costs of each observed log-ratio ``d[i]`` (period i+1 over
    period i) against the pattern's, with period 0 placed at pattern interval s: the
    residual scaled by the shorter of the two intervals over the median interval, at most 1
    (an edge displaced by some degrees moves a short interval's log more than a long one's),
    squared, at most :data:`CLIP` ²; and the scaled residuals' magnitudes, unclipped."""
    K = ia.size
    la = np.log(ia)
    rho = la - np.roll(la, 1)  # rho[j] = log(a_j / a_{j-1})
    scale = np.minimum(np.minimum(ia, np.roll(ia, 1)) / np.median(ia), 1.0)
    i = np.arange(d.size)[:, None] + 1
    j = (np.arange(K)[None, :] + i) % K
    r = np.abs((d[:, None] - rho[j]) * scale[j])
    return np.minimum(r * r, CLIP * CLIP), r


def _runs(good: np.ndarray, best: np.ndarray, bad: np.ndarray) -> list[tuple[int, int, int]]:
    """Runs (first log-ratio, last + 1, placement) of neighbouring good windows of one
    placement, split where a single log-ratio is bad under it."""
    runs = []
    n = good.size
    i = 0
    while i < n:
        if not good[i] or bad[i, best[i]]:
            i += 1
            continue
        j = i
        while j + 1 < n and good[j + 1] and best[j + 1] == best[i] and not bad[j + 1, best[i]]:
            j += 1
        runs.append((i, j + 1, int(best[i])))
        i = j + 1
    return runs


def decode_edges(
    times: ArrayLike,
    pattern: TriggerPattern,
    polarity: str | None = None,
    *,
    kinds: ArrayLike | None = None,
    min_turns: float = 1.0,
) -> PatternFit:
    """Read edge times ``times`` [s] (one polarity, or both where ``polarity="both"``) as
    ``pattern``: each edge's place in the pattern and its crankshaft angle.

    ``kinds``: with ``polarity="both"``, each edge's kind (1 rising, 0 falling; an inverted
    signal's kinds flipped): a placement must put rising edges on the pattern's rising ones.

    Stretches of edges that follow one placement (log-ratio RMS below :data:`FIT_RMS` over
    a window of two turns, or below :data:`LOOSE_RMS` where that placement is clearly ahead
    of the next, no single ratio off by more than :data:`BAD_RATIO` or :data:`BAD_SPREAD`
    times the window's RMS) are kept; they are
    joined where the time between them, at the speed on either side, spans a whole number
    of pattern intervals within a quarter of the mean interval. Where a break cannot be
    bridged, the longest joined stretch is kept and the rest reported as dropped.

    **Raises** :class:`LogError` where no stretch of at least ``min_turns`` turns fits.
    """
    polarity = polarity or pattern.read
    t = np.asarray(times, dtype=np.float64)
    a = pattern.angles_deg(polarity)
    K = int(a.size)
    what = f"the {pattern.name} pattern ({polarity} edges)"
    if K == 0:
        raise LogError(f"{what} states no {polarity} edges")
    need = max(int(math.ceil(min_turns * K)) + 2, 4)
    if t.size < need:
        raise LogError(f"{t.size} edges; {what} needs {need} or more ({min_turns:g} turn)")
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise LogError(f"edge times not increasing at t = {t[1:][dt <= 0][0]:.6f} s")
    period = pattern.period_deg
    ia = np.diff(np.concatenate([a, [a[0] + period]]))
    d = _log_ratios(dt)
    reps = pattern.repeats(polarity)
    C, R = _placement_costs(d, ia)  # C[i, s]: log-ratio i of the log against placement s
    if kinds is not None:
        ek = np.asarray(kinds, dtype=np.int8)
        if ek.shape != t.shape:
            raise LogError(f"kinds: {ek.size} for {t.size} edges")
        pk = pattern.kinds(polarity)
        j = (np.arange(K)[None, :] + np.arange(d.size)[:, None] + 1) % K
        wrong = pk[j] != ek[1:-1, None]
        C = np.where(wrong, CLIP * CLIP, C)
        R = np.where(wrong, np.inf, R)
    W = max(2 * K, 8)
    n = d.size
    cs = np.vstack([np.zeros((1, K)), np.cumsum(C, axis=0)])
    lo = np.clip(np.arange(n) - W // 2, 0, max(n - W, 0))
    hi = np.minimum(lo + W, n)
    win = (cs[hi] - cs[lo]) / (hi - lo)[:, None]
    bad = R > np.maximum(BAD_RATIO, BAD_SPREAD * np.sqrt(win))
    unit_k = K // reps
    if reps > 1:  # equal placements: take the first of each class
        win = win[:, :unit_k]
        bad = bad[:, :unit_k]
    order = np.argsort(win, axis=1)
    best = order[:, 0]
    b = win[np.arange(n), best]
    # a window fits where its best placement is close, or clearly ahead of the next best
    good = np.sqrt(b) < FIT_RMS
    if win.shape[1] > 1:
        second = win[np.arange(n), order[:, 1]]
        good |= (np.sqrt(b) < LOOSE_RMS) & (
            b < (CLEAR_AHEAD_SPARSE if period / K >= SPARSE_DEG else CLEAR_AHEAD) * second
        )
    min_edges = max(K // 2, 4)
    pieces = [(r0, r1 + 2, s) for r0, r1, s in _runs(good, best, bad) if r1 - r0 + 2 >= min_edges]
    if not pieces:
        raise LogError(f"no stretch of the edges fits {what}")
    unit = period / reps
    mean_int = period / K
    segments: list[list[tuple[np.ndarray, np.ndarray, np.ndarray]]] = []
    joined = 0
    for e0, e1, s in pieces:
        idx = (s + np.arange(e0, e1)) % K  # period e runs from pattern edge (s + e) to the next
        tt = t[e0:e1]
        local = np.concatenate([[0.0], np.cumsum(ia[idx[:-1]])])
        if segments:
            pt, pang, pidx = segments[-1][-1]
            if tt[0] <= pt[-1]:  # neighbouring pieces share an edge
                keep = tt > pt[-1]
                if keep.sum() < 2:
                    continue
                tt, idx = tt[keep], idx[keep]
                local = np.concatenate([[0.0], np.cumsum(ia[idx[:-1]])])
            k0 = max(pt.size - K - 1, 0)
            w_prev = (pang[-1] - pang[k0]) / (pt[-1] - pt[k0])
            k1 = min(K, tt.size - 1)
            w_next = (local[k1] - local[0]) / (tt[k1] - tt[0])
            est = (tt[0] - pt[-1]) * 0.5 * (w_prev + w_next)
            base = (a[idx[0]] - a[pidx[-1]]) % unit
            m = np.round((est - base) / unit)
            span = base + m * unit
            if span > 0 and abs(span - est) < 0.25 * mean_int:
                segments[-1].append((tt, pang[-1] + span + local, idx))
                joined += 1
                continue
        segments.append([(tt, a[idx[0]] + local, idx)])

    def extent(seg):
        return seg[-1][1][-1] - seg[0][1][0]

    seg = max(segments, key=extent)
    tk = np.concatenate([p[0] for p in seg])
    ang_deg = np.concatenate([p[1] for p in seg])
    idx = np.concatenate([p[2] for p in seg])
    dropped: list[tuple[float, float]] = []
    if tk[0] > t[0]:
        dropped.append((float(t[0]), float(tk[0])))
    if tk[-1] < t[-1]:
        dropped.append((float(tk[-1]), float(t[-1])))
    w = np.diff(ang_deg) / np.diff(tk)
    res = np.log(w[1:] / w[:-1]) if w.size > 2 else np.zeros(1)
    rms = float(np.sqrt(np.mean(np.minimum(res * res, CLIP * CLIP))))
    d_kept = _log_ratios(np.diff(tk))
    null = float(np.mean(np.minimum(d_kept * d_kept, CLIP * CLIP))) if d_kept.size else 0.0
    fit = PatternFit(
        pattern=pattern,
        polarity=polarity,
        t=tk,
        angle_rad=np.deg2rad(ang_deg),
        index=idx.astype(np.int64),
        rms=rms,
        kept=float(tk.size / t.size),
        dropped=tuple(dropped),
        joined=joined,
        repeats=reps,
        evidence=null - rms * rms,
    )
    if fit.turns < min_turns:
        raise LogError(f"{what}: the edges that fit span {fit.turns:.2f} turns; need {min_turns:g}")
    return fit
