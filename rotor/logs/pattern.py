"""Following a trigger wheel's pattern through the edges: any ``N-g1-g2-…`` wheel, the
places of its gaps found from the log, and the repairs the pattern proves.

**Tooth periods in pitches.** Each period between neighbouring edges is divided by the
median of the 9 periods around it (a running median filter) (the local tooth period: a gap or a stray edge among
them does not move a median), so a regular tooth reads about 1 and a gap of g missing
teeth about g + 1 while the speed changes by a few per cent per tooth (a start, a
compression stroke while cranking). Rounded, these are the pitches each period spans.

**Repairs, each reported** (:class:`Repair`: what, when, in which revolution, how sure):

- a period shorter than half a pitch holds an **extra edge** (a glitch, a double edge):
  of the two edges around it, the one whose removal leaves the merged period nearer a
  whole number of pitches is removed (sureness: 1 − 2·that distance);
- the edges are placed on the wheel by the offset at which the fewest fall on a missing
  position; a period that spans a position where the wheel has a tooth holds a **missed
  edge** (a weak tooth below the threshold, two teeth merged): it is inferred at its
  place in time, pro rata of the pitches (sureness: 1 − 2·the period's distance from a
  whole number of pitches; only where the period is within 0.25 of one). With a sampled
  signal the tooth itself is looked for there at a lower level (a ``probe``,
  :func:`rotor.logs.edges.find_weak_edges`) and, where it is there, measured (**missed
  edge found**);
- where the fewest edges on a missing position leave several placements (a tooth missed
  in every revolution next to a gap: timing alone cannot tell the first tooth after it
  from the last before it), the placement whose missed edges the signal shows is taken,
  and ``ToothTrack.placement`` says so (without a signal, or where it does not tell,
  the placement with the earliest tooth 0, and it says that);
- edges that do not fit at the start or the end of the log (at most two revolutions'
  worth each: a starter engaging, an engine stopping) are **dropped**.

Anything else, a stretch in the middle where no placement fits, is an error naming the
time and the period that breaks the pattern.

**Angle 0** is the first tooth after gap 1 (see :class:`rotor.logs.wheel.Wheel`).
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Callable

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike

from ..errors import LogError
from .wheel import Repair, ToothTrack, Wheel, parse_wheel, period_ratios, repairs_json, repairs_summary
from .windows import running

__all__ = ["Repair", "locate_teeth", "follow_pattern", "repairs_json", "repairs_summary", "pitches"]

SHORT = 0.5  # a period shorter than this many local tooth periods holds an extra edge
END_REVS = 2  # at most this many revolutions' edges dropped at either end of the log
HALF = 4  # the local tooth period: the median of 2·HALF + 1 periods
PROBE_LIMIT = 200  # missed edges asked of the signal per placement, to choose between placements
UNSURE = 0.25  # a missed edge is inferred only where its period is this near a whole number of pitches


def pitches(dt: np.ndarray, refine: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Each period of ``dt`` [s] in local tooth periods [-], two ways: (against the
    geometric mean of its two neighbours, each divided by the pitches it spans: follows a
    speed that changes by half within a few teeth, as while cranking; against the median
    of the 2·4 + 1 periods around it: robust to a stray edge next to it). The first comes
    from the second in ``refine`` rounds."""
    n = dt.size
    if n < 2 * HALF + 1:
        p0 = dt / np.median(dt)
    else:
        p0 = dt / running(dt, 2 * HALF + 1, np.median, "mirror")  # the ends reflected
    p = p0
    if n < 3:
        return p, p0
    k_prev = None
    ref = np.empty(n)
    for _ in range(refine):
        k = np.maximum(np.round(p), 1.0)
        if k_prev is not None and np.array_equal(k, k_prev):
            break  # the pitches are what they were: so is every ratio after them
        u = dt / k
        np.multiply(u[:-2], u[2:], out=ref[1:-1])
        np.sqrt(ref[1:-1], out=ref[1:-1])
        ref[0], ref[-1] = u[1], u[-2]
        p = dt / ref
        k_prev = k
    return p, p0


