"""Trigger wheels: N−M missing-tooth wheels and wheels with an index, gap detection,
tooth angles, and the tooth-spacing errors of a wheel estimated from the data.

**Angles.** The wheel angle φ [rad] is 0 at the first tooth edge after the gap (or after
the index) of revolution 0, the first revolution whose reference edge the log holds;
tooth ``j`` of revolution ``r`` sits nominally at ``2π·r + j·2π/N``. Edges before the
first reference belong to revolution −1.

**Gap detection.** Each tooth period is compared with its two neighbours by the ratio
``dt_i / √(dt_{i−1}·dt_{i+1})``: a uniform acceleration changes neighbouring periods by
nearly the same factor, which the geometric mean cancels, so the ratio stays near 1
on a regular tooth and near M+1 on the gap while the speed changes fast (a coast-down,
a start). The threshold is their geometric midpoint √(M+1). The gaps must then be
exactly N−M edges apart all through the log; anything else (a missed or doubled edge,
the wrong wheel) is an error naming the time, never a silently wrong angle.

**Tooth-spacing errors** (cf. Diamond et al. 2016, Mech. Syst. Signal Process. 81):
each edge's angle error is read against a smooth angle-of-time curve through one
reference edge per revolution (a cubic spline through the times of tooth 0), and
averaged over the revolutions (an even number, so that a four-stroke engine's half
orders cancel). If the speed changes by more than half across the log (a coast-down),
each tooth's error is instead regressed on (ω̄/ω_rev)², which takes out the part of the
engine's fluctuation driven by gas and friction torque (it scales with 1/ω²). What no
data can separate: the engine's own speed fluctuation at integer orders that does not
scale with speed (the reciprocating inertia) looks exactly like a wheel error at that
order. So orders that stand out of the per-tooth errors (amplitude above ``4×`` the
median of the upper half of the orders) are left to the engine and removed from the
estimate (``engine_orders="auto"``); a calibration run with a smooth speed (a bare
wheel, or a motored coast-down of an engine with little reciprocating mass) recovers
all orders (``engine_orders=()``), and is saved as JSON for other recordings.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from collections import Counter
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import LogError
from ..fileio import load_json, save_json
from ..results import Result
from ..units import RPM_PER_RAD_S

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = [
    "Wheel",
    "parse_wheel",
    "read_wheel_file",
    "ToothTrack",
    "Repair",
    "repairs_json",
    "repairs_summary",
    "ToothErrors",
    "estimate_tooth_errors",
    "TooFewOrders",
    "firing_orders",
]

TWO_PI = 2.0 * np.pi


class TooFewOrders(LogError):
    """A firing run's tooth errors cannot be estimated: the engine's orders leave too few of
    the wheel's (a calibration from a coast-down or motored run gives them)."""


ENGINE_ORDER_FACTOR = 4.0  # an order is the engine's if its amplitude is this many times the floor


@dataclasses.dataclass(frozen=True)
class Wheel:
    """A trigger wheel of ``teeth`` equally spaced positions per revolution, ``missing`` of
    them without a tooth.

    ``gaps``: the missing teeth of each gap in the order the wheel passes the sensor,
    gap 1 first (``(2,)`` for a 60-2 wheel, ``(2, 1)`` for 36-2-1); ``layout``: the teeth
    that follow each gap up to the next one (``(58,)`` for 60-2; for several gaps found
    from the log by :func:`locate_teeth`, ``None`` until then). ``missing = 0``: a wheel
    whose revolutions are marked by a separate once-per-revolution index signal.
    ``angles_deg``: measured angle of each tooth from tooth 0 [deg] (a wheel file), or
    ``None``.

    **Angle 0** is the first tooth after gap 1 (the gap named first in the spec; in a
    wheel file, the longest gap). Where the spec names several gaps of the same size,
    gap 1 is the one followed by the most teeth (the layout read round from gap 1 is the
    largest in lexicographic order); on a wheel whose pattern repeats within a
    revolution (e.g. three equal gaps evenly spaced), the first such gap in the log.
    """

    teeth: int
    missing: int = 0
    gaps: tuple = ()
    layout: tuple | None = dataclasses.field(default=None, compare=False)
    angles_deg: tuple | None = dataclasses.field(default=None, compare=False)

    def __post_init__(self):
        if not (isinstance(self.teeth, (int, np.integer)) and self.teeth >= 3):
            raise LogError(f"wheel: {self.teeth!r} teeth; need a whole number, 3 or more")
        if not (isinstance(self.missing, (int, np.integer)) and not isinstance(self.missing, bool)):
            raise LogError(f"wheel: {self.missing!r} missing teeth; need a whole number")
        gaps = tuple(int(g) for g in self.gaps)
        if not gaps and self.missing:
            gaps = (int(self.missing),)
        missing = int(self.missing) if self.missing else sum(gaps)
        if any(g < 1 for g in gaps) or sum(gaps) != missing:
            raise LogError(f"wheel: gaps {gaps!r} do not add up to {missing} missing teeth (each gap 1 or more)")
        if not (0 <= missing <= self.teeth - 2 * max(len(gaps), 1)):
            raise LogError(f"wheel: {self.missing!r} missing teeth of {self.teeth}; need 0 … {self.teeth - 2}")
        object.__setattr__(self, "gaps", gaps)
        object.__setattr__(self, "missing", missing)
        layout = self.layout
        if layout is None and len(gaps) == 1:
            layout = (self.teeth - missing,)
        if layout is not None:
            layout = tuple(int(x) for x in layout)
            if len(layout) != len(gaps) or any(x < 1 for x in layout) or sum(layout) != self.teeth - missing:
                raise LogError(
                    f"wheel {self.spec}: teeth between the gaps {layout!r} do not fit {len(gaps)} gap(s) and "
                    f"{self.teeth - missing} teeth"
                )
        object.__setattr__(self, "layout", layout)
        if self.angles_deg is not None:
            a = tuple(float(x) for x in self.angles_deg)
            if len(a) != self.edges_per_rev or not all(math.isfinite(x) for x in a):
                raise LogError(
                    f"wheel {self.spec}: {len(a)} measured tooth angles; the wheel has {self.edges_per_rev} teeth"
                )
            object.__setattr__(self, "angles_deg", a)

    @property
    def spec(self) -> str:
        return f"{self.teeth}" + "".join(f"-{g}" for g in self.gaps)

    @property
    def pitch_rad(self) -> float:
        """Angle between neighbouring tooth positions [rad]."""
        return TWO_PI / self.teeth

    @property
    def edges_per_rev(self) -> int:
        return self.teeth - self.missing

    @property
    def needs_index(self) -> bool:
        return self.missing == 0

    @property
    def positions(self) -> np.ndarray:
        """The position (0 … teeth−1, 0 = tooth 0) of each tooth, tooth 0 first; a
        :class:`LogError` while the gaps' places are not known (found by :func:`locate_teeth`)."""
        if self.missing == 0:
            return np.arange(self.teeth)
        if self.layout is None:
            raise LogError(f"wheel {self.spec}: where its gaps lie is found from the log (locate_teeth)")
        out: list[int] = []
        pos = 0
        for run, gap in zip(self.layout, self.gaps[1:] + self.gaps[:1]):
            out.extend(range(pos, pos + run))
            pos += run + gap
        return np.asarray(out, dtype=np.int64)

    @property
    def tooth_angles_rad(self) -> np.ndarray:
        """Nominal angle of each tooth from tooth 0 [rad] (its position × the pitch)."""
        return self.pitch_rad * self.positions

    def describe(self) -> str:
        """The pattern in words: teeth and gaps going round from tooth 0."""
        if self.missing == 0:
            return f"{self.teeth} teeth and an index"
        if self.layout is None:
            return f"{self.teeth} positions, gaps of {', '.join(map(str, self.gaps))} missing teeth"
        parts = []
        for run, gap in zip(self.layout, self.gaps[1:] + self.gaps[:1]):
            parts.append(f"{run} teeth, {gap} missing")
        return f"{self.teeth} positions going round from tooth 0: " + ", ".join(parts)


