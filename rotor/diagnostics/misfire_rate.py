"""Misfire rates over windows of revolutions, and the OBD codes they set.

The on-board misfire monitors of the regulations judge a **rate**, not single firings:
California's OBD II regulation (title 13, California Code of Regulations, §1968.2(e)(3))
asks for the misfire percentage that damages the catalyst, evaluated over 200-revolution
increments and set by the manufacturer for each speed and load, and the percentage that
raises the emissions past their limit, evaluated over 1000-revolution increments (about
1 % of the firings for many engines). The monitor identifies the misfiring cylinder, and
stores a separate multiple-cylinder code where more than one cylinder misfires (SAE J2012
numbers them: P0301 … P0312 for cylinders 1 … 12, P0300 random or multiple cylinders).

:class:`WindowCounter` counts each cylinder's misfires over the last ``W`` revolutions of
judged firings (``W·2n/strokes`` firings of an n-cylinder engine) for two windows, the
catalyst's (:data:`CATALYST_REVOLUTIONS`) and the emission's
(:data:`EMISSION_REVOLUTIONS`), and judges both every ``step_revolutions`` (default 200:
the catalyst's windows are then consecutive increments, the emission's slide over the last
1000 revolutions by 200 at a time; a step equal to a window gives that window's consecutive
increments). A window is **exceeded** where its rate (misfires over firings judged, in
percent) reaches its threshold (the regulation's monitor detects the rate at which the
catalyst is damaged or the emissions pass their limit): for the catalyst, the table of :class:`CatalystTable` at
the window's mean speed and load (its lowest rate over the loads at that speed where the
load is not known: without an engine file), for the emission a fixed rate. An exceeded
window carries a **code** (:func:`misfire_code`): a cylinder counts as misfiring where it
holds at least ``min_share`` (default 10 %) of the window's misfires; one such cylinder
gives its own code, two or more P0300.

**Short recordings.** At the end of the stream a window that never filled (a recording
shorter than it) is judged over the firings there are, and says so (``partial``, its
``revolutions`` below its ``window_revolutions``); the revolutions after the last judged
window are judged in one more window over the last ``W`` revolutions. A rate over fewer
revolutions is a coarser estimate: 2 misfires in 160 revolutions of a four-cylinder are
0.6 %, 1 in 50 revolutions 1 %.

The default catalyst table (:data:`DEFAULT_CATALYST_TABLE`) is an example of the shape
such a table takes (higher rates at low speed and load, where the unburnt mixture heats the
catalyst least), not an engine's calibration: an engine's own comes from its catalyst's
temperature tests.

**Memory**: the firings of the longer window (a V8's 1000 revolutions: 4000 firings) in
rings of fixed size allocated at the start (about 30 bytes a firing), the exceeded windows at
most :data:`MAX_EXCEEDED`.
"""

from __future__ import annotations

import collections
import dataclasses
import enum
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import EngineError

__all__ = [
    "CATALYST_REVOLUTIONS",
    "DEFAULT_CATALYST_TABLE",
    "EMISSION_RATE_PCT",
    "EMISSION_REVOLUTIONS",
    "MAX_EXCEEDED",
    "MIN_SHARE",
    "STEP_REVOLUTIONS",
    "CatalystTable",
    "MisfireThresholds",
    "MisfireWindow",
    "WindowCounter",
    "WindowKind",
    "misfire_code",
]

CATALYST_REVOLUTIONS = 200
"""Revolutions of the catalyst-damage window (§1968.2(e)(3): 200-revolution increments)."""
EMISSION_REVOLUTIONS = 1000
"""Revolutions of the emission window (§1968.2(e)(3): 1000-revolution increments)."""
STEP_REVOLUTIONS = 200
"""Revolutions between two judgements of the windows."""
EMISSION_RATE_PCT = 1.0
"""The emission threshold: misfires in percent of the firings over an emission window."""
MIN_SHARE = 0.1
"""A cylinder counts as misfiring in a window where it holds at least this share of its misfires."""
MAX_EXCEEDED = 1000
"""Exceeded windows kept for the summary (the oldest dropped beyond this; each is handed out as it comes)."""
MAX_CYLINDER_CODE = 12
"""The highest cylinder with a code of its own (SAE J2012: P0301 … P0312)."""