def remove_extra_edges(t: np.ndarray, repair: bool, what: str):
    """``t`` without the edges that split a tooth period (periods < SHORT pitches), the
    repairs, and the periods of the edges kept in pitches (:func:`pitches`; None if not
    known)."""
    out: list[Repair] = []
    p = None
    for _ in range(20):
        dt = np.diff(t)
        p, p0 = pitches(dt)
        short = np.flatnonzero((p < SHORT) & (p0 < SHORT))
        if short.size == 0:
            break
        if not repair:
            i = int(short[0])
            raise LogError(
                f"at t = {t[i + 1]:.6f} s a tooth period of {p[i]:.2f} pitches (an extra edge?) in {what}; "
                f"repair=True removes it"
            )
        big = np.inf
        left = np.where(short > 0, p0[np.maximum(short - 1, 0)] + p0[short], big)
        right = np.where(short + 1 < dt.size, p0[short] + p0[np.minimum(short + 1, dt.size - 1)], big)
        with np.errstate(invalid="ignore"):  # inf where there is no neighbour: never the nearer
            el = np.abs(left - np.round(left))
            er = np.abs(right - np.round(right))
        el[short == 0] = 0.0  # the first edge of the log: drop it
        er[short + 1 == dt.size] = 0.0
        use_left = el <= er
        drop = np.where(use_left, short, short + 1)
        err = np.where(use_left, el, er)
        keep = np.concatenate([[True], np.diff(drop) > 1])
        drop, err = drop[keep], err[keep]
        out += [
            Repair(
                "extra edge removed",
                float(t[k]),
                None,
                float(max(1 - 2 * e, 0.0)),
                "a tooth period split in two (a glitch or a double edge)",
            )
            for k, e in zip(drop, err)
        ]
        t = np.delete(t, drop)
        p = None  # the periods changed
    return t, out, p


def _canonical(gaps: tuple, layout: tuple) -> tuple:
    """Of the rotations of (gaps, layout) that keep ``gaps``, the layout largest in
    lexicographic order (gap 1 = the one followed by the most teeth)."""
    G = len(gaps)
    rots = [tuple(layout[r:] + layout[:r]) for r in range(G) if tuple(gaps[r:] + gaps[:r]) == tuple(gaps)]
    return max(rots)


def _find_layout(n: np.ndarray, wheel: Wheel, t: np.ndarray) -> tuple:
    """The teeth after each gap, from the periods ``n`` [pitches]: the commonest window of
    long periods whose missing teeth are the wheel's gaps and whose pitches add up to N."""
    G = len(wheel.gaps)
    L = np.flatnonzero(n >= 2)
    if L.size < G + 1:
        raise LogError(
            f"{L.size} gap(s) found in {t.size} tooth edges (t = {t[0]:.6f} … {t[-1]:.6f} s): a {wheel.spec} "
            f"wheel has {G} per revolution (is the wheel right? wheel='auto' finds it)"
        )
    s = n[L] - 1
    C = np.concatenate([[0], np.cumsum(n)])
    win = sliding_window_view(s, G)[: L.size - G]
    ok = np.all(win == np.asarray(wheel.gaps)[None, :], axis=1)
    span = C[L[G:]] - C[L[: L.size - G]]
    ok &= span == wheel.teeth
    if not np.any(ok):
        seen = ", ".join(str(int(x)) for x in s[:8])
        raise LogError(
            f"no revolution of the log shows a {wheel.spec} wheel: the gaps found miss {seen}"
            f"{' …' if s.size > 8 else ''} teeth (t = {t[L[0]]:.6f} s on); is the wheel right? (wheel='auto' finds it)"
        )
    lay = np.diff(sliding_window_view(L, G + 1)[: L.size - G][ok], axis=1)
    base = int(wheel.teeth) + 1
    if base**G < 2**62:  # each row as one number: np.unique of numbers is far faster than of rows
        code = lay @ (base ** np.arange(G, dtype=np.int64))
        u, first, counts = np.unique(code, return_index=True, return_counts=True)
        rows = lay[first]
    else:
        rows, counts = np.unique(lay, axis=0, return_counts=True)
    votes: Counter = Counter()
    for r, c in zip(rows, counts):
        votes[_canonical(wheel.gaps, tuple(int(x) for x in r))] += int(c)
    return votes.most_common(1)[0][0]