MAX_POSITIONS = 100_000
"""The most tooth positions a wheel spec may name (an encoder of 10⁵ lines per revolution)."""
WHEEL_FILE_KEYS = ("positions", "missing", "angles_deg")
"""The keys of a wheel file; any other is refused by name."""
MAX_WHEEL_FILE_BYTES = 10_000_000
"""The largest wheel file read [bytes]: 10⁵ measured angles take about 2 MB."""


def _shown(spec: object, limit: int = 40) -> str:
    text = repr(spec)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def parse_wheel(spec: str | int | os.PathLike | Wheel) -> Wheel:
    """A :class:`Wheel` from ``"60-2"``, ``"36-1"`` (N−M), ``"36-2-1"``, ``"36-2-2-2"``
    (N positions and the missing teeth of each gap, gap 1 first: where the gaps lie is
    found from the log), ``"60"`` or ``60`` (with an index) or a wheel file (``*.toml``, see
    :func:`read_wheel_file`).

    **Errors:** a spec that names no wheel raises :class:`LogError` with ``argument="wheel"``
    and a message starting ``wheel=``: N from 3 to :data:`MAX_POSITIONS`, each gap 1 or
    more, and at most N − 2 × gaps missing teeth in all (a tooth on either side of each
    gap). A ``spec`` of another type (a float, a list, None) raises ``TypeError`` naming
    ``wheel``."""
    if isinstance(spec, Wheel):
        return spec
    if isinstance(spec, bool) or not isinstance(spec, (str, int, np.integer, os.PathLike)):
        raise TypeError(
            f"wheel={_shown(spec)}: expected a spec such as '60-2' (a str), a tooth count (an int), a wheel "
            f"file's path or a Wheel, not {type(spec).__name__}"
        )
    if isinstance(spec, os.PathLike):
        return read_wheel_file(spec)
    text = str(spec).strip()
    if text.lower().endswith(".toml"):
        return read_wheel_file(text)
    m = re.fullmatch(r"(\d+)((?:\s*-\s*\d+)*)", text)
    if not m:
        raise LogError(
            f"wheel={_shown(spec)}: expected N-M teeth such as 60-2, 36-1, 36-2, N-g1-g2 such as 36-2-1, "
            f"a wheel file (.toml), auto, or N for a wheel with an index",
            argument="wheel",
        )
    digits = [d.lstrip("0") for d in re.findall(r"\d+", text)]
    if any(len(d) > len(str(MAX_POSITIONS)) for d in digits):
        longest = max(len(d) for d in digits)
        raise LogError(
            f"wheel={_shown(spec)}: a number of {longest} digits; a wheel has 3 to {MAX_POSITIONS} tooth "
            "positions (e.g. 60-2)",
            argument="wheel",
        )
    n = int(m.group(1))
    gaps = tuple(int(g) for g in re.findall(r"\d+", m.group(2)))
    if not 3 <= n <= MAX_POSITIONS:
        raise LogError(
            f"wheel={_shown(spec)}: {n} teeth; need a whole number of tooth positions from 3 to {MAX_POSITIONS}",
            argument="wheel",
        )
    if any(g == 0 for g in gaps):
        raise LogError(
            f"wheel={_shown(spec)}: a gap of 0 missing teeth; give each gap 1 or more (e.g. 60-2, 36-2-1), "
            "or N alone for a wheel with an index",
            argument="wheel",
        )
    limit = n - 2 * max(len(gaps), 1)
    count = f"{len(gaps)} gaps" if len(gaps) > 1 else "1 gap"
    if len(gaps) > limit:
        raise LogError(
            f"wheel={_shown(spec)}: {count} need {3 * len(gaps)} positions or more (each gap a missing tooth and "
            f"a tooth on either side); the wheel has {n}",
            argument="wheel",
        )
    if sum(gaps) > limit:
        raise LogError(
            f"wheel={_shown(spec)}: {sum(gaps)} missing teeth in {count} on {n} positions; at most "
            f"{max(limit, 0)} fit (N − 2 × gaps: a tooth on either side of each gap)",
            argument="wheel",
        )
    try:
        return Wheel(n, sum(gaps), gaps)
    except LogError as e:
        raise LogError(f"wheel={_shown(spec)}: {e}", argument="wheel") from None