class WindowKind(enum.Enum):
    """Which threshold a :class:`MisfireWindow` is judged against."""

    CATALYST = "catalyst"  # the catalyst-damage rate, a table over speed and load
    EMISSION = "emission"  # the emission rate, one number


@dataclasses.dataclass(frozen=True)
class CatalystTable:
    """The catalyst-damage misfire rate [% of the firings] over speed and load:
    ``rate_pct[i][j]`` at ``rpm[i]`` [rev/min] and ``load[j]`` [-, 0 … 1 of full load],
    read bilinearly between the nodes and held at the nearest edge beyond them."""

    rpm: tuple[float, ...]
    load: tuple[float, ...]
    rate_pct: tuple[tuple[float, ...], ...]

    def __post_init__(self) -> None:
        try:
            rpm = np.asarray(self.rpm, dtype=np.float64)
            load = np.asarray(self.load, dtype=np.float64)
        except (TypeError, ValueError):
            raise EngineError("catalyst table: rpm and load must be lists of numbers") from None
        try:
            rate = np.asarray(self.rate_pct, dtype=np.float64)
        except (TypeError, ValueError):
            raise EngineError("catalyst table: rate_pct must be a table of numbers, one row per speed") from None
        for name, x in (("rpm", rpm), ("load", load)):
            if x.ndim != 1 or x.size == 0 or not np.isfinite(x).all() or (np.diff(x) <= 0).any():
                raise EngineError(f"catalyst table: {name} = {list(np.ravel(x))!r}: increasing finite numbers")
        if rate.shape != (rpm.size, load.size):
            raise EngineError(
                f"catalyst table: rate_pct has shape {rate.shape}, where {rpm.size} speeds × {load.size} loads "
                f"give ({rpm.size}, {load.size})"
            )
        if not (np.isfinite(rate).all() and (rate > 0).all() and (rate <= 100).all()):
            raise EngineError("catalyst table: every rate_pct a percentage of the firings, above 0 and up to 100")
        object.__setattr__(self, "rpm", tuple(float(x) for x in rpm))
        object.__setattr__(self, "load", tuple(float(x) for x in load))
        object.__setattr__(self, "rate_pct", tuple(tuple(float(x) for x in row) for row in rate))

    def rate_at(self, rpm: float, load: float | None) -> float:
        """The rate [%] at ``rpm`` [rev/min] and ``load`` [-]; with ``load`` None (not known)
        the lowest over the loads at that speed."""
        rate = np.asarray(self.rate_pct)
        by_speed = np.array([np.interp(rpm, self.rpm, rate[:, j]) for j in range(len(self.load))])
        if load is None or not math.isfinite(load):
            return float(by_speed.min())
        return float(np.interp(load, self.load, by_speed))

    @classmethod
    def from_dict(cls, d: dict) -> CatalystTable:
        """From ``{"rpm": [...], "load": [...], "rate_pct": [[...], ...]}`` (a JSON file's content)."""
        if not isinstance(d, dict) or set(d) != {"rpm", "load", "rate_pct"}:
            got = sorted(d) if isinstance(d, dict) else type(d).__name__
            raise EngineError(f"catalyst table: the keys rpm, load and rate_pct, not {got}")
        try:
            return cls(tuple(d["rpm"]), tuple(d["load"]), tuple(tuple(row) for row in d["rate_pct"]))
        except TypeError:
            raise EngineError("catalyst table: rpm and load lists of numbers, rate_pct a list of rows") from None

    def to_json_dict(self) -> dict:
        return {"rpm": list(self.rpm), "load": list(self.load), "rate_pct": [list(r) for r in self.rate_pct]}


DEFAULT_CATALYST_TABLE = CatalystTable(
    rpm=(800.0, 2000.0, 4000.0, 6000.0),
    load=(0.0, 0.5, 1.0),
    rate_pct=((25.0, 20.0, 15.0), (20.0, 15.0, 10.0), (15.0, 10.0, 6.0), (10.0, 6.0, 4.0)),
)
"""An example table (see the module doc): not an engine's calibration."""