def _missed(t, n, pos, present, N):
    """Where the periods ``n`` [pitches] between the edges ``t`` [s] at wheel positions
    ``pos`` span a position with a tooth: (period index, pitches into it) of each, by
    period."""
    long = np.flatnonzero(n > 1)  # only these can span a position
    if long.size == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    nl = n[long]
    mmax = int(nl.max())
    m = np.arange(1, mmax)
    ahead = (pos[long][:, None] + m[None, :]) % N
    hit = (m[None, :] < nl[:, None]) & present[ahead]
    r, k = np.nonzero(hit)
    return long[r], m[k]


def _probe_score(probe, t, n, pos, present, N, limit=PROBE_LIMIT):
    """How many of the first ``limit`` edges a placement says are missed the signal shows
    (``probe``), and their summed swing."""
    ii, mm = _missed(t, n, pos, present, N)
    if ii.size == 0:
        return (0, 0.0)
    order = np.argsort(ii, kind="stable")[:limit]
    ii, mm = ii[order], mm[order]
    guess = t[ii] + (t[ii + 1] - t[ii]) * mm / n[ii]
    found, swing = probe(guess, (t[ii + 1] - t[ii]) / n[ii])
    ok = np.isfinite(found)
    return (int(ok.sum()), float(swing[ok].sum()))


def follow_pattern(
    t: np.ndarray,
    wheel: Wheel,
    *,
    repair: bool = True,
    what: str = "the tooth edges",
    probe: Callable | None = None,
) -> ToothTrack:
    """Place the edge times ``t`` [s] on ``wheel`` (see the module notes), finding where
    its gaps lie if the wheel does not say; with ``repair``, remove extra edges, infer
    missed ones and drop edges at the ends that do not fit, each reported in the
    track's ``repairs``; without, any of these is an error.

    ``probe(guess_s, pitch_s) -> (times_s, swing)``: looks for a missed edge in the
    recorded signal near each guessed time [s], given the local tooth period [s]; NaN
    where there is none (for a sampled signal, :func:`rotor.logs.edges.find_weak_edges`).
    With it, a missed edge the signal shows is measured (``"missed edge found"``) instead
    of inferred, and where timing alone cannot tell which tooth is missed (a tooth missed
    in every revolution next to a gap: the last tooth before it or the first after it),
    the placement whose missed edges the signal shows is taken.

    **Returns:** :class:`rotor.logs.wheel.ToothTrack`.
    """
    t = np.asarray(t, dtype=np.float64)
    N, E = wheel.teeth, wheel.edges_per_rev
    t, repairs, p = remove_extra_edges(t, repair, what)
    if t.size < E + 3:
        raise LogError(f"{t.size} tooth edges after removing extra ones: a {wheel.spec} wheel needs {E + 3} or more")
    dt = np.diff(t)
    if p is None:
        p, _ = pitches(dt)
    n = np.maximum(np.round(p).astype(np.int64), 1)
    if wheel.layout is None:
        wheel = Wheel(wheel.teeth, wheel.missing, wheel.gaps, _find_layout(n, wheel, t), wheel.angles_deg)
    present = np.zeros(N, bool)
    present[wheel.positions] = True
    c = np.concatenate([[0], np.cumsum(n)])
    pos0 = c % N
    h = np.bincount(pos0, minlength=N)
    miss = (~present).astype(np.int64)
    bad = np.array([int(np.dot(h, np.roll(miss, -o))) for o in range(N)])
    tied = np.flatnonzero(bad == bad.min())
    first0 = [int(np.argmax(pos0 == (N - o) % N)) if h[(N - o) % N] else c.size for o in tied]
    o = int(tied[int(np.argmin(first0))])
    ambiguous = ""
    if tied.size > 1 and repair:
        # timing alone cannot tell these placements apart (e.g. a tooth missed in every revolution next to a
        # gap: the last before it or the first after it); the signal can, where it shows the missed teeth
        scores = [_probe_score(probe, t, n, (pos0 + oo) % N, present, N) if probe else (0, 0.0) for oo in tied]
        best = max(range(tied.size), key=lambda k: (scores[k], -first0[k]))
        o = int(tied[best])
        others = [k for k in range(tied.size) if k != best]
        if probe is not None and scores[best][0] > max(scores[k][0] for k in others):
            ambiguous = (
                f"of {tied.size} placements that fit the timing alike, the one whose missed edges the signal "
                f"shows ({scores[best][0]} of those looked for, against "
                f"{max(scores[k][0] for k in others)})"
            )
        else:
            ambiguous = (
                f"{tied.size} placements fit the timing alike and the signal does not tell them apart: the one "
                f"with the earliest tooth 0 taken (angle 0 may be a tooth off)"
            )
    pos = pos0 + o
    pos[pos >= N] -= N
    good = present[pos]
    # a period that spans a tooth but is far from a whole number of pitches (the engine stopping, a
    # starter engaging): not a missed edge the pattern proves
    link = np.ones(n.size, bool)  # period i joins edges i and i + 1
    span, _ = _missed(t, n, pos, present, N)
    link[span] = np.abs(p[span] - n[span]) <= UNSURE
    lo, hi = _fitting_stretch(t, p, dt, good, link, wheel, repair, repairs)  # the edges kept: lo … hi − 1
    t, c, pos, p, n = t[lo:hi], c[lo:hi], pos[lo:hi], p[lo : hi - 1], n[lo : hi - 1]
    # missed edges: present positions inside a period
    t, c = _fill_missed(t, c, p, n, pos, present, wheel, repair, probe, repairs)
    C = c + o
    pos = C % N
    tooth_of = np.cumsum(present) - 1
    tooth = tooth_of[pos]
    zero = np.flatnonzero(tooth == 0)
    if zero.size == 0:
        raise LogError(f"no edge of tooth 0 of the {wheel.spec} wheel in the log")
    rev = np.floor_divide(C - C[zero[0]], N)
    # the gap and tooth period ratios, as for a single gap
    d = np.diff(t)
    r = np.full(d.size, np.nan)
    r[1:-1] = d[1:-1] / np.sqrt(d[:-2] * d[2:])
    step = np.diff(C)
    regular = np.zeros(d.size, bool)
    regular[1:-1] = (step[1:-1] == 1) & (step[:-2] == 1) & (step[2:] == 1)
    on_gap1 = (tooth[:-1] == E - 1) & (tooth[1:] == 0)
    on_gap1[[0, -1]] = False
    gap_ratio = float(np.median(r[on_gap1])) if np.any(on_gap1) else float("nan")
    tooth_max = float(np.nanmax(r[regular])) if np.any(regular) else float("nan")
    repairs = place(repairs, t, rev)
    return ToothTrack(t, tooth, rev, wheel, gap_ratio, tooth_max, tuple(repairs), ambiguous)