def read_wheel_file(path: str | os.PathLike) -> Wheel:
    """A :class:`Wheel` from a TOML file::

        positions = 36               # equally spaced tooth positions per revolution
        missing = [16, 17, 35]       # positions without a tooth (0 … positions−1, going round)
        angles_deg = [0.0, 10.02, …] # optional: the measured angle of each tooth [deg], in
                                     # position order from position 0 (the file's frame)

    Angle 0 is the first tooth after the longest gap (of equal ones, the first in position
    order); the measured angles are taken relative to their nominal places, so their frame
    does not matter. A malformed file raises :class:`LogError` naming the file and key.
    """
    import difflib
    import tomllib

    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path = {_shown(path)}: a wheel file's path (str or os.PathLike), not {type(path).__name__}")
    path = os.fspath(path)
    if os.path.isdir(path):
        raise LogError(f"{path}: is a folder, not a wheel file; give the .toml file inside it")
    if not os.path.isfile(path):
        raise LogError(f"{path}: No such wheel file")
    try:
        size = os.path.getsize(path)
        if size > MAX_WHEEL_FILE_BYTES:
            raise LogError(
                f"{path}: {size / 1e6:.3g} MB is far too large for a wheel file (at most "
                f"{MAX_WHEEL_FILE_BYTES / 1e6:g} MB): is it the wheel's TOML file?"
            )
        with open(path, "rb") as f:
            text = f.read().decode("utf-8-sig")  # a byte-order mark at the start is accepted
        if "\x00" in text:
            raise LogError(f"{path}: not a wheel file (it holds NUL bytes: a binary file?)")
        d = tomllib.loads(text)
    except UnicodeDecodeError as e:
        raise LogError(f"{path}: not a wheel file: byte {e.start} is not UTF-8 text (save the file as UTF-8)") from None
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise LogError(f"{path}: not a wheel file ({e})") from None
    for key in d:
        if key not in WHEEL_FILE_KEYS:
            close = difflib.get_close_matches(key, WHEEL_FILE_KEYS, n=1, cutoff=0.6)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise LogError(f"{path}: {key}: unknown key{hint}; known keys: {', '.join(WHEEL_FILE_KEYS)}")
    n = d.get("positions")
    if not isinstance(n, int) or isinstance(n, bool) or not 3 <= n <= MAX_POSITIONS:
        raise LogError(
            f"{path}: 'positions' must be a whole number of tooth positions from 3 to {MAX_POSITIONS}, not {_shown(n)}"
        )
    miss = d.get("missing", [])
    if not isinstance(miss, list) or not all(
        isinstance(x, int) and not isinstance(x, bool) and 0 <= x < n for x in miss
    ):
        raise LogError(f"{path}: 'missing' must be a list of positions 0 … {n - 1}, not {str(miss)[:40]!r}")
    twice = sorted(p for p, c in Counter(miss).items() if c > 1)
    if twice:
        raise LogError(f"{path}: 'missing' names position {twice[0]} twice; name each missing position once")
    present = np.ones(n, bool)
    present[miss] = False
    if not miss:
        return Wheel(n, 0)
    if present.sum() < 2:
        raise LogError(f"{path}: 'missing' leaves {int(present.sum())} teeth")
    # runs of missing positions going round, from the first tooth after a gap
    first_tooth = next(p for p in range(n) if present[p] and not present[p - 1])
    order = (first_tooth + np.arange(n)) % n
    pr = present[order]
    change = np.flatnonzero(np.diff(pr.astype(np.int8))) + 1
    bounds = np.concatenate([[0], change, [n]])
    runs = [(bool(pr[a]), int(b - a), int(order[a])) for a, b in zip(bounds[:-1], bounds[1:])]
    teeth_runs = [r for r in runs if r[0]]
    gap_runs = [r for r in runs if not r[0]]
    # teeth_runs[k] is followed by gap_runs[k]; gap 1 = the longest gap (first in position order)
    g1 = max(range(len(gap_runs)), key=lambda k: (gap_runs[k][1], -((gap_runs[k][2] - 1) % n)))
    k = np.roll(np.arange(len(gap_runs)), -g1)
    gaps = tuple(gap_runs[i][1] for i in k)
    layout = tuple(teeth_runs[(i + 1) % len(teeth_runs)][1] for i in k)
    tooth0 = teeth_runs[(g1 + 1) % len(teeth_runs)][2]
    rolled = None
    if d.get("angles_deg") is not None:
        a = d["angles_deg"]
        if (
            not isinstance(a, list)
            or len(a) != int(present.sum())
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in a)
        ):
            raise LogError(f"{path}: 'angles_deg' must be {int(present.sum())} numbers, one per tooth [deg]")
        pos = np.flatnonzero(present)
        err = np.asarray(a, dtype=np.float64) - pos * 360.0 / n
        rolled = np.roll(err, -int(np.searchsorted(pos, tooth0)))
    try:
        w0 = Wheel(n, sum(gaps), gaps, layout)
        if rolled is None:
            return w0
        return Wheel(n, sum(gaps), gaps, layout, tuple(w0.positions * 360.0 / n + rolled - rolled[0]))
    except LogError as e:
        raise LogError(f"{path}: {e}") from None


