"""Which wheel a signal really has, and how well a wheel fits its edges.

**Counting.** The periods between edges are divided by the local tooth period
(:func:`rotor.logs.pattern.pitches`) and rounded: a regular tooth spans one pitch, a gap of
g missing teeth g + 1. The edge next to a gap is often displaced (a weak, early or late
tooth: the magnetic field bends round the gap's edge), which makes the gap look longer or
shorter and its neighbour shorter or longer by the same amount. Both errors cancel in the
sum of the gap's period and its two neighbours: a gap's size is counted from that sum, in
units of the tooth period outside it (the mean of the periods two before and two after).

**Scoring.** Each candidate wheel (the counted one, the one counted without that
correction, and the standard patterns :data:`STANDARD_WHEELS` with the same edges per
revolution) is placed on the edges (:func:`rotor.logs.pattern.locate_teeth`; with repairs
where the pattern proves them) and scored by (1) the edges it had to infer, against a
budget of one per :data:`REVOLUTIONS_PER_INFERRED_EDGE` revolutions (at least one in the
record), and (2) its **gap misfit**: the rms, over the gaps, of the relative difference
between each gap's window (the gap's period and its two neighbours) and the pitches the
wheel says that window spans. A 60-2 wheel read as 61-3 misfits by about 17 %; the right
wheel by the speed's change over a few teeth (under 2 % on the bench recordings).

**Refusing.** When the runner-up's misfit is within :data:`MARGIN` × the best's (or both are
below :data:`MISFIT_FLOOR`, where noise cannot tell them apart), the signal does not tell
the wheels apart: a standard pattern is preferred over another (a wheel whose pattern
repeats within a revolution reads as its repeating part: 36-2-2-2 as 12-2), and between
two standard patterns (or two others) :func:`find_wheel` refuses, naming both.
"""

from __future__ import annotations

import dataclasses
import enum
from collections import Counter
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..errors import LogError
from .catalogue import catalogue_layout
from .pattern import END_REVS, locate_teeth, pitches, place, remove_extra_edges
from .wheel import Repair, ToothTrack, Wheel, parse_wheel
from .windows import running

__all__ = [
    "FitStatus",
    "MARGIN",
    "MISFIT_FLOOR",
    "REVOLUTIONS_PER_INFERRED_EDGE",
    "STANDARD_WHEELS",
    "WheelFit",
    "candidates",
    "counted_wheels",
    "evidence",
    "rank",
    "find_wheel",
    "fit_wheel",
    "gap_misfit",
    "inferred_budget",
    "period_jitter",
]

STANDARD_WHEELS = ("60-2", "60-1", "36-1", "36-2", "36-2-1", "36-2-1-1", "36-2-2-2", "24-1", "12-1")
MARGIN = 3.0  # the best wheel's gap misfit must be this many times below the runner-up's
MISFIT_FLOOR = 0.03  # below this relative misfit, two wheels fit alike whatever their ratio
REVOLUTIONS_PER_INFERRED_EDGE = 20  # a wheel may need one inferred edge per this many revolutions
MAX_GAP_MISFIT = 0.25
"""The largest gap misfit (:func:`gap_misfit`) of a wheel found from the log [-]: a wheel whose
gaps are further off the edges is not this signal's, whatever else fits."""
MIN_REVOLUTIONS = 2
"""The fewest complete revolutions on which a wheel is found from the log [-]."""
MIN_COUNTED_POSITIONS = 8
"""A wheel counted from the log (not a standard pattern) has at least this many positions [-]:
a handful of uneven edges a turn is some other pattern's, not a wheel of three or five teeth."""


class FitStatus(enum.Enum):
    """How a wheel fits a signal's edges (a typed state: decisions test this, never a message)."""

    FITS = "fits as found"
    REPAIRED = "fits with repairs within the budget"
    OVER_BUDGET = "needs more inferred edges than the budget allows"
    NO_FIT = "does not fit"
    NO_EDGES = "no edges found"

    @property
    def ok(self) -> bool:
        return self in (FitStatus.FITS, FitStatus.REPAIRED)