def _fitting_stretch(t, p, dt, good, link, wheel: Wheel, repair: bool, repairs: list) -> tuple[int, int]:
    """The edges to keep, ``lo`` … ``hi`` − 1: all where every edge and period fits, else the
    longest stretch of edges that fit, joined by periods that fit, the rest lying at the
    ends (each dropped edge added to ``repairs``); an error where it does not."""
    E = wheel.edges_per_rev
    if good.all() and link.all():
        return 0, t.size
    # the longest stretch of edges that fit, joined by periods that fit; the rest must lie at the ends
    new_seg = np.ones(t.size, bool)
    new_seg[1:] = ~(good[1:] & good[:-1] & link)
    seg = np.cumsum(new_seg)
    size = np.bincount(seg, weights=good.astype(np.float64))
    k = int(np.argmax(size))
    idx = np.flatnonzero(seg == k)
    a, b = int(idx[0]), int(idx[-1]) + 1
    if not good[a]:
        a += 1
    if not repair or a > END_REVS * E or t.size - b > END_REVS * E:
        if not repair:
            i = int(np.argmin(good))
        else:
            i = b if t.size - b > END_REVS * E else a - 1
        i = int(np.clip(i, 0, t.size - 1))
        j = min(i, dt.size - 1)
        raise LogError(
            f"at t = {t[i]:.6f} s the edges stop fitting the {wheel.spec} wheel ({wheel.describe()}): "
            f"a tooth period of {p[j]:.2f} pitches puts an edge where the wheel has no tooth "
            f"(edges {a} … {b - 1} of {t.size} fit; a wrong wheel, or edges too irregular to follow)"
        )
    for lo_i, hi_i, where in ((0, a, "start"), (b, t.size, "end")):
        repairs += [
            Repair(
                "edge dropped",
                float(t[i]),
                None,
                1.0,
                f"one of {hi_i - lo_i} edges at the {where} of the log ({t[lo_i]:.6f} … {t[hi_i - 1]:.6f} s) "
                f"that do not fit the wheel (a starter engaging, the engine stopping?)",
            )
            for i in range(lo_i, hi_i)
        ]
    return a, b