@dataclasses.dataclass(frozen=True)
class Repair:
    """One repair of the edges.

    **Attributes:** ``kind``: ``"glitch removed"``, ``"extra edge removed"``, ``"missed
    edge found"`` (measured in the signal at a lower level), ``"missed edge inferred"``
    (placed from the pattern, pro rata of the pitches), ``"edge dropped"``; ``time_s``
    [s]; ``revolution`` (as in :class:`rotor.logs.wheel.ToothTrack`, ``None`` if not
    placed); ``confidence``: how sure, 0 … 1 [-]; ``detail``: in words.
    """

    kind: str
    time_s: float
    revolution: int | None = None
    confidence: float = 1.0
    detail: str = ""

    def to_json_dict(self) -> dict:
        """Plain JSON: kind, time [s], revolution, confidence and detail."""
        return {
            "kind": self.kind,
            "time_s": float(self.time_s),
            "revolution": None if self.revolution is None else int(self.revolution),
            "confidence": round(float(self.confidence), 3),
            "detail": self.detail,
        }


def repairs_json(repairs, max_items: int = 200) -> dict:
    """The repairs as plain JSON: their count, the count of each kind, and the first
    ``max_items`` of them (``items_left_out`` says how many more)."""
    repairs = list(repairs)
    return {
        "count": len(repairs),
        "by_kind": dict(Counter(r.kind for r in repairs)),
        "items": [r.to_json_dict() for r in repairs[:max_items]],
        "items_left_out": max(len(repairs) - max_items, 0),
    }


def repairs_summary(repairs) -> str:
    """One line: how many of each kind, the least sure."""
    if not repairs:
        return "none"
    c = Counter(r.kind for r in repairs)
    low = min(repairs, key=lambda r: r.confidence)
    return (
        ", ".join(f"{k} × {v}" for k, v in c.items()) + f" (least sure {low.confidence:.2f} at t = {low.time_s:.6f} s)"
    )


@dataclasses.dataclass(frozen=True, eq=False)
class ToothTrack:
    """Tooth edges with their place on the wheel.

    **Attributes:** ``t`` [s]: edge times (with any edge inferred from the pattern);
    ``tooth``: the tooth (0 … N−M−1, 0 = the first edge after gap 1, see :class:`Wheel`);
    ``rev``: revolution (0 = the first with a reference edge in the log, −1 before it);
    ``wheel`` (with the places of its gaps as found); ``gap_ratio``: the median period
    ratio found on gap 1 (its missing teeth + 1 expected) and ``tooth_ratio_max``: the
    largest ratio on a regular tooth (1 expected); ``repairs``: what was done to the
    edges to make them follow the wheel (:class:`rotor.logs.wheel.Repair`: glitches
    and extra edges removed, missed edges found or inferred, edges dropped at the ends);
    ``placement``: where the timing alone fits several placements on the wheel alike (a
    tooth missed in every revolution next to a gap), how one was chosen, in words
    (empty otherwise).
    """

    t: np.ndarray
    tooth: np.ndarray
    rev: np.ndarray
    wheel: Wheel
    gap_ratio: float = float("nan")
    tooth_ratio_max: float = float("nan")
    repairs: tuple = ()
    placement: str = ""

    @property
    def nominal_angle(self) -> np.ndarray:
        """Nominal wheel angle of each edge [rad]."""
        return TWO_PI * self.rev + self.wheel.tooth_angles_rad[self.tooth]

    @property
    def revolutions(self) -> int:
        """Complete revolutions (from one reference edge to the next) in the log."""
        return int(np.count_nonzero(self.tooth == 0)) - 1

    def to_json_dict(self) -> dict:
        """Plain JSON: the wheel as found (teeth, edges, revolutions, the gap's period ratios,
        the repairs made to the edges)."""
        w = self.wheel
        if w.missing and len(w.gaps) == 1:
            where = (
                f"after tooth position {w.edges_per_rev - 1} (edges 0 … {w.edges_per_rev - 1} per revolution; "
                f"gap spans {w.missing + 1} pitches)"
            )
        elif w.missing:
            ends = np.cumsum(w.layout or ()) - 1
            where = (
                f"{w.describe()}; gaps after teeth {', '.join(str(int(e)) for e in ends)}; tooth 0 = the first "
                f"after gap 1 ({w.gaps[0]} missing)"
            )
        else:
            where = "index signal"
        return {
            "spec": w.spec,
            "teeth_per_rev": w.teeth,
            "missing_teeth": w.missing,
            "gaps": list(w.gaps),
            "teeth_between_gaps": None if w.layout is None else list(w.layout),
            "edges_per_rev": w.edges_per_rev,
            "edges": int(self.t.size),
            "complete_revolutions": self.revolutions,
            "gap_position": where,
            "first_reference_time_s": float(self.t[np.argmax(self.tooth == 0)]),
            "gap_period_ratio": _finite_or_none(self.gap_ratio),  # none for an index wheel
            "max_tooth_period_ratio": _finite_or_none(self.tooth_ratio_max),
            "repairs": repairs_json(self.repairs),
            "placement": self.placement or None,
        }


