"""Tooth edges of digital (0/1) channels given at their transitions: a logic-analyser or
ECU export (e.g. a Saleae CSV, ``Time[s], Channel 0, Channel 1``), one row per
transition of any channel, each row holding every channel's level after it.

A row where a channel keeps its level is no edge of that channel (another channel
changed), and the first row (often t = 0 with the initial levels) is no edge. **Glitches**
(a pulse of a fraction of a microsecond, e.g. a double edge) are removed as in
:func:`rotor.logs.edges.find_edges`, by duration: a high or low state lasting less than
``glitch`` (20 %) of the median duration of that state is merged into its neighbours, the
shortest first; each removal is reported (:class:`rotor.logs.wheel.Repair`). Then the
transitions to high (``edge="rising"``) or to low (``"falling"``) are the edges; which
is the cleaner one depends on the sensor and its conditioning, so both are offered.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import LogError
from .edges import Edges
from .pattern import Repair

__all__ = ["digital_edges", "digital_levels"]


def digital_levels(v: ArrayLike, name: str = "encoder_d") -> np.ndarray:
    """The 0/1 state of each row of a digital channel ``v`` (two levels, e.g. 0 and 1, or
    0 and 5 V: above their midpoint is 1); a :class:`LogError` naming the column if it
    holds more or fewer than two values."""
    v = np.asarray(v, dtype=np.float64)
    vals = np.unique(v)
    if vals.size != 2:
        shown = ", ".join(f"{x:g}" for x in vals[:5]) + (" …" if vals.size > 5 else "")
        raise LogError(
            f"column {name!r}: a digital channel holds two levels (0 and 1); this one holds {vals.size} ({shown})"
            + (": an analog signal? name it encoder_v" if vals.size > 2 else "")
        )
    return (v > 0.5 * (vals[0] + vals[1])).astype(np.int8)


def digital_edges(
    t: ArrayLike, v: ArrayLike, *, edge: str = "rising", glitch: float = 0.2, name: str = "encoder_d"
) -> Edges:
    """Edge times [s] of a digital channel given at its transitions.

    **Arguments:** ``t``: the row times [s], increasing; ``v``: the channel's level after
    each row (0/1); ``edge``: ``"rising"`` (to 1) or ``"falling"`` (to 0); ``glitch``: a
    state shorter than this fraction of the median duration of that state is a glitch
    [-]; ``name``: the column, for messages.

    **Returns:** :class:`rotor.logs.edges.Edges` (levels 0 and 1, ``repairs``: the glitches).
    """
    if edge not in ("rising", "falling"):
        raise LogError(f"edge = {edge!r}: 'rising' or 'falling'")
    t = np.asarray(t, dtype=np.float64)
    s = digital_levels(v, name)
    if t.shape != s.shape:
        raise LogError(f"{name}: {s.size} rows but {t.size} times")
    k = np.flatnonzero(np.diff(s) != 0) + 1  # rows where the channel changes
    tt, ss = t[k], s[k]  # transition times and the state after each
    repairs: list[Repair] = []
    for frac in (glitch / 4, glitch / 2, glitch):
        if tt.size < 6:
            break
        dur = np.diff(tt)  # run i: from transition i to i + 1, state ss[i]
        st = ss[:-1]
        short = np.zeros(dur.size, bool)
        med = {}
        for state in (0, 1):
            m = st == state
            if np.any(m):
                med[state] = float(np.median(dur[m]))
                short |= m & (dur < frac * med[state])
        short[0] = short[-1] = False
        if not np.any(short):
            continue
        # the shortest first; never two neighbouring runs at once
        i = np.flatnonzero(short)
        i = i[np.argsort(dur[i], kind="stable")]
        taken = np.zeros(dur.size + 2, bool)
        chosen = []
        for j in i:
            if not (taken[j] or taken[j + 2]):
                taken[j + 1] = True
                chosen.append(int(j))
        sel = np.sort(np.asarray(chosen, dtype=np.int64))
        repairs += [
            Repair(
                "glitch removed",
                float(tt[j]),
                None,
                float(1.0 - dur[j] / med[int(st[j])]),
                f"a {'high' if st[j] else 'low'} pulse of {dur[j] * 1e6:.3g} µs in {name!r}",
            )
            for j in sel
        ]
        drop = np.concatenate([sel, sel + 1])
        keep = np.ones(tt.size, bool)
        keep[drop] = False
        tt, ss = tt[keep], ss[keep]
        # merged runs of the same state leave no transition between them
        same = np.concatenate([[False], ss[1:] == ss[:-1]])
        tt, ss = tt[~same], ss[~same]
    want = 1 if edge == "rising" else 0
    times = tt[ss == want]
    return Edges(times, 0.0, 1.0, (0.5, 0.5), 0.5, len(repairs), edge == "falling", tuple(repairs), "digital")