@dataclasses.dataclass(frozen=True)
class MisfireThresholds:
    """The windows and their thresholds: ``catalyst`` (a :class:`CatalystTable`) over
    ``catalyst_revolutions``, ``emission_pct`` [% of the firings] over
    ``emission_revolutions``, both judged every ``step_revolutions``; ``min_share`` [-]:
    a cylinder's share of a window's misfires from which it counts as misfiring."""

    catalyst: CatalystTable = DEFAULT_CATALYST_TABLE
    emission_pct: float = EMISSION_RATE_PCT
    catalyst_revolutions: int = CATALYST_REVOLUTIONS
    emission_revolutions: int = EMISSION_REVOLUTIONS
    step_revolutions: int = STEP_REVOLUTIONS
    min_share: float = MIN_SHARE

    def __post_init__(self) -> None:
        if not isinstance(self.catalyst, CatalystTable):
            raise EngineError(f"catalyst = {self.catalyst!r}: a CatalystTable")
        for name in ("catalyst_revolutions", "emission_revolutions", "step_revolutions"):
            v = getattr(self, name)
            if not (isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= 1):
                raise EngineError(f"{name} = {v!r}: a whole number of revolutions, 1 or more")
        if not (isinstance(self.emission_pct, (int, float)) and 0 < self.emission_pct <= 100):
            raise EngineError(
                f"emission_pct = {self.emission_pct!r}: a percentage of the firings, above 0 and up to 100"
            )
        if not (isinstance(self.min_share, (int, float)) and 0 < self.min_share <= 0.5):
            raise EngineError(f"min_share = {self.min_share!r}: a share of a window's misfires, above 0 and up to 0.5")

    def to_json_dict(self) -> dict:
        return {
            "catalyst_revolutions": int(self.catalyst_revolutions),
            "emission_revolutions": int(self.emission_revolutions),
            "step_revolutions": int(self.step_revolutions),
            "emission_pct": float(self.emission_pct),
            "catalyst_table": self.catalyst.to_json_dict(),
            "min_share": float(self.min_share),
        }


def misfire_code(per_cylinder: Sequence[int], min_share: float = MIN_SHARE) -> tuple[str | None, tuple[int, ...]]:
    """The code of a window's misfires ``per_cylinder`` (counts, cylinder 1 first) and the
    cylinders counted as misfiring (from 1; those with at least ``min_share`` of the
    misfires): one cylinder's code (P0301 …, up to :data:`MAX_CYLINDER_CODE`), P0300 for two
    or more (or for one above cylinder 12); (None, ()) without a misfire."""
    total = sum(per_cylinder)
    if total <= 0:
        return None, ()
    cyls = tuple(c + 1 for c, m in enumerate(per_cylinder) if m > 0 and m >= min_share * total)
    if len(cyls) == 1 and cyls[0] <= MAX_CYLINDER_CODE:
        return f"P03{cyls[0]:02d}", cyls
    return "P0300", cyls