def _finite_or_none(x):
    x = float(x)
    return x if math.isfinite(x) else None


def period_ratios(dt: np.ndarray) -> np.ndarray:
    """Each tooth period [s] over the geometric mean of its two neighbours [-] (NaN at the ends)."""
    r = np.full(dt.size, np.nan)
    r[1:-1] = dt[1:-1] / np.sqrt(dt[:-2] * dt[2:])
    return r


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class ToothErrors(Result):
    """Angle errors of a wheel's teeth: tooth ``j`` sits at ``j·pitch + errors_rad[j]``.

    The errors have zero mean (the angle origin is the best-fit tooth grid).
    **Attributes:** ``wheel`` (spec string), ``errors_rad`` (N−M,) [rad], ``method``,
    ``revolutions`` (how many were averaged), ``engine_orders``: the orders left to the
    engine (removed from the estimate), ``standard_error_rad``: each tooth's standard
    error of the mean [rad], ``source``: where it was estimated, ``order_rms_rad``: the
    RMS amplitude of one order of the errors at the orders not left to the engine
    (single teeth far off the rest set aside) [rad]: what the wheel's uncorrected errors at
    the engine's orders are likely to be.
    """

    wheel: str
    errors_rad: np.ndarray
    method: str = "given"
    revolutions: int = 0
    engine_orders: tuple = ()
    standard_error_rad: np.ndarray | None = None
    source: str = ""
    order_rms_rad: float | None = None

    def __post_init__(self):
        w = parse_wheel(self.wheel)
        e = np.asarray(self.errors_rad, dtype=np.float64)
        if e.shape != (w.edges_per_rev,):
            raise LogError(f"tooth errors: {e.size} values for a {w.spec} wheel, which has {w.edges_per_rev} edges")
        if not np.all(np.isfinite(e)):
            raise LogError("tooth errors: not all finite")
        if np.max(np.abs(e)) >= 0.5 * w.pitch_rad:
            raise LogError(
                f"tooth errors up to {np.rad2deg(np.max(np.abs(e))):.3f}°: half a pitch or more; "
                f"not the errors of a {w.spec} wheel"
            )
        object.__setattr__(self, "wheel", w.spec)
        object.__setattr__(self, "errors_rad", e - e.mean())

    @property
    def errors_deg(self) -> np.ndarray:
        return np.rad2deg(self.errors_rad)

    @property
    def rms_rad(self) -> float:
        return float(np.sqrt(np.mean(self.errors_rad**2)))

    def angles(self, track: ToothTrack) -> np.ndarray:
        """Corrected wheel angle of each edge of ``track`` [rad]."""
        if parse_wheel(self.wheel) != track.wheel:
            raise LogError(f"tooth errors of a {self.wheel} wheel applied to a {track.wheel.spec} wheel")
        return track.nominal_angle + self.errors_rad[track.tooth]

    def to_json_dict(self) -> dict:
        """Plain JSON: the wheel, how the errors were found, their rms and largest [deg], each
        tooth's error [rad] (and standard error, if known); what :meth:`save` writes."""
        d = {
            "wheel": self.wheel,
            "method": self.method,
            "revolutions": int(self.revolutions),
            "engine_orders": [float(k) for k in self.engine_orders],
            "rms_deg": float(np.rad2deg(self.rms_rad)),
            "max_abs_deg": float(np.max(np.abs(self.errors_deg))),
            "errors_rad": [float(x) for x in self.errors_rad],
            "source": self.source,
        }
        if self.standard_error_rad is not None:
            d["standard_error_rad"] = [float(x) for x in self.standard_error_rad]
        if self.order_rms_rad is not None:
            d["order_rms_rad"] = float(self.order_rms_rad)
        return d

    def summary(self) -> str:
        """A few lines: the wheel, the method, the rms and largest error and the orders left
        to the engine."""
        lines = [
            f"tooth errors of a {self.wheel} wheel ({self.method}"
            + (f", {self.revolutions} revolution{'s' if self.revolutions != 1 else ''}" if self.revolutions else "")
            + (f", from {self.source}" if self.source else "")
            + ")",
            f"  rms {np.rad2deg(self.rms_rad):.4f}°, largest {np.max(np.abs(self.errors_deg)):.4f}° "
            f"(tooth {int(np.argmax(np.abs(self.errors_rad)))}, 0 = the first after the gap)",
        ]
        if self.engine_orders:
            lines.append(f"  orders left to the engine: {', '.join(f'{k:g}' for k in self.engine_orders)}")
        if self.order_rms_rad is not None:
            lines.append(f"  the wheel's likely error per order there: {np.rad2deg(self.order_rms_rad):.4f}° rms")
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """One row per tooth (0 = the first edge after the gap): ``tooth``, ``error_deg``,
        ``error_rad`` and, if known, ``standard_error_rad``."""
        import pandas as pd

        d = {
            "tooth": np.arange(self.errors_rad.size),
            "error_deg": self.errors_deg,
            "error_rad": self.errors_rad,
        }
        if self.standard_error_rad is not None:
            d["standard_error_rad"] = np.asarray(self.standard_error_rad, dtype=np.float64)
        return pd.DataFrame(d)

    def plot(self, ax: Any = None) -> Any:
        """Each tooth's error [deg] as a bar (:func:`rotor.plotting.logs.plot_tooth_errors`);
        returns the Axes."""
        from ..plotting.logs import plot_tooth_errors

        return plot_tooth_errors(self.errors_deg, self.method, ax=ax)

    def save(self, path: str | os.PathLike) -> None:
        """Write as JSON (whole or not at all) to ``path``, to reuse on other recordings of
        the same wheel."""
        save_json(path, self.to_json_dict(), what="the tooth errors", error=LogError)

    @classmethod
    def load(cls, path: str | os.PathLike) -> ToothErrors:
        """Read a file written by :meth:`save` from ``path``; a malformed file raises
        :class:`rotor.LogError` naming the file and the key."""
        path = os.fspath(path)
        if os.path.isdir(path):
            raise LogError(f"{path}: is a folder, not a tooth-error file")
        if not os.path.exists(path):
            raise LogError(f"{path}: No such file or directory (no tooth-error file there)")
        d = load_json(path, what="a tooth-error file", error=LogError)
        if not isinstance(d, dict) or "wheel" not in d or "errors_rad" not in d:
            raise LogError(f"{path}: not a tooth-error file (needs 'wheel' and 'errors_rad')")

        def numbers(key, shape=None):
            v = d.get(key)
            try:
                a = np.asarray(v, dtype=np.float64)
            except (TypeError, ValueError):
                a = None
            if a is None or a.ndim != 1 or not np.all(np.isfinite(a)):
                raise LogError(f"{path}: '{key}' must be a list of finite numbers, not {str(v)[:40]!r}")
            if shape is not None and a.shape != shape:
                raise LogError(f"{path}: '{key}' has {a.size} values, 'errors_rad' {shape[0]}")
            return a

        try:
            wheel = parse_wheel(d["wheel"])
        except (LogError, TypeError) as e:
            raise LogError(f"{path}: 'wheel': {e}") from None
        errors = numbers("errors_rad")
        if errors.size != wheel.edges_per_rev:
            raise LogError(
                f"{path}: 'errors_rad' has {errors.size} values; a {wheel.spec} wheel has {wheel.edges_per_rev} edges"
            )
        se = None if d.get("standard_error_rad") is None else numbers("standard_error_rad", errors.shape)
        orders = numbers("engine_orders") if d.get("engine_orders") else np.zeros(0)
        if np.any(orders != np.round(orders)):
            raise LogError(f"{path}: 'engine_orders' must be whole orders")
        rv = d.get("revolutions", 0)
        if not isinstance(rv, (int, float)) or isinstance(rv, bool) or rv < 0 or rv != int(rv):
            raise LogError(f"{path}: 'revolutions' must be a whole number, not {rv!r}")
        orms = d.get("order_rms_rad")
        if orms is not None and not (isinstance(orms, (int, float)) and math.isfinite(orms) and orms >= 0):
            raise LogError(f"{path}: 'order_rms_rad' must be a number ≥ 0, not {orms!r}")
        try:
            return cls(
                wheel.spec,
                errors,
                str(d.get("method", "given")),
                int(rv),
                tuple(int(k) for k in orders),
                se,
                str(d.get("source", path)),
                None if orms is None else float(orms),
            )
        except LogError as e:
            raise LogError(f"{path}: {e}") from None