@dataclasses.dataclass(frozen=True, eq=False)
class WheelFit:
    """One wheel tried on one set of edges: the evidence for choosing it or not.

    **Attributes:** ``spec``: the wheel; ``edge``: ``"rising"``/``"falling"`` (``None``
    for tooth times); ``status``: :class:`FitStatus`; ``revolutions``: complete
    revolutions placed; ``inferred``: edges inferred from the pattern; ``removed``: extra
    edges removed; ``interior``: of those, the ones away from the first and last revolution (an
    engine starting or stopping makes edges no pattern proves); ``found``: weak edges found in the signal where the pattern has a
    tooth; ``signature``: the teeth (0 = the first after gap 1) the signal lacks in most
    revolutions, a property of the wheel and sensor (:data:`SIGNATURE_SHARE`): their edges,
    placed from the pattern, are not counted as inferred; ``budget``: inferred edges allowed; ``gap_misfit`` [-]: rms relative misfit of
    the gap windows; ``jitter`` [-]: rms relative change of the tooth period from one
    regular tooth to the next; ``reason``: in words, why it does not fit (empty if it
    does); ``track``: the placed edges (``None`` if it does not fit).
    """

    spec: str
    edge: str | None
    status: FitStatus
    revolutions: int = 0
    inferred: int = 0
    removed: int = 0
    found: int = 0
    budget: int = 0
    gap_misfit: float = float("nan")
    jitter: float = float("nan")
    reason: str = ""
    track: ToothTrack | None = None
    standard: bool = False
    interior: int = 0
    signature: tuple = ()

    @property
    def repairs(self) -> int:
        """Edges guessed rather than measured: inferred and removed."""
        return self.inferred + self.removed

    def describe(self) -> str:
        """One line: the wheel, the edge, how it fits."""
        e = f" ({self.edge} edges)" if self.edge else ""
        if not self.status.ok:
            return f"{self.spec}{e}: {self.status.value}" + (f" — {self.reason}" if self.reason else "")
        rep = f", {self.inferred} inferred / {self.removed} removed / {self.found} weak found" if self.repairs else ""
        return (
            f"{self.spec}{e}: {self.revolutions} revolutions, gap misfit {100 * self.gap_misfit:.1f} %, "
            f"jitter {100 * self.jitter:.2f} %{rep}"
        )

    def to_json_dict(self) -> dict:
        def num(x):
            return float(x) if np.isfinite(x) else None

        return {
            "wheel": self.spec,
            "edge": self.edge,
            "status": self.status.name.lower(),
            "standard": self.standard,
            "revolutions": int(self.revolutions),
            "inferred_edges": int(self.inferred),
            "removed_edges": int(self.removed),
            "weak_edges_found": int(self.found),
            "inferred_budget": int(self.budget),
            "gap_misfit": num(self.gap_misfit),
            "jitter": num(self.jitter),
            "reason": self.reason or None,
            "signature": list(self.signature),
        }