@dataclasses.dataclass(frozen=True)
class MisfireWindow:
    """One window judged: ``kind``; ``window_revolutions`` (its length) and ``revolutions``
    (the judged firings it holds, in revolutions: fewer where ``partial``, a recording
    shorter than the window); ``firings``, ``misfires`` and ``per_cylinder`` (misfires of
    cylinder 1, 2, …); ``rate_pct`` and ``threshold_pct`` [% of the firings];
    ``exceeded``; ``code`` (where exceeded, :func:`misfire_code`) and ``cylinders`` (those
    counted as misfiring, from 1); ``first`` and ``last`` (cycle, cylinder) of its firings;
    ``end_s``: the log time at which its last firing's cycle ends [s]; ``mean_rpm``
    [rev/min] and ``load`` [-] (the model's mean IMEP of its fired firings over the engine
    file's full IMEP; None without an engine) at which the threshold was read."""

    kind: WindowKind
    window_revolutions: int
    revolutions: float
    firings: int
    misfires: int
    per_cylinder: tuple[int, ...]
    rate_pct: float
    threshold_pct: float
    exceeded: bool
    code: str | None
    cylinders: tuple[int, ...]
    first: tuple[int, int]
    last: tuple[int, int]
    end_s: float
    mean_rpm: float
    load: float | None
    partial: bool = False

    def to_json_dict(self) -> dict:
        return {
            "kind": self.kind.value,
            "window_revolutions": self.window_revolutions,
            "revolutions": round(self.revolutions, 3),
            "partial": self.partial,
            "firings": self.firings,
            "misfires": self.misfires,
            "per_cylinder": list(self.per_cylinder),
            "rate_pct": self.rate_pct,
            "threshold_pct": self.threshold_pct,
            "exceeded": self.exceeded,
            "code": self.code,
            "cylinders": list(self.cylinders),
            "first": list(self.first),
            "last": list(self.last),
            "end_s": self.end_s if math.isfinite(self.end_s) else None,
            "mean_rpm": self.mean_rpm if math.isfinite(self.mean_rpm) else None,
            "load": self.load,
        }

    def line(self) -> str:
        """One line for people."""
        where = f"{self.mean_rpm:.0f} rpm" if math.isfinite(self.mean_rpm) else "speed not known"
        where += f", load {self.load:.2f}" if self.load is not None else ", load not known"
        span = (
            f"{self.revolutions:.0f} of {self.window_revolutions} revolutions: the recording is shorter than the "
            "window, judged over what it has"
            if self.partial
            else f"{self.window_revolutions} revolutions"
        )
        verdict = f"EXCEEDED {self.code}" if self.exceeded else "within"
        cyl = f" (cylinders {','.join(map(str, self.cylinders))})" if self.cylinders else ""
        return (
            f"window {self.kind.value:8s} cycles {self.first[0]}–{self.last[0]} ({span}; {where}): "
            f"{self.misfires} misfire(s) in {self.firings} firings, {self.rate_pct:.2f} % against "
            f"{self.threshold_pct:.2f} %: {verdict}{cyl}"
        )


class _Window:
    __slots__ = ("kind", "revolutions", "size", "judged_full", "at")

    def __init__(self, kind: WindowKind, revolutions: int, size: int) -> None:
        self.kind, self.revolutions, self.size = kind, revolutions, size
        self.judged_full = False  # a full window has been judged
        self.at = 0  # the firings counted when it was last judged