def order_fit_matrix(phi: ArrayLike, orders: Sequence[float]) -> np.ndarray:
    """The least-squares design matrix of a constant and a cosine and sine of each order
    at the angles ``phi`` [rad]: (len(phi), 1 + 2·len(orders))."""
    phi = np.asarray(phi, dtype=np.float64)
    cols = [np.ones_like(phi)]
    for k in orders:
        cols += [np.cos(k * phi), np.sin(k * phi)]
    return np.stack(cols, axis=1)


FIT_MATRIX_CELLS = 4_000_000
"""The largest design matrix of the engine's orders fitted directly [cells]; a larger fit (a
wheel of thousands of teeth) runs matrix-free by FFTs (:func:`_fitted_orders`)."""


def _fitted_orders(phi: np.ndarray, a: np.ndarray, clean: np.ndarray, keep: Sequence[int], teeth: int) -> np.ndarray:
    """The least-squares fit of a constant and the orders ``keep`` to ``a`` at the teeth
    ``clean`` (angles ``phi`` [rad] on the wheel's grid of ``teeth`` positions), evaluated
    at every tooth. Directly where the design matrix is small; else by LSQR with the
    matrix applied by FFTs over the grid (the same minimum to the solver's tolerance)."""
    cols = 1 + 2 * len(keep)
    if phi.size * cols <= FIT_MATRIX_CELLS:
        X = order_fit_matrix(phi, keep)
        beta, *_ = np.linalg.lstsq(X[clean], a[clean], rcond=None)
        return X @ beta
    from scipy.sparse.linalg import LinearOperator, lsqr

    pos = np.round(phi * teeth / TWO_PI).astype(np.int64) % teeth
    ks = np.asarray(keep, dtype=np.int64)
    used = pos[clean]

    def on_grid(beta: np.ndarray) -> np.ndarray:
        z = np.zeros(teeth, complex)
        z[0] = beta[0]
        z[ks] = 0.5 * (beta[1::2] - 1j * beta[2::2])
        z[(-ks) % teeth] += np.conj(z[ks])
        return np.fft.ifft(z).real * teeth

    def matvec(beta):
        return on_grid(np.ravel(beta))[used]

    def rmatvec(y):
        g = np.zeros(teeth)
        g[used] = np.ravel(y)
        f = np.fft.fft(g)
        out = np.empty(cols)
        out[0] = f[0].real
        out[1::2] = f[ks].real
        out[2::2] = -f[ks].imag
        return out

    op = LinearOperator((used.size, cols), matvec=matvec, rmatvec=rmatvec, dtype=np.float64)
    beta = lsqr(op, a[clean], atol=1e-14, btol=1e-14, iter_lim=500)[0]
    return on_grid(beta)[pos]