def inferred_budget(revolutions: int) -> int:
    """Inferred edges a wheel may need in ``revolutions`` revolutions: one per
    :data:`REVOLUTIONS_PER_INFERRED_EDGE`, and at least one (the odd missed tooth)."""
    return max(1, int(revolutions) // REVOLUTIONS_PER_INFERRED_EDGE)


def _unit_periods(track: ToothTrack) -> tuple[np.ndarray, np.ndarray]:
    """(periods [s], pitches each spans [-]) of a placed track."""
    w = track.wheel
    pitch = 2 * np.pi / w.teeth
    k = np.rint(np.diff(track.nominal_angle) / pitch).astype(np.int64)
    return np.diff(track.t), k


def gap_misfit(track: ToothTrack) -> float:
    """The rms relative misfit [-] of the gap windows of ``track``: each gap's period plus
    its two neighbours against the pitches the wheel says they span, in units of the
    tooth period outside the window (the mean of the periods two before and two after, where
    those are single pitches; else the median single-pitch period near it)."""
    dt, k = _unit_periods(track)
    n = dt.size
    g = np.flatnonzero(k > 1)
    g = g[(g >= 2) & (g <= n - 3)]
    if g.size == 0:
        return 0.0
    u = dt / np.maximum(k, 1)
    single = k == 1
    a, b = g - 2, g + 2
    ok = single[a] & single[b]
    unit = np.where(ok, 0.5 * (u[a] + u[b]), np.nan)
    if not np.all(ok):
        med = running(np.where(single, u, np.median(u[single]) if single.any() else 1.0), 9, np.median, "nearest")
        unit = np.where(ok, unit, med[g])
    span = dt[g - 1] + dt[g] + dt[g + 1]
    want = (k[g - 1] + k[g] + k[g + 1]) * unit
    e = span / want - 1.0
    return float(np.sqrt(np.mean(e**2)))


def period_jitter(track: ToothTrack) -> float:
    """The rms relative change [-] of the tooth period from one single-pitch period to the
    next (a timer's or a flank's noise, and edges displaced near the gaps), away from the first
    and last revolution where there are five or more."""
    dt, k = _unit_periods(track)
    both = (k[1:] == 1) & (k[:-1] == 1)
    r0, r1 = int(np.min(track.rev)), int(np.max(track.rev))
    if r1 - r0 >= 4:  # away from the first and last revolution (an engine starting or stopping)
        both &= (track.rev[1:-1] > r0) & (track.rev[1:-1] < r1)
    if not np.any(both):
        return float("nan")
    r = np.diff(dt)[both] / (0.5 * (dt[1:] + dt[:-1])[both])
    return float(np.sqrt(np.mean(r**2)))


def fit_wheel(
    times: ArrayLike,
    wheel: str | Wheel,
    *,
    edge: str | None = None,
    index_times: ArrayLike | None = None,
    probe: Callable | None = None,
    repair: bool = True,
) -> WheelFit:
    """Place the edge ``times`` [s] on ``wheel`` and say how it fits (:class:`WheelFit`).

    The edges are placed as they are; where that fails and ``repair`` is set, with the
    repairs the pattern proves (:func:`rotor.logs.pattern.locate_teeth`; ``probe`` looks
    for a weak tooth in the signal). A wheel that needs more inferred edges than
    :func:`inferred_budget` allows is :attr:`FitStatus.OVER_BUDGET`: repairs are for the
    odd glitch or missed tooth, not for making a wrong wheel fit.
    """
    w = parse_wheel(wheel)
    std = w.spec in STANDARD_WHEELS
    try:
        track = locate_teeth(times, w, index_times=index_times)
    except LogError as e:
        if not repair or w.needs_index:
            return WheelFit(w.spec, edge, FitStatus.NO_FIT, reason=str(e), standard=std)
        try:
            track = locate_teeth(times, w, index_times=index_times, repair=True, probe=probe)
        except LogError as e2:
            return WheelFit(w.spec, edge, FitStatus.NO_FIT, reason=str(e2), standard=std)
    signature = _signature(track)
    track = _ends_dropped(np.asarray(times, dtype=np.float64), track, w, index_times, probe, signature)
    std = std and catalogue_layout(track.wheel)  # a standard spec with its gaps elsewhere is another wheel
    kinds = Counter(r.kind for r in track.repairs)
    inferred = kinds.get("missed edge inferred", 0) - _at_teeth(track, signature)
    removed = kinds.get("extra edge removed", 0)
    found = kinds.get("missed edge found", 0)
    revs = max(track.revolutions, 0)
    budget = inferred_budget(revs)
    first, last = int(np.min(track.rev)), int(np.max(track.rev))
    interior = sum(
        r.kind in ("missed edge inferred", "extra edge removed") and first < (r.revolution or 0) < last
        for r in track.repairs
    )
    status = FitStatus.FITS if not track.repairs else FitStatus.REPAIRED
    reason = ""
    if inferred > budget:
        status = FitStatus.OVER_BUDGET
        reason = (
            f"{inferred} edges inferred in {revs} revolutions (at most {budget}: one per "
            f"{REVOLUTIONS_PER_INFERRED_EDGE} revolutions)"
        )
    return WheelFit(
        w.spec,
        edge,
        status,
        revs,
        inferred,
        removed,
        found,
        budget,
        gap_misfit(track),
        period_jitter(track),
        reason,
        track if status.ok else None,
        std,
        interior,
        signature,
    )


SIGNATURE_SHARE = 0.8
"""A tooth whose edge had to be inferred in this share of the revolutions or more (and in
:data:`SIGNATURE_REVOLUTIONS` or more) is a signature of the wheel and its sensor [-]: missing
at the same place in most revolutions, it is no repair of random faults."""
SIGNATURE_REVOLUTIONS = 3


def _inferred_teeth(track: ToothTrack) -> np.ndarray:
    """The teeth (0 = the first after gap 1) whose edges ``track`` inferred from the pattern."""
    inferred = [r.time_s for r in track.repairs if r.kind == "missed edge inferred"]
    if not inferred:
        return np.zeros(0, np.int64)
    at = np.clip(np.searchsorted(track.t, inferred), 0, track.t.size - 1)
    exact = np.isclose(track.t[at], inferred, rtol=0.0, atol=1e-12)
    return np.asarray(track.tooth[at[exact]], dtype=np.int64)


def _at_teeth(track: ToothTrack, teeth: tuple[int, ...]) -> int:
    """The edges inferred at ``teeth``."""
    return int(np.isin(_inferred_teeth(track), teeth).sum()) if teeth else 0


def _signature(track: ToothTrack) -> tuple[int, ...]:
    """The teeth (0 = the first after gap 1) that are a signature of the wheel and sensor
    (:data:`SIGNATURE_SHARE`), where each lies next to a gap: the signal lacks them in most
    revolutions, so their edges, placed from the pattern, are no repairs of random faults. A
    tooth lacking away from the gaps is a gap of another wheel, not a signature."""
    inferred = _inferred_teeth(track)
    if inferred.size < SIGNATURE_REVOLUTIONS:
        return ()
    teeth = Counter(int(k) for k in inferred)
    need = max(SIGNATURE_REVOLUTIONS, SIGNATURE_SHARE * max(track.revolutions, 1))
    lacking = sorted(k for k, c in teeth.items() if c >= need)
    w = track.wheel
    nominal = w.tooth_angles_rad
    pitch = w.pitch_rad
    n = nominal.size
    # next to a gap: the angle to the tooth before or after is more than a pitch
    beside = {
        k
        for k in lacking
        if (nominal[k] - nominal[k - 1]) % (2 * np.pi) > 1.5 * pitch
        or (nominal[(k + 1) % n] - nominal[k]) % (2 * np.pi) > 1.5 * pitch
    }
    return tuple(lacking) if lacking and set(lacking) <= beside else ()


def _ends_dropped(t: np.ndarray, track: ToothTrack, w: Wheel, index_times, probe, signature=()) -> ToothTrack:
    """``track`` with the edges of its first and last :data:`rotor.logs.pattern.END_REVS`
    revolutions dropped from the first (last) edge that had to be inferred there: a starter
    engaging, an engine coming to a stop (its speed changing by half within a tooth) make periods
    no pattern proves, and an edge guessed there is no measurement. Unchanged where none is.
    The edges inferred at the teeth of the wheel's ``signature`` (:func:`_signature`) do not count."""
    inferred = np.array([r.time_s for r in track.repairs if r.kind == "missed edge inferred"])
    if signature and inferred.size:
        at = np.clip(np.searchsorted(track.t, inferred), 0, track.t.size - 1)
        inferred = inferred[~np.isin(track.tooth[at], signature)]
    E = w.edges_per_rev
    if inferred.size == 0 or t.size < 2 * END_REVS * E + E + 3:
        return track
    head = t[END_REVS * E]
    tail = t[t.size - 1 - END_REVS * E]
    lo = inferred[inferred <= head].max() if np.any(inferred <= head) else -np.inf
    hi = inferred[inferred >= tail].min() if np.any(inferred >= tail) else np.inf
    if not (np.isfinite(lo) or np.isfinite(hi)):
        return track
    keep = (t > lo) & (t < hi)
    try:
        cut = locate_teeth(t[keep], w, index_times=index_times, repair=True, probe=probe)
    except LogError:
        return track
    dropped = [
        Repair(
            "edge dropped",
            float(x),
            None,
            1.0,
            f"one of {int((~keep).sum())} edges at the {'start' if x <= lo else 'end'} of the log where the pattern "
            f"needed an edge guessed (a starter engaging, the engine stopping?)",
        )
        for x in t[~keep]
    ]
    return dataclasses.replace(cut, repairs=tuple(place(list(cut.repairs) + dropped, cut.t, cut.rev)))


# ---------------------------------------------------------------------- counting
def _gap_pitches(dt: np.ndarray, p: np.ndarray, n: np.ndarray) -> np.ndarray:
    """The pitches each long period spans, counted from its window (itself and its two
    neighbours, where those are single pitches) in units of the periods just outside it: a
    displaced edge next to the gap cancels."""
    out = n.copy()
    L = np.flatnonzero(n >= 2)
    for i in L:
        if i < 2 or i > dt.size - 3:
            continue
        lo = i - 1 if n[i - 1] == 1 else i
        hi = i + 1 if n[i + 1] == 1 else i
        a, b = lo - 1, hi + 1
        if n[a] != 1 or n[b] != 1:
            continue
        unit = 0.5 * (dt[a] + dt[b])
        total = float(np.sum(dt[lo : hi + 1]) / unit)
        out[i] = max(int(round(total - (i - lo) - (hi - i))), 2)
    return out


def _pattern(n: np.ndarray) -> Wheel:
    """The wheel whose gaps repeat in the periods ``n`` [pitches]; LogError if none does."""
    L = np.flatnonzero(n >= 2)
    if L.size < 3:
        raise LogError(
            f"{L.size} gap(s) in {n.size + 1} tooth edges: no repeating gap found (a wheel without a gap needs its "
            f"tooth count and an index column, e.g. wheel='60' with index_v)"
        )
    s = n[L] - 1
    run = np.diff(L)
    s = s[:-1]
    C = np.concatenate([[0], np.cumsum(n)])
    for G in range(1, min(8, s.size - 1) + 1):
        same = (s[G:] == s[:-G]) & (run[G:] == run[:-G])
        if same.size and np.mean(same) >= 0.8:
            break
    else:
        raise LogError(
            f"the gaps in the log (missing {', '.join(map(str, s[:8]))} …) do not repeat; give the wheel "
            f"(wheel='N-g1-g2…')"
        )
    span = C[L[G:]] - C[L[:-G]]
    N = int(Counter(span.tolist()).most_common(1)[0][0])
    windows = Counter(
        (tuple(int(x) for x in s[j : j + G]), tuple(int(x) for x in run[j : j + G]))
        for j in range(min(s.size - G + 1, 400))
        if C[L[j + G]] - C[L[j]] == N
    )
    if not windows:
        raise LogError("no revolution of the log repeats its gaps; give the wheel (wheel='N-g1-g2…')")
    (gaps, lay), _ = windows.most_common(1)[0]
    r = max(range(G), key=lambda k: (gaps[k], lay[k:] + lay[:k]))
    gaps, lay = gaps[r:] + gaps[:r], lay[r:] + lay[:r]
    return Wheel(N, sum(gaps), gaps, lay)


def counted_wheels(times: ArrayLike) -> list[Wheel]:
    """The wheels counted from the edges: with the gap windows corrected for a displaced
    neighbour, and as counted plainly (distinct, the corrected one first)."""
    t = np.asarray(times, dtype=np.float64)
    if t.size < 12:
        raise LogError(f"{t.size} tooth edges: too few to find the wheel")
    t, _, p = remove_extra_edges(t, True, "the tooth edges")
    dt = np.diff(t)
    if p is None:
        p, _ = pitches(dt)
    n = np.maximum(np.round(p).astype(np.int64), 1)
    out: list[Wheel] = []
    err: LogError | None = None
    for m in (_gap_pitches(dt, p, n), n):
        try:
            w = _pattern(m)
        except LogError as e:
            err = err or e
            continue
        if all(w.spec != o.spec or w.layout != o.layout for o in out):
            out.append(w)
    if not out:
        assert err is not None
        raise err
    return out


def _may_be(counted: Wheel, std: Wheel) -> bool:
    """Whether the edges counted as ``counted`` may be those of the wheel ``std``: over a whole
    number of either's revolutions, as many edges, or fewer by at most one per gap (a weak tooth
    next to a gap that the threshold did not see)."""
    if counted.teeth % std.teeth == 0:
        k = counted.teeth // std.teeth
        return k * (std.edges_per_rev - len(std.gaps)) <= counted.edges_per_rev <= k * std.edges_per_rev
    if std.teeth % counted.teeth == 0:  # a pattern that repeats within a revolution, counted as its part
        k = std.teeth // counted.teeth
        return std.edges_per_rev - len(std.gaps) <= k * counted.edges_per_rev <= std.edges_per_rev
    return False


def candidates(times: ArrayLike) -> list[Wheel]:
    """The wheels worth trying on these edges: those counted (:func:`counted_wheels`) and the
    standard patterns with as many edges per revolution, or up to one more per gap (a weak
    tooth next to each gap that the threshold did not see, which the signal may show), or
    that repeat a counted one; every standard pattern where counting finds no repeating gap
    (weak teeth seen in some revolutions only)."""
    try:
        counted = counted_wheels(times)
    except LogError:
        return [parse_wheel(spec) for spec in STANDARD_WHEELS]
    out = list(counted)
    for spec in STANDARD_WHEELS:
        s = parse_wheel(spec)
        if any(s.spec == c.spec for c in out):
            continue
        if any(_may_be(c, s) for c in counted):
            out.append(s)
    return out


def _plainest(ok: list[WheelFit]) -> list[WheelFit]:
    """The fits a wheel found from the signal is chosen from: a wheel with a signature (a tooth
    the signal lacks in most revolutions) only where it is a standard one and no standard wheel
    fits without one (a 60-1 whose second tooth after the gap never shows is a 60-2)."""
    plain = [f for f in ok if not f.signature]
    if any(f.standard for f in plain):
        return plain
    return plain + [f for f in ok if f.signature and f.standard]


def rank(fits: Sequence[WheelFit]) -> tuple[WheelFit | None, WheelFit | None, str]:
    """The best fit of ``fits``, the runner-up, and why in words; ``(None, runner-up, why)``
    where the signal does not tell the two best apart (both standard patterns, or neither)."""
    ok = [
        f
        for f in fits
        if f.status.ok
        and f.gap_misfit <= MAX_GAP_MISFIT
        and f.revolutions >= MIN_REVOLUTIONS
        and (f.standard or int(f.spec.split("-")[0]) >= MIN_COUNTED_POSITIONS)
    ]
    if not ok:
        loose = [f for f in fits if f.status.ok]
        small = [
            f
            for f in loose
            if f.gap_misfit <= MAX_GAP_MISFIT
            and f.revolutions >= MIN_REVOLUTIONS
            and int(f.spec.split("-")[0]) < MIN_COUNTED_POSITIONS
        ]
        if small:
            f = small[0]
            return (
                None,
                None,
                (
                    f"{f.spec} fits ({f.revolutions} revolutions, gap misfit {100 * f.gap_misfit:.1f} %), but a wheel of "
                    f"fewer than {MIN_COUNTED_POSITIONS} positions is taken only when named (wheel='{f.spec}')"
                ),
            )
        if loose:
            f = min(loose, key=lambda f: f.gap_misfit)
            return (
                None,
                None,
                (
                    f"no wheel fits within a gap misfit of {100 * MAX_GAP_MISFIT:.0f} % on {MIN_REVOLUTIONS} or more "
                    f"revolutions (the best, {f.spec}: {100 * f.gap_misfit:.1f} % on {f.revolutions})"
                ),
            )
        return None, None, "no wheel fits"
    ok = _plainest(ok)
    ok.sort(key=lambda f: (f.inferred, f.gap_misfit))
    best = ok[0]
    if len(ok) == 1:
        return best, None, "the only wheel that fits"
    rest = [f for f in ok[1:] if f.spec != best.spec]
    if not rest:
        return best, None, "the only wheel that fits"
    second = rest[0]
    close = second.inferred == best.inferred and (
        second.gap_misfit < MARGIN * best.gap_misfit or second.gap_misfit < MISFIT_FLOOR
    )
    if not close:
        why = (
            f"gap misfit {100 * best.gap_misfit:.1f} % against {100 * second.gap_misfit:.1f} % for {second.spec}"
            if second.inferred == best.inferred
            else f"{best.inferred} inferred edges against {second.inferred} for {second.spec}"
        )
        return best, second, why
    if best.standard != second.standard:
        std = best if best.standard else second
        other = second if best.standard else best
        return (
            std,
            other,
            f"a standard pattern, where {other.spec} fits alike (gap misfit {100 * std.gap_misfit:.1f} % and "
            f"{100 * other.gap_misfit:.1f} %)",
        )
    return None, second, f"{best.spec} and {second.spec} fit alike"


def find_wheel(times: ArrayLike, *, what: str = "the tooth edges") -> tuple[Wheel, str]:
    """The wheel of a log, found from its edge times [s] (``wheel="auto"``).

    The candidates (:func:`candidates`) are placed on the edges and ranked (:func:`rank`):
    fewest inferred edges, then the smallest gap misfit. Raises :class:`LogError` naming
    both where the signal does not tell the two best apart, or where none fits.

    **Returns:** (the wheel with its layout, the evidence in words).
    """
    t = np.asarray(times, dtype=np.float64)
    cands = candidates(t)
    fits = [fit_wheel(t, w) for w in cands]
    best, second, why = rank(fits)
    if best is None:
        if second is None:
            reasons = "; ".join(f.describe() for f in fits)
            lead = f"{why}; " if why != "no wheel fits" else ""
            raise LogError(f"no wheel fits {what}: {lead}{reasons}; give the wheel (wheel='N-g1-g2…')")
        ok = sorted((f for f in fits if f.status.ok), key=lambda f: (f.inferred, f.gap_misfit))
        raise LogError(
            f"{what} fit {ok[0].describe()} and {second.describe()} alike (within {MARGIN:g}× gap misfit); "
            f"give the wheel (wheel='{ok[0].spec}' or wheel='{second.spec}')"
        )
    assert best.track is not None
    return best.track.wheel, evidence(best, second, why)


def evidence(best: WheelFit, second: WheelFit | None, why: str) -> str:
    """In words: the wheel found, what it rests on, and the runner-up."""
    w = best.track.wheel if best.track is not None else parse_wheel(best.spec)
    said = (
        f"wheel found from the log: {w.spec} ({w.describe()}); {best.revolutions} revolutions of "
        f"{w.edges_per_rev} edges, gap misfit {100 * best.gap_misfit:.1f} %"
    )
    if second is not None:
        said += f"; chosen over {second.spec}: {why}"
    return said