def _fill_missed(t, c, p, n, pos, present, wheel: Wheel, repair: bool, probe, repairs: list):
    """The edge times and counts with the missed edges put in: measured where ``probe``
    finds them in the signal, else inferred pro rata (each added to ``repairs``); an error
    where there are any and not ``repair``."""
    N = wheel.teeth
    ii, mm = _missed(t, n, pos, present, N)
    if ii.size:
        if not repair:
            j = int(ii.min())
            raise LogError(
                f"at t = {t[j]:.6f} s a tooth period of {p[j]:.2f} pitches spans a tooth of the {wheel.spec} "
                f"wheel (a missed edge); repair=True infers it"
            )
        tt = t[ii] + (t[ii + 1] - t[ii]) * mm / n[ii]
        conf = np.maximum(1 - 2 * np.abs(p[ii] - n[ii]), 0.0)
        found = np.full(tt.size, np.nan)
        swing = np.zeros(tt.size)
        if probe is not None:
            found, swing = probe(tt, (t[ii + 1] - t[ii]) / n[ii])
            # a found edge must keep its place between its neighbours (the edges around it, found or not)
            lo_b = t[ii] + (t[ii + 1] - t[ii]) * (mm - 0.5) / n[ii]
            hi_b = t[ii] + (t[ii + 1] - t[ii]) * (mm + 0.5) / n[ii]
            found = np.where((found > lo_b) & (found < hi_b), found, np.nan)
        got = np.isfinite(found)
        for x, f, q, pp, sw in zip(tt, found, conf, p[ii], swing):
            if np.isfinite(f):
                repairs.append(
                    Repair(
                        "missed edge found",
                        float(f),
                        None,
                        float(min(1.0, sw / 0.1) * q),
                        f"a weak tooth ({sw:.0%} of the swing) found where the pattern has one",
                    )
                )
            else:
                repairs.append(
                    Repair(
                        "missed edge inferred",
                        float(x),
                        None,
                        float(q),
                        f"a period of {pp:.2f} pitches spans a tooth: placed pro rata",
                    )
                )
        t = np.concatenate([t, np.where(got, found, tt)])
        c = np.concatenate([c, c[ii] + mm])
        order = np.argsort(c, kind="stable")
        t, c = t[order], c[order]
    return t, c


def place(repairs, t: np.ndarray, rev: np.ndarray) -> list:
    """The repairs with their revolution: that of the edge at or before each (of the first
    edge, for one before the first), sorted by time."""
    out = []
    for rp in repairs:
        k = int(np.clip(np.searchsorted(t, rp.time_s, side="right") - 1, 0, t.size - 1))
        out.append(dataclasses.replace(rp, revolution=int(rev[k])))
    return sorted(out, key=lambda r: r.time_s)