def _order_amplitudes(phi, values, kmax):
    """(orders 1 … kmax, amplitude of each) of values at angles phi [rad], each order fitted
    alone by least squares (a cosine and a sine). Where the angles sit on a grid of
    2π/(2·kmax + 2) or finer (a wheel's tooth positions), the sums of the normal equations
    come from FFTs of the grid, in O(N log N) for any number of orders; else order by order."""
    orders = np.arange(1, kmax + 1)
    phi = np.asarray(phi, dtype=np.float64)
    x = values - values.mean()
    n = max(2 * kmax + 2, 4)
    for grid in (n, n + 1):
        pos = phi * grid / TWO_PI
        k = np.round(pos).astype(np.int64)
        if np.allclose(pos, k, atol=1e-9) and np.unique(k % grid).size == k.size:
            break
    else:
        grid = 0
    if grid:
        m = np.zeros(grid)
        y = np.zeros(grid)
        m[k % grid] = 1.0
        y[k % grid] = x
        Fm = np.fft.fft(m)
        Fy = np.fft.fft(y)
        c2 = Fm[(2 * orders) % grid]
        cc = 0.5 * (k.size + c2.real)  # Σ cos²
        ss = 0.5 * (k.size - c2.real)  # Σ sin²
        cs = -0.5 * c2.imag  # Σ cos·sin
        yc, ys = Fy[orders].real, -Fy[orders].imag
        det = cc * ss - cs * cs
        with np.errstate(invalid="ignore", divide="ignore"):
            a = (ss * yc - cs * ys) / det
            b = (cc * ys - cs * yc) / det
        ok = det > 1e-9 * k.size**2
        amp = np.where(ok, np.hypot(a, b), 0.0)
        return orders, amp
    amp = np.empty(orders.size)
    for i, kk in enumerate(orders):
        A = np.stack([np.cos(kk * phi), np.sin(kk * phi)], axis=1)
        c, *_ = np.linalg.lstsq(A, x, rcond=None)
        amp[i] = np.hypot(*c)
    return orders, amp