class WindowCounter:
    """Misfire counts over the windows of ``thresholds`` (:class:`MisfireThresholds`) for
    an engine of ``cylinders`` cylinders and ``strokes`` strokes; ``full_imep_pa``: its
    full-load IMEP [Pa] (the load of a window is the mean IMEP of its fired firings over
    it; None: the load not known). :meth:`add` takes each judged firing in firing order and
    returns the windows judged with it; :meth:`close` the last ones (see the module doc).
    The firings are kept in rings of fixed size, allocated at the start (the longer
    window's firings): the memory does not grow as the stream goes on."""

    def __init__(
        self,
        cylinders: int,
        strokes: int,
        thresholds: MisfireThresholds | None = None,
        full_imep_pa: float | None = None,
    ) -> None:
        from array import array

        self.thresholds = MisfireThresholds() if thresholds is None else thresholds
        if not isinstance(self.thresholds, MisfireThresholds):
            raise EngineError(f"thresholds = {thresholds!r}: a MisfireThresholds")
        self.cylinders = int(cylinders)
        self.firings_per_rev = 2.0 * self.cylinders / int(strokes)
        self.revs_per_cycle = int(strokes) / 2
        self.full_imep_pa = full_imep_pa if full_imep_pa is not None and full_imep_pa > 0 else None
        th = self.thresholds
        self._windows = [
            _Window(kind, revs, max(1, round(revs * self.firings_per_rev)))
            for kind, revs in (
                (WindowKind.CATALYST, th.catalyst_revolutions),
                (WindowKind.EMISSION, th.emission_revolutions),
            )
        ]
        size = max(w.size for w in self._windows)
        self._size = size
        # each firing: the misfiring cylinder (from 0) or -1, its cycle, cylinder, cycle end
        # [s] and IMEP [Pa] (NaN for a misfire or where not known); -2: no firing yet
        self._fired = array("b", [-2]) * size
        self._cycle = array("q", [0]) * size
        self._cyl = array("b", [0]) * size if self.cylinders < 128 else array("q", [0]) * size
        self._end = array("d", [math.nan]) * size
        self._imep = array("d", [math.nan]) * size
        self._step = max(1, round(th.step_revolutions * self.firings_per_rev))
        self._count = 0
        self.judged: collections.Counter = collections.Counter()  # windows judged, per kind
        self.exceeded: collections.deque = collections.deque(maxlen=MAX_EXCEEDED)
        self.exceeded_count: collections.Counter = collections.Counter()

    def add(self, cycle: int, cylinder: int, misfire: bool, cycle_end_s: float, imep_pa: float) -> list[MisfireWindow]:
        """One judged firing (``cylinder`` from 1; ``cycle_end_s`` [s]; ``imep_pa`` [Pa], NaN
        where not known); the windows judged with it."""
        i = self._count % self._size
        self._fired[i] = cylinder - 1 if misfire else -1
        self._cycle[i] = cycle
        self._cyl[i] = cylinder
        self._end[i] = cycle_end_s
        self._imep[i] = math.nan if misfire else imep_pa
        self._count += 1
        if self._count % self._step:
            return []
        return [self._judge(w, partial=False) for w in self._windows if self._count >= w.size]

    def close(self) -> list[MisfireWindow]:
        """The windows that never filled, over what there is (``partial``), and a last full
        window over the revolutions judged since the last one."""
        out = []
        for w in self._windows:
            if not self._count:
                continue
            if self._count < w.size and not w.judged_full:
                out.append(self._judge(w, partial=True))
            elif self._count > w.at:
                out.append(self._judge(w, partial=False))
        return out

    def _last(self, ring: Any, m: int) -> Any:
        """The last ``m`` values of a ring, oldest first (an array of its type: a few bytes a value)."""
        end = self._count % self._size
        if m <= end:
            return ring[end - m : end]
        return ring[self._size - (m - end) :] + ring[:end]

    def _judge(self, w: _Window, partial: bool) -> MisfireWindow:
        n = min(self._count, w.size)
        fired = self._last(self._fired, n)
        per = tuple(fired.count(c) for c in range(self.cylinders))
        mis = sum(per)
        first, last = (self._count - n) % self._size, (self._count - 1) % self._size
        k0, c0, e0 = self._cycle[first], self._cyl[first], self._end[first]
        k1, c1, e1 = self._cycle[last], self._cyl[last], self._end[last]
        revs = (k1 - k0) * self.revs_per_cycle
        rpm = 60.0 * revs / (e1 - e0) if revs > 0 and e1 > e0 else math.nan
        load = None
        if self.full_imep_pa is not None:
            x = np.frombuffer(self._last(self._imep, n), dtype=np.float64)
            x = x[np.isfinite(x)]
            if x.size:
                load = round(max(float(x.mean()) / self.full_imep_pa, 0.0), 4)
        th = self.thresholds
        if w.kind is WindowKind.CATALYST:
            limit = th.catalyst.rate_at(rpm, load) if math.isfinite(rpm) else min(min(r) for r in th.catalyst.rate_pct)
        else:
            limit = float(th.emission_pct)
        rate = 100.0 * mis / n
        exceeded = rate >= limit
        code, cyls = misfire_code(per, th.min_share)
        window = MisfireWindow(
            kind=w.kind,
            window_revolutions=w.revolutions,
            revolutions=n / self.firings_per_rev,
            firings=n,
            misfires=mis,
            per_cylinder=per,
            rate_pct=round(rate, 4),
            threshold_pct=round(limit, 4),
            exceeded=exceeded,
            code=code if exceeded else None,
            cylinders=cyls,
            first=(int(k0), int(c0)),
            last=(int(k1), int(c1)),
            end_s=float(e1),
            mean_rpm=float(rpm),
            load=load,
            partial=partial,
        )
        w.at = self._count
        w.judged_full = w.judged_full or not partial
        self.judged[w.kind.value] += 1
        if exceeded:
            self.exceeded.append(window)
            self.exceeded_count[w.kind.value] += 1
        return window

    def summary_dict(self) -> dict[str, Any]:
        """The windows judged and exceeded, per kind, and the exceeded ones (the last :data:`MAX_EXCEEDED`)."""
        return {
            "thresholds": self.thresholds.to_json_dict(),
            "windows_judged": {k.value: int(self.judged[k.value]) for k in WindowKind},
            "windows_exceeded_count": {k.value: int(self.exceeded_count[k.value]) for k in WindowKind},
            "windows_exceeded": [w.to_json_dict() for w in self.exceeded],
        }