def locate_teeth(
    times: ArrayLike,
    wheel: str | Wheel,
    *,
    index_times: ArrayLike | None = None,
    repair: bool = False,
    probe: Callable | None = None,
) -> ToothTrack:
    """Place each tooth edge on the wheel: find the gaps (or use the index) and count.

    **Arguments:** ``times``: tooth edge times [s], increasing; ``wheel``: a
    :class:`Wheel` or a spec such as ``"60-2"`` or ``"36-2-1"``; ``index_times``:
    once-per-revolution index edge times [s], needed for a wheel without a gap;
    ``repair``: make the edges follow the wheel's pattern where it proves how
    (:func:`rotor.logs.pattern.follow_pattern`: an extra edge removed, a missed one
    inferred, edges that do not fit at the ends of the log dropped), each repair reported
    in ``ToothTrack.repairs``; ``False`` (default): any edge that does not fit is an error;
    ``probe``: with ``repair``, looks for a missed edge in the recorded signal (see
    :func:`rotor.logs.pattern.follow_pattern`).

    **Returns:** :class:`ToothTrack`. Raises :class:`LogError` if the log is shorter
    than a revolution, no gap is found, or the edges between two gaps are not N−M (or,
    with ``repair``, where the pattern cannot be followed, saying where and why).
    """
    wheel = parse_wheel(wheel)
    try:
        t = np.asarray(times, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"locate_teeth(times): an array of edge times [s], not {type(times).__name__}") from None
    if t.ndim != 1:
        raise LogError(f"tooth edge times: a 1-d array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise LogError(
            f"tooth edge {int(np.flatnonzero(~np.isfinite(t))[0])}: time {t[~np.isfinite(t)][0]} is not finite"
        )
    E = wheel.edges_per_rev
    n = t.size
    if n < E + 3:
        raise LogError(
            f"{n} tooth edge{'s' if n != 1 else ''}: a {wheel.spec} wheel gives {E} per revolution; the log must hold more than "
            f"one revolution ({E + 3} edges or more) to find its reference"
        )
    if np.any(np.diff(t) <= 0):
        i = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        raise LogError(f"tooth edge {i}: time {t[i]:.9g} s is not after the previous edge's {t[i - 1]:.9g} s")
    if not wheel.needs_index and (repair or len(wheel.gaps) > 1):
        return follow_pattern(t, wheel, repair=repair, probe=probe)
    dt = np.diff(t)
    r = period_ratios(dt)
    if wheel.needs_index:
        if index_times is None:
            raise LogError(
                f"wheel {wheel.spec} has no gap: give a once-per-revolution index signal "
                f"(column 'index_v'), or the missing teeth (e.g. {wheel.teeth}-2)"
            )
        idx = np.asarray(index_times, dtype=np.float64)
        ref = np.unique(np.searchsorted(t, idx, side="left"))
        ref = ref[ref < n]
        if ref.size < 2:
            raise LogError(f"{ref.size} index pulse(s) within the tooth edges: need two or more (a whole revolution)")
        sp = np.diff(ref)
        bad = np.flatnonzero(sp != E)
        if bad.size:
            b = int(bad[0])
            raise LogError(
                f"between the index pulses at t = {t[ref[b]]:.6f} s and {t[ref[b + 1]]:.6f} s: "
                f"{sp[b]} tooth edges where a {wheel.spec} wheel gives {E} (a missed or extra edge?)"
            )
        first = int(ref[0])
        gap_ratio, tooth_max = float("nan"), float(np.nanmax(r))
    else:
        thr = math.sqrt(wheel.missing + 1)
        cand = np.flatnonzero(r > thr)
        if cand.size == 0:
            raise LogError(
                f"no gap of a {wheel.spec} wheel found in {n} tooth edges (t = {t[0]:.6f} … {t[-1]:.6f} s): "
                f"the largest tooth period is {np.nanmax(r):.2f}× its neighbours', a gap gives "
                f"{wheel.missing + 1}× (is the wheel right?)"
            )
        sp = np.diff(cand)
        bad = np.flatnonzero(sp != E)
        if bad.size:
            b = int(bad[0])
            raise LogError(
                f"between the gaps at t = {t[cand[b]]:.6f} s and {t[cand[b + 1]]:.6f} s: {sp[b]} tooth edges "
                f"where a {wheel.spec} wheel gives {E} (a missed or extra edge, or another wheel)"
            )
        g0, g1 = int(cand[0]), int(cand[-1])
        if g0 - E >= 1:
            i = g0 - E
            raise LogError(
                f"at t = {t[i]:.6f} s a gap of the {wheel.spec} wheel is due but the tooth period there is "
                f"only {r[i]:.2f}× its neighbours' (a missed or extra edge, or another wheel)"
            )
        if g1 + E <= dt.size - 2:
            i = g1 + E
            raise LogError(
                f"at t = {t[i]:.6f} s a gap of the {wheel.spec} wheel is due but the tooth period there is "
                f"only {r[i]:.2f}× its neighbours' (a missed or extra edge, or another wheel)"
            )
        # the first edge after the first gap found; an earlier edge at the same position (the log starts right
        # at a gap, whose long period is then before the first edge) is the first reference
        first = (g0 + 1) % E
        gap_ratio = float(np.median(r[cand]))
        regular = np.ones(dt.size, bool)
        regular[cand] = False
        regular[(np.arange(dt.size) - first) % E == E - 1] = False  # the unclassified end gaps
        tooth_max = float(np.nanmax(r[regular])) if np.any(regular & np.isfinite(r)) else float("nan")
    k = np.arange(n) - first
    return ToothTrack(t, np.mod(k, E), np.floor_divide(k, E), wheel, gap_ratio, tooth_max)