def firing_orders(cylinders: int, strokes: int, teeth: int) -> tuple:
    """The whole orders of the per-revolution pattern below ``teeth/2`` that an evenly
    firing engine of ``cylinders`` cylinders excites: the multiples of its firing order
    (cylinders/2 per revolution for a four-stroke, ``cylinders`` for a two-stroke) that
    are whole. Empty where every whole order is one (a single-cylinder four-stroke, a
    twin four-stroke, a single-cylinder two-stroke): the engine's band is then found from
    the data (``engine_orders="auto"``)."""
    if not (isinstance(cylinders, (int, np.integer)) and not isinstance(cylinders, bool) and cylinders >= 1):
        raise LogError(f"cylinders = {cylinders!r}: a whole number, 1 or more")
    step = int(cylinders) if strokes == 2 else (int(cylinders) // 2 if cylinders % 2 == 0 else int(cylinders))
    if step <= 1:
        return ()
    return tuple(range(step, (teeth + 1) // 2, step))


def _inertia_ripple(wheel, engine, tdc_deg):
    """Each edge's angle deviation [rad] (mean zero) that the engine's varying reduced
    inertia makes at constant kinetic energy, ω ∝ I(θ)^(-1/2), as the tooth-error estimate
    measures it (against a uniform time-to-angle map over the revolution); edge 0 is the
    first after the gap, cylinder 1's TDC ``tdc_deg`` after it."""
    from ..engine.inertia import reduced_inertia

    fine = np.linspace(0.0, TWO_PI, 2881)
    root = np.sqrt(np.asarray(reduced_inertia(engine, fine - math.radians(tdc_deg))))
    T = np.concatenate([[0.0], np.cumsum(0.5 * (root[1:] + root[:-1]) * np.diff(fine))])  # ∝ time at constant E
    nominal = wheel.tooth_angles_rad
    d = TWO_PI * np.interp(nominal, fine, T) / T[-1] - nominal
    return d - d.mean()


def estimate_tooth_errors(
    track: ToothTrack,
    *,
    engine_orders: str | Sequence[int] = "auto",
    strokes: int = 4,
    cylinders: int = 1,
    coastdown_ratio: float = 1.5,
    source: str = "",
    engine: Engine | None = None,
    tdc_deg: float | None = None,
) -> ToothErrors:
    """Tooth-spacing errors of the wheel, from the log itself.

    **Arguments:**
    - ``track``: the edges on the wheel (:func:`locate_teeth`).
    - ``engine_orders``: the integer orders of the per-revolution pattern to leave to the
      engine (removed from the estimate): ``"auto"`` (those that stand out, see the
      module notes; with ``cylinders`` > 1, every whole multiple of the firing order as
      well, see :func:`firing_orders`), a list of orders, or ``()`` (none: a calibration
      run whose speed has no fluctuation locked to the crank).
    - ``cylinders``: of an evenly firing engine; 1 (default) for a single cylinder.
    - ``strokes``: 4 averages an even number of revolutions, so the half orders cancel.
    - ``coastdown_ratio``: if the fastest revolution is this much faster than the
      slowest, each tooth's error is regressed on (ω̄/ω)² (the gas and friction torque
      part of the fluctuation scales so) instead of averaged.
    - ``engine``, ``tdc_deg``: the :class:`rotor.Engine` on the wheel and the angle from
      the first edge after the gap to cylinder 1's TDC [deg]: the speed ripple of its
      varying reduced inertia I(θ) (reciprocating masses), which does not die with speed
      and would otherwise be taken for the wheel's, is removed first. This makes the
      engine's own fuel-cut coast-down a wheel calibration (4chn15: 0.29° wrong without,
      0.01° with; ``tests/logs/test_wheel_inertia.py``).

    **Returns:** :class:`ToothErrors`.
    """
    from scipy.interpolate import CubicSpline

    w = track.wheel
    E = w.edges_per_rev
    ref = np.flatnonzero(track.tooth == 0)
    R = ref.size - 1
    if strokes == 4 and R % 2:
        R -= 1
    if R < 2:
        raise LogError(
            f"tooth errors: {max(R, 0)} complete revolution{'s' if R != 1 else ''}; need 2 or more to estimate them"
        )
    ref = ref[: R + 1]
    t0 = track.t[ref]
    theta = CubicSpline(t0, TWO_PI * track.rev[ref], bc_type="not-a-knot")
    sel = slice(ref[0], ref[-1])  # all edges of revolutions 0 … R−1
    tt, tooth, rev = track.t[sel], track.tooth[sel], track.rev[sel]
    if tt.size != R * E:
        raise LogError("tooth errors: the revolutions are not complete")  # locate_teeth guarantees it
    d = (theta(tt) - TWO_PI * rev - w.tooth_angles_rad[tooth]).reshape(R, E)
    if engine is not None:
        if tdc_deg is None or not math.isfinite(float(tdc_deg)):
            raise LogError(
                "tooth errors with an engine's inertia ripple removed need tdc_deg: the angle from the "
                "first edge after the gap to cylinder 1's TDC [deg]"
            )
        d = d - _inertia_ripple(w, engine, float(tdc_deg))[None, :]
    omega = TWO_PI / np.diff(t0)
    method = "revolution average"
    if omega.max() > coastdown_ratio * omega.min() and R >= 8:
        x = (np.mean(omega) / omega) ** 2
        X = np.stack([np.ones(R), x], axis=1)
        coef, *_ = np.linalg.lstsq(X, d, rcond=None)
        a = coef[0]  # the speed-independent part: (ω̄/ω)² → 0 leaves no torque-driven fluctuation
        resid = d - X @ coef
        se = np.sqrt(np.sum(resid**2, axis=0) / max(R - 2, 1) / R)
        method = (
            f"coast-down regression on (ω̄/ω)², {omega.min() * RPM_PER_RAD_S:.0f}–{omega.max() * RPM_PER_RAD_S:.0f} rpm"
        )
    else:
        a = d.mean(axis=0)
        se = d.std(axis=0, ddof=1) / np.sqrt(R) if R > 1 else np.zeros(E)
    if engine is not None:
        method += f", {engine.name}'s inertia ripple removed (TDC {tdc_deg:g}° after the gap)"
    a = a - a.mean()
    # single teeth far off the rest (e.g. the edges that border the gap) are the wheel's;
    # they are left out of the order analysis, so their broad spectrum does not mask the engine's
    # (against a running median over 7 teeth around the wheel, which the engine's smooth part passes)
    local = np.median(np.stack([np.roll(a, s) for s in range(-3, 4)]), axis=0)
    dev = a - local
    mad = 1.4826 * np.median(np.abs(dev))
    worst = np.argsort(-np.abs(dev))[: max(2, E // 20)]  # at most 5 % of the teeth
    clean = np.ones(E, bool)
    clean[worst[np.abs(dev[worst]) > 6 * mad]] = False
    phi = w.tooth_angles_rad
    if isinstance(engine_orders, str):
        if engine_orders != "auto":
            raise LogError(f"engine_orders = {engine_orders!r}: 'auto', a list of orders, or ()")
        orders, amp = _order_amplitudes(phi[clean], a[clean], w.teeth // 2 - 1)
        upper = amp[orders > orders.max() / 2]
        floor = float(np.median(upper))
        loud = orders[(orders <= orders.max() / 2) & (amp > ENGINE_ORDER_FACTOR * floor)]
        keep = tuple(range(1, int(loud.max()) + 1)) if loud.size else ()  # the engine's band, 1 … highest loud order
        # an evenly firing multi-cylinder engine: its fluctuation at the multiples of the firing order can
        # be as small as the wheel's errors there, so the detection above cannot be trusted to see it
        keep = tuple(sorted(set(keep) | set(firing_orders(cylinders, strokes, w.teeth))))
        if len(keep) > (int(np.count_nonzero(clean)) - 1) // 2 - 2:
            which = f"the engine's orders {keep[0]} … {keep[-1]} leave" if keep else "the wheel has"
            raise TooFewOrders(
                f"tooth errors: {which} too few orders to estimate from {E} teeth; give a calibration "
                f"(tooth_errors=FILE), engine_orders, or tooth_errors=None"
            )
    else:
        keep = tuple(int(k) for k in engine_orders)
        if any(k < 1 or k >= w.teeth // 2 for k in keep):
            raise LogError(f"engine_orders = {engine_orders!r}: whole orders from 1 to {w.teeth // 2 - 1}")
    e = a - _fitted_orders(phi, a, clean, keep, w.teeth)
    # the wheel's errors per order at the orders estimated (flat for independent tooth errors): what the
    # orders left to the engine probably hold of the wheel's
    free = max((int(np.count_nonzero(clean)) - (1 + 2 * len(keep))) / 2, 1.0)
    order_rms = float(np.sqrt(2 * np.mean(e[clean] ** 2) / free))
    return ToothErrors(w.spec, e, method, R, keep, se, source, order_rms)
