"""The wheel-track stage: a log's edges placed on its wheel, with every choice made on the way.

A recording's signal is read once into a :class:`WheelReading` (edges → wheel track,
independent of TDC); the phasing and analysis stages that follow reuse it.

**Which edge.** Which edge of a signal is the clean one differs between installations (a
sensor's polarity, a conditioner's output stage). With ``edge="auto"`` (the default) both
are read and placed on the wheel; the edge whose placement needs the fewest repairs is
taken, then (with ``wheel="auto"``) the one whose wheel is a standard pattern, then the
one with the lower tooth-period jitter (:func:`rotor.logs.identify.period_jitter`).

**Which wheel.** ``wheel="auto"`` tries the candidates of :func:`rotor.logs.identify.candidates`
on each edge and ranks them (:func:`rotor.logs.identify.rank`); a given wheel is placed as
given. A wheel that needs more inferred edges than the budget allows
(:func:`rotor.logs.identify.inferred_budget`) is refused, naming the wheel that fits.

**Which levels.** An analog signal's edges are found with its global levels, or with levels
that follow the signal (:func:`rotor.logs.edges.find_edges`, ``levels="adaptive"``) where
those leave fewer edges guessed or cover more of the record (an amplitude that changes
with speed, a weak tooth next to the gap).

Every choice is recorded in :attr:`WheelReading.choices` with its evidence, and
:meth:`WheelReading.pins` gives the arguments that pin them.
"""

from __future__ import annotations

import dataclasses
import enum
from typing import Any

import numpy as np

from ..errors import LogError
from .digital import digital_edges
from .edges import GLOBAL_LEVELS, VR_CROSSINGS, Edges, find_edges, find_weak_edges, noise_rms, two_level_locally
from .identify import FitStatus, WheelFit, candidates, evidence, fit_wheel, rank
from .pattern import place
from .plausibility import check_time_base, check_time_resolution
from .reader import Log
from .wheel import ToothTrack, Wheel, parse_wheel

JITTER_MARGIN = 0.8
"""Where both edges fit alike, the sensor's less usual edge is taken only where its tooth-period
jitter is below this fraction of the usual one's (the usual edge: a two-level pulse's rising
edge, a variable-reluctance signal's falling zero crossing)."""

__all__ = [
    "JITTER_MARGIN",
    "ChoiceSource",
    "Choice",
    "WheelReading",
    "read_track",
    "edges_of",
    "named",
    "weak_edge_probe",
]


class ChoiceSource(enum.Enum):
    """Where a choice came from."""

    GIVEN = "given"
    FOUND = "found from the signal"
    FIXED = "fixed by the log's kind"


@dataclasses.dataclass(frozen=True)
class Choice:
    """One choice made while reading a signal: what (``name``), the value taken, where it
    came from, and the evidence in words."""

    name: str
    value: str
    source: ChoiceSource
    evidence: str = ""

    def to_json_dict(self) -> dict:
        return {"value": self.value, "source": self.source.name.lower(), "evidence": self.evidence or None}


def named(log_name: str, fn, *args, **kwargs):
    """``fn(*args, **kwargs)`` with a LogError's message prefixed by the log's name ``name``."""
    try:
        return fn(*args, **kwargs)
    except LogError as e:
        text = str(e)
        if not log_name or text.startswith(f"{log_name}:"):
            raise
        raise LogError(f"{log_name}: {text}") from None


def edges_of(log: Log, edge: str, *, levels: str | None = None, name: str = "") -> Edges:
    """The wheel's ``edge`` (``"rising"``/``"falling"``) edges of an analog (``encoder_v``) or
    digital (``encoder_d``) channel. An analog two-level pulse train is read with its global
    levels (``levels=None``), a drifting one with adaptive levels, a variable-reluctance
    signal at its zero crossings; ``levels`` forces one."""
    if log.kind == "digital":
        return named(name, digital_edges, log["time"], log["encoder_d"], edge=edge)
    t, v = log["time"], log["encoder_v"]
    if levels is not None:
        return named(name, find_edges, t, v, edge=edge, levels=levels)
    try:
        return named(name, find_edges, t, v, edge=edge)
    except LogError:
        pass
    if two_level_locally(v):
        return named(name, find_edges, t, v, edge=edge, levels="adaptive")
    return named(name, find_edges, t, v, edge=edge, levels="vr")


def weak_edge_probe(log: Log, edges: Edges):
    """A probe for :func:`rotor.logs.pattern.follow_pattern`: looks for a missed edge in the
    sampled signal at a lower level (:func:`rotor.logs.edges.find_weak_edges`), at the
    fraction of its own swing that ``edges`` were placed at."""
    tt, vv = log["time"], log["encoder_v"]
    noise = noise_rms(vv)
    span = edges.high_v - edges.low_v
    frac = float(np.clip((edges.level_v - edges.low_v) / span, 0.05, 0.95)) if span > 0 else 0.5
    dt = float(np.median(np.diff(tt[: min(tt.size, 100_000)])))  # the sampling interval [s]

    def probe(guess_s, pitch_s):
        return find_weak_edges(
            tt,
            vv,
            guess_s,
            pitch_s,
            edges.low_v,
            edges.high_v,
            inverted=edges.inverted,
            level=frac,
            noise_v=noise,
            dt_s=dt,
        )

    return probe


def _uncovered(log: Log, track: ToothTrack) -> str:
    """In words, where the edges of ``track`` leave more than the wheel's longest period and
    two teeth of the sampled record uncovered at its start or end; empty if nowhere."""
    t = log["time"]
    d = np.diff(track.t)
    if d.size < 20:
        return ""
    w = track.wheel
    longest = (max(w.gaps) + 3) if w.gaps else 3
    out = []
    if track.t[0] - t[0] > float(np.median(d[:10])) * longest:
        out.append(f"no edge in the first {track.t[0] - t[0]:.4g} s")
    if t[-1] - track.t[-1] > float(np.median(d[-10:])) * longest:
        out.append(f"no edge in the last {t[-1] - track.t[-1]:.4g} s")
    return " and ".join(out) + (" of the record" if out else "")


@dataclasses.dataclass(frozen=True, eq=False)
class WheelReading:
    """A recording's wheel signal read: its edges placed on its wheel (before any phasing).

    **Attributes:** ``source``: the log's name; ``log``: the :class:`rotor.logs.reader.Log`;
    ``track``: the placed edges (:class:`rotor.logs.wheel.ToothTrack`, repairs included);
    ``edges``: the :class:`rotor.logs.edges.Edges` of a sampled signal (``None`` for tooth
    times); ``fit``: the chosen :class:`rotor.logs.identify.WheelFit`; ``fits``: every
    (edge, wheel) tried; ``choices``: the edge, the levels and the wheel, each a
    :class:`Choice` with its evidence; ``notes``: what else was found.
    """

    source: str
    log: Log
    track: ToothTrack
    edges: Edges | None
    fit: WheelFit
    fits: tuple
    choices: tuple
    notes: tuple = ()

    @property
    def wheel(self) -> Wheel:
        return self.track.wheel

    @property
    def edge(self) -> str | None:
        return self.fit.edge

    def choice(self, name: str) -> Choice | None:
        return next((c for c in self.choices if c.name == name), None)

    def pins(self) -> str:
        """The arguments that pin the automatic choices (``wheel='60-2', edge='rising'``;
        the command line prints them as its flags, ``--wheel 60-2 --edge rising``)."""
        out = f"wheel={self.wheel.spec!r}"
        if self.edge is not None:
            out += f", edge={self.edge!r}"
        return out

    def plot(self, ax: Any = None, *, revolutions: float = 2.5) -> Any:
        """The signal as read around its first gap (``revolutions`` of it [-]): the samples,
        the levels and thresholds found, the edges taken and every repair. Returns the Axes."""
        from ..plotting.logs import plot_reading

        log, tr = self.log, self.track
        if log.kind == "teeth":
            t = tr.t
            v = np.zeros(t.size)
        else:
            t = log["time"]
            v = log["encoder_v"] if log.kind == "encoder" else np.asarray(log["encoder_d"], dtype=np.float64)
        z = tr.t[tr.tooth == 0]
        per_rev = float(np.median(np.diff(z))) if z.size > 1 else float(tr.t[-1] - tr.t[0])
        start = float(z[0]) - 0.25 * per_rev if z.size else float(tr.t[0])
        span = (max(start, float(t[0])), min(start + revolutions * per_rev, float(t[-1])))
        levels = {}
        e = self.edges
        if e is not None and log.kind == "encoder":
            sign = -1.0 if e.inverted else 1.0
            levels = {
                "low": sign * e.low_v,
                "high": sign * e.high_v,
                "off": sign * e.thresholds_v[0],
                "on": sign * e.thresholds_v[1],
                "timed at": sign * e.level_v,
            }
        title = f"{self.source}: read as {self.pins()} ({e.method if e is not None else 'tooth times'})"
        return plot_reading(t, v, tr.t, levels, tr.repairs, title, span_s=span, steps=log.kind == "digital", ax=ax)

    def to_json_dict(self) -> dict:
        return {
            "choices": {c.name: c.to_json_dict() for c in self.choices},
            "pins": self.pins(),
            "tried": [f.to_json_dict() for f in self.fits],
        }


RANKING_EDGES = 20_000
"""Of a long record, the candidate wheels are ranked on its first this many edges [-]; the
wheel chosen is then placed on all of them."""


def _fit_edges(log, name, edges, times, wheel, edge, index_times, auto):
    """The fits of the candidate wheels on one set of edges, the best, the runner-up and why
    (:func:`rotor.logs.identify.rank`; the best ``None`` where ambiguous or none fits). A long
    record's candidates are ranked on its first :data:`RANKING_EDGES` edges and the best placed
    on all of them."""
    probe = weak_edge_probe(log, edges) if log.kind == "encoder" and edges is not None else None
    if not auto:
        f = fit_wheel(times, wheel, edge=edge, index_times=index_times, probe=probe)
        return [f], (f if f.status.ok else None), None, "given"
    times = np.asarray(times, dtype=np.float64)
    head = times[:RANKING_EDGES] if times.size > 2 * RANKING_EDGES else times
    try:
        wheels = candidates(head)
    except LogError as e:
        return [WheelFit("auto", edge, FitStatus.NO_FIT, reason=str(e))], None, None, "no wheel found"
    fits = [fit_wheel(head, w, edge=edge, index_times=index_times, probe=probe) for w in wheels]
    best, second, why = rank(fits)
    if best is not None and head.size < times.size:
        assert best.track is not None
        whole = fit_wheel(times, best.track.wheel, edge=edge, index_times=index_times, probe=probe)
        fits = [whole if f is best else f for f in fits]
        best = whole if whole.status.ok else None
    return fits, best, second, why


def read_track(
    log: Log,
    wheel: str | Wheel | int,
    *,
    edge: str = "auto",
    name: str | None = None,
    level: float | None = None,
) -> WheelReading:
    """Read the wheel signal of ``log``: its edges, placed on its wheel (see the module notes).

    **Arguments:** ``log``: a :class:`rotor.logs.reader.Log` with a tooth-time, analog or
    digital wheel channel; ``wheel``: a spec (``"60-2"``, ``"36-2-1"``), a wheel file, a
    :class:`rotor.logs.wheel.Wheel`, or ``"auto"``; ``edge``: ``"auto"`` (default: both
    tried), ``"rising"`` or ``"falling"``; ``name``: the log's name in messages; ``level``:
    an analog signal's edges timed at this fraction of its swing, its global levels, and no
    other (as another recording of the installation was read) [-]; None: the levels that
    read the wheel best.

    **Returns:** :class:`WheelReading`. Raises :class:`LogError` (naming the file, what was
    expected and what to try) where no edge fits the wheel, or where two wheels fit alike.
    """
    name = log.source if name is None else name
    if edge not in ("auto", "rising", "falling"):
        raise LogError(f"edge = {edge!r}: 'auto', 'rising' or 'falling'")
    if log.kind == "speed":
        raise LogError(f"{name}: a speed log has no wheel signal")
    auto = isinstance(wheel, str) and wheel.strip().lower() == "auto"
    w = None if auto else parse_wheel(wheel)
    index_times = None
    if "index_v" in log:
        index_times = named(name, find_edges, log["time"], log["index_v"], name="index_v").times
    polarities: list[str | None] = (
        [None] if log.kind == "teeth" else (["rising", "falling"] if edge == "auto" else [edge])
    )
    tried: list[WheelFit] = []
    per_edge: list[tuple] = []  # (best, runner-up, why, edges, times)
    edge_errors: dict = {}
    level_notes: dict = {}
    for pol in polarities:
        read = _read_edge(log, name, pol, w, index_times, auto, tried, edge_errors, level_notes, level)
        if read is not None:
            per_edge.append(read)
    ok = [p for p in per_edge if p[0] is not None]
    if not ok:
        raise _refusal(name, log, w, edge, per_edge, tried, edge_errors)
    if edge != "auto" and w is not None and ok[0][0].repairs + ok[0][0].found and log.kind in ("encoder", "digital"):
        # the given edge needs repairs: where the other edge fits as it is, the given one is the wrong one
        other = "falling" if edge == "rising" else "rising"
        try:
            o = edges_of(log, other, name=name)
            clean = fit_wheel(o.times, w, edge=other, index_times=index_times, repair=False).status is FitStatus.FITS
        except LogError:
            clean = False
        if clean:
            f = ok[0][0]
            raise LogError(
                f"{name}: the {w.spec} wheel does not fit the signal's {edge} edges as they are ({f.repairs + f.found} "
                f"repairs in {f.revolutions} revolutions) but fits its {other} ones (an inverted signal?): give "
                f"edge={other!r}, or leave the edge out (edge='auto')"
            )
    usual = _tooth_edge(log, ok[0][0].track, ok[0][3]) if len(ok) > 1 else None
    # found from a two-level signal, the polarity whose wheel has more teeth has seen a tooth the other
    # missed (a VR signal's other crossings are no teeth of their own)
    ok.sort(key=lambda p: (p[0].interior, (not p[0].standard) if auto else False, -_seen(p), p[0].edge != usual))
    if (
        len(ok) > 1
        and ok[1][0].interior == ok[0][0].interior
        and ok[1][0].standard == ok[0][0].standard
        and _seen(ok[1]) == _seen(ok[0])
    ):
        # alike but for the jitter: the other edge only where it is clearly steadier
        if ok[1][0].jitter < JITTER_MARGIN * ok[0][0].jitter:
            ok = [ok[1], ok[0], *ok[2:]]
    best, second, why, edges, times, _ = ok[0]
    track = best.track
    assert track is not None
    check_time_base(track.t, track.wheel.teeth, name, log.kind)
    notes: list[str] = []
    resolution = check_time_resolution(
        times,
        name,
        sample_times=log["time"] if "time" in log else None,
        column="tooth_time_s" if log.kind == "teeth" else "time",
    )
    if resolution is not None:
        notes.append(resolution)
    choices = _choices(best, second, why, edges, edge, ok, auto, tried)
    if best.edge in level_notes:
        notes.append(level_notes[best.edge])
    if track.placement:
        notes.append(f"the wheel's placement: {track.placement}")
    if best.signature:
        which = ", ".join(f"tooth {k} ({_ordinal(k + 1)} after the gap)" for k in best.signature)
        notes.append(
            f"signature: {which} missing from the signal in most revolutions, a property of this wheel and its "
            "sensor: the wheel keeps its geometry, and the edge there is placed from the pattern, not measured"
        )
    if edges is not None and edges.repairs:
        track = dataclasses.replace(track, repairs=tuple(place(track.repairs + edges.repairs, track.t, track.rev)))
    return WheelReading(name, log, track, edges, best, tuple(tried), tuple(choices), tuple(notes))


def _read_edge(log, name, pol, w, index_times, auto, tried: list, edge_errors: dict, level_notes: dict, level=None):
    """The edges of polarity ``pol`` (None: tooth times) fitted to the wheel: (best fit,
    runner-up, why, edges, times, fits), or None where no edges are found (the error in
    ``edge_errors``); every fit tried added to ``tried``, and why adaptive levels were taken
    (where they were) to ``level_notes``."""
    if pol is None:
        edges, times = None, log["tooth_time_s"]
    elif level is not None and log.kind == "encoder":
        try:
            edges = named(name, find_edges, log["time"], log["encoder_v"], edge=pol, band=_band(level), level=level)
        except LogError as e:
            edge_errors[pol] = e
            tried.append(WheelFit(w.spec if w else "auto", pol, FitStatus.NO_EDGES, reason=str(e)))
            return None
        fits, best, second, why = _fit_edges(log, name, edges, edges.times, w, pol, index_times, auto)
        tried += fits
        return (best, second, why, edges, edges.times, fits)
    else:
        try:
            edges = edges_of(log, pol, name=name)
        except LogError as e:
            edge_errors[pol] = e
            tried.append(WheelFit(w.spec if w else "auto", pol, FitStatus.NO_EDGES, reason=str(e)))
            return None
        times = edges.times
    fits, best, second, why = _fit_edges(log, name, edges, times, w, pol, index_times, auto)
    # an analog signal: levels that follow it, where the global ones guess edges or leave the record uncovered
    if (
        log.kind == "encoder"
        and edges is not None
        and edges.method == GLOBAL_LEVELS
        and pol is not None
        and (best is None or best.repairs or (best.track is not None and _uncovered(log, best.track)))
    ):
        try:
            adaptive = edges_of(log, pol, levels="adaptive", name=name)
        except LogError:
            adaptive = None
        if adaptive is not None:
            fits_a, best_a, second_a, why_a = _fit_edges(log, name, adaptive, adaptive.times, w, pol, index_times, auto)
            if best_a is not None and (
                best is None
                or best_a.repairs < best.repairs
                or (best_a.repairs == best.repairs and best_a.track.t.size > best.track.t.size)
            ):
                if best is None:
                    level_notes[pol] = _ADAPTIVE + "with its global levels the edges did not fit the wheel"
                elif best.repairs > best_a.repairs:
                    level_notes[pol] = _ADAPTIVE + f"with its global levels {best.repairs} edges were guessed"
                else:
                    level_notes[pol] = _ADAPTIVE + f"with its global levels {_uncovered(log, best.track)}"
                fits, best, second, why, edges, times = fits_a, best_a, second_a, why_a, adaptive, adaptive.times
    if log.kind == "encoder" and edges is not None and pol is not None and _worth_another_level(best, auto):
        found = _level_search(log, name, pol, w, index_times, auto, best)
        if found is not None:
            fits_l, best, second, why, edges, note = found
            fits = fits + fits_l
            times = edges.times
            level_notes[pol] = note
    tried += fits
    return (best, second, why, edges, times, fits)


_ADAPTIVE = (
    "edges found with adaptive levels (the running minimum and maximum of the signal over each tooth period "
    "and two either side): "
)

LEVEL_BANDS = (((0.06, 0.22), 0.14), ((0.13, 0.3), 0.21), ((0.55, 0.85), 0.7))
"""The other levels an analog wheel signal is read at, where its default one (a Schmitt trigger
at 20 % / 45 % of the swing, the edge timed at 32 %) does not read the wheel cleanly: ((off, on),
timing level) as fractions of the swing [-]. A tooth that swings less than the others (the one
after the gap of some sensors) crosses a low level only; a tooth that merges with its neighbour
at the bottom (a wide one before the gap) is told apart at a high one."""


def _seen(read) -> int:
    """The teeth a revolution of a polarity's wheel (its positions less its missing ones), where
    its edges are a two-level signal's (0 for a variable-reluctance signal's crossings and tooth
    times: no reading's count tells there)."""
    fit, edges = read[0], read[3]
    if edges is None or edges.method == VR_CROSSINGS:
        return 0
    w = fit.track.wheel
    return int(w.teeth - w.missing)


def _ordinal(n: int) -> str:
    return f"{n}{'th' if 10 <= n % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(n % 10, 'th')}"


def _band(level: float) -> tuple[float, float]:
    """The Schmitt trigger's (off, on) band [-] for edges timed at ``level`` of the swing [-]."""
    for band, at in LEVEL_BANDS:
        if abs(at - level) < 0.01:
            return band
    return (max(0.02, level - 0.12), min(0.98, level + 0.13))


def _worth_another_level(best, auto: bool) -> bool:
    """Whether the signal is read at the other levels: found from the signal (a tooth the
    default level misses makes a wheel of more missing teeth), or no wheel fits, or edges were
    repaired."""
    return auto or best is None or best.repairs > 0


def _level_rank(fit, auto: bool) -> tuple:
    """How well a fit at one level reads the wheel, larger better: it fits; a standard wheel
    (found from the signal); fewer repairs; more teeth seen a revolution (a level that misses a
    tooth sees fewer, one that catches noise breaks the fit)."""
    if fit is None:
        return (False,)
    w = fit.track.wheel
    return (True, fit.standard if auto else True, -fit.repairs, w.teeth - w.missing)


def _better_level(new, old, auto: bool) -> bool:
    """Whether the fit at another level reads the wheel better than ``old`` (:func:`_level_rank`)."""
    return new is not None and _level_rank(new, auto) > _level_rank(old, auto)


LEVEL_HEAD = 1_500_000
"""A record of more samples than this chooses its level on its first ones [-], and is read
whole at the level chosen only (the search's cost bounded whatever the record's length)."""


def _level_search(log, name, pol, w, index_times, auto, best):
    """The signal read at each of :data:`LEVEL_BANDS`: (fits, best, runner-up, why, edges, the
    note) of the level that reads the wheel best, where one reads it better than ``best`` (on a
    long record: than the default level on its head, :data:`LEVEL_HEAD`); else None."""
    t, v = log["time"], log["encoder_v"]
    head = t.size > LEVEL_HEAD
    if head:
        t, v = t[:LEVEL_HEAD], v[:LEVEL_HEAD]
        part = Log({"time": t, "encoder_v": v}, log.lines, log.source, log.notes)
        try:
            e0 = named(name, find_edges, t, v, edge=pol)
            ref = _fit_edges(part, name, e0, e0.times, w, pol, index_times, auto)[1]
        except LogError:
            ref = None
    else:
        part, ref = log, best
    chosen = None
    for band, level in LEVEL_BANDS:
        try:
            e = named(name, find_edges, t, v, edge=pol, band=band, level=level)
        except LogError:
            continue
        found = _fit_edges(part, name, e, e.times, w, pol, index_times, auto)
        if _better_level(found[1], ref if chosen is None else chosen[1][1], auto):
            chosen = ((band, level), found, e)
    if chosen is None:
        return None
    (band, level), (fits, b, second, why), e = chosen
    if head:  # the whole record at the level chosen
        e = named(name, find_edges, log["time"], log["encoder_v"], edge=pol, band=band, level=level)
        fits, b, second, why = _fit_edges(log, name, e, e.times, w, pol, index_times, auto)
        if not _better_level(b, best, auto):
            return None
    before = "no wheel fitted" if best is None else f"{best.spec} with {best.repairs} repairs"
    note = f"{pol} edges timed at {level:.0%} of the swing: at the default level (32 %) {before}"
    return (fits, b, second, why, e, note)


def _choices(best, second, why, edges, edge, ok, auto, tried) -> list[Choice]:
    """The edge, levels and wheel the reading took, each with where it came from and why."""
    wname = best.track.wheel.spec
    choices = []
    if best.edge is not None:
        if edge == "auto" and len(ok) > 1:
            other = ok[1][0]
            if best.interior != other.interior:
                rule = "fewer repairs away from the record's first and last revolution"
            elif auto and best.standard != other.standard:
                rule = f"{best.spec} is a standard pattern, {other.spec} is not"
            elif best.jitter < JITTER_MARGIN * other.jitter:
                rule = "lower tooth-period jitter"
            else:
                rule = (
                    f"the teeth's own edge ({_tooth_edge_why(edges, best.edge)}), where the two fit alike "
                    f"(jitter within {1 / JITTER_MARGIN:.2g}×)"
                )
            ev = (
                f"{rule}: {best.edge} edges ({best.spec}) {best.repairs} repairs, jitter {100 * best.jitter:.2f} %; "
                f"{other.edge} edges ({other.spec}) {other.repairs} repairs, jitter {100 * other.jitter:.2f} %"
            )
        elif edge == "auto":
            bad = next((f for f in tried if f.edge != best.edge), None)
            ev = f"only the {best.edge} edges fit" + (f" ({bad.describe()})" if bad is not None else "")
        else:
            ev = ""
        choices.append(Choice("edge", best.edge, ChoiceSource.FOUND if edge == "auto" else ChoiceSource.GIVEN, ev))
        assert edges is not None
        choices.append(
            Choice(
                "levels",
                edges.method,
                ChoiceSource.FOUND,
                f"low {edges.low_v:.4g} V, high {edges.high_v:.4g} V, edge timed at {edges.level_v:.4g} V",
            )
        )
    choices.append(
        Choice(
            "wheel",
            wname,
            ChoiceSource.FOUND if auto else ChoiceSource.GIVEN,
            evidence(best, second, why) if auto else best.describe(),
        )
    )
    return choices


def _tooth_edge_why(edges: Edges | None, edge: str | None) -> str:
    """Why ``edge`` is the teeth's own edge, in words."""
    if edges is not None and edges.method == VR_CROSSINGS:
        lobe = "positive" if edge == "falling" else "negative"
        return f"a variable-reluctance signal's zero crossing at the tooth's centre, after its {lobe} first lobe"
    level = "low" if edge == "rising" else "high"
    return f"the edge out of the level the gap sits at ({level})"


def _tooth_edge(log: Log, track: ToothTrack | None, edges: Edges | None) -> str | None:
    """The edge that the teeth themselves make, read from the signal across the gaps (the same
    whatever the signal's sign): for a two-level signal the edge out of the level the gap sits at
    (the tooth's leading edge: rising where the gap is low); for a variable-reluctance signal,
    flat across the gap, the zero crossing at the tooth's centre (falling where the first lobe
    after the gap is positive, as its conditioners time it). ``None`` where it cannot be read."""
    if track is None or edges is None or log.kind not in ("encoder", "digital"):
        return None
    t = log["time"]
    v = np.asarray(log["encoder_v"] if log.kind == "encoder" else log["encoder_d"], dtype=np.float64)
    pitch = 2 * np.pi / track.wheel.teeth
    k = np.rint(np.diff(track.nominal_angle) / pitch)
    gaps = np.flatnonzero(k > 1)[:200]
    if gaps.size == 0:
        return None
    sub = v[:: max(1, v.size // 1_000_000)]
    lo, hi = np.percentile(sub, [1.0, 99.0])
    centre = 0.5 * (lo + hi)
    mid = 0.5 * (track.t[gaps] + track.t[gaps + 1])
    if edges.method != VR_CROSSINGS:
        level = v[np.clip(np.searchsorted(t, mid, side="right") - 1, 0, v.size - 1)]  # the level holding then
        return "rising" if np.median(level) < centre else "falling"
    signs = []
    for g, m in zip(gaps, mid):
        step = (track.t[g + 1] - track.t[g]) / k[g]
        a, b = np.searchsorted(t, [m, track.t[g + 1] + step])
        seg = v[a:b] - centre
        if seg.size == 0:
            continue
        big = np.flatnonzero(np.abs(seg) > 0.3 * np.max(np.abs(seg)))
        if big.size:
            signs.append(np.sign(seg[big[0]]))
    if not signs:
        return None
    return "falling" if np.mean(signs) > 0 else "rising"


def _swapped_column(log: Log, w: Wheel | None) -> str:
    """Where another sampled column of ``log`` reads as a wheel (``w``, or any), the words that
    say so; empty otherwise (a column given in the wrong place of ``columns``)."""
    if log.kind not in ("encoder", "digital"):
        return ""
    others = ("pressure_v", "cam_v", "index_v") if log.kind == "encoder" else ("cam_d",)
    for other in others:
        if other not in log:
            continue
        try:
            if log.kind == "encoder":
                probe = Log.from_arrays(time=log["time"], encoder_v=log[other])
            else:
                probe = Log.from_arrays(time=log["time"], encoder_d=log[other])
            r = read_track(probe, "auto" if w is None else w, name=log.source)
        except LogError:
            continue
        if r.track.revolutions < 2 or r.fit.inferred:
            continue
        return (
            f"; the column read as {other!r} reads as the {r.wheel.spec} wheel ({r.track.revolutions} revolutions): "
            f"check which column is which (columns=)"
        )
    return ""


def _refusal(name, log, w, edge, per_edge, tried, edge_errors) -> LogError:
    """The one-line error where no edge fits: what was expected, and what to try."""
    better = _what_fits(log, per_edge)
    swapped = "" if better else _swapped_column(log, w)  # only where the column read fits no wheel at all
    if swapped:
        col = "encoder_v" if log.kind == "encoder" else "encoder_d"
        why = (
            f"no wheel fits the {col!r} column" if w is None else f"the {w.spec} wheel does not fit the {col!r} column"
        )
        return LogError(f"{name}: {why}{swapped}")
    if w is None:
        ambiguous = [p for p in per_edge if p[1] is not None and p[0] is None]
        if ambiguous:
            fits = sorted((f for f in ambiguous[0][5] if f.status.ok), key=lambda f: (f.inferred, f.gap_misfit))
            a, b = fits[0], ambiguous[0][1]
            return LogError(
                f"{name}: the signal fits {a.describe()} and {b.describe()} alike; give the wheel "
                f"(wheel='{a.spec}' or wheel='{b.spec}')"
            )
        said = next((p[2] for p in per_edge if p[0] is None and p[2] and p[2] != "no wheel fits"), "")
        if said:
            return LogError(f"{name}: no wheel found: {said}")
        reasons = "; ".join(f.describe() for f in tried[:4])
        return LogError(f"{name}: no wheel found that fits the signal: {reasons}; give the wheel (wheel='N-g1-g2…')")
    mine = [f for f in tried if f.spec == w.spec]
    over = [f for f in mine if f.status == FitStatus.OVER_BUDGET]
    hint = f"; {better}" if better else "; check the wheel (wheel='auto' finds it) and which column is the wheel"
    if edge != "auto" and log.kind in ("encoder", "digital"):
        other = "falling" if edge == "rising" else "rising"
        try:
            o = edges_of(log, other, name=name)
            of = fit_wheel(o.times, w, edge=other, probe=weak_edge_probe(log, o) if log.kind == "encoder" else None)
        except LogError:
            of = None
        if of is not None and of.status.ok and not over:
            return LogError(
                f"{name}: the {w.spec} wheel does not fit the signal's {edge} edges but fits its {other} ones "
                f"(an inverted signal?): give edge={other!r}, or leave the edge out (edge='auto')"
            )
    if over:
        f = over[0]
        return LogError(
            f"{name}: the {w.spec} wheel does not fit the {f.edge + ' ' if f.edge else ''}edges: {f.reason}, so it "
            f"is not this signal's wheel{hint}"
        )
    if edge_errors and len(edge_errors) == len([p for p in (["rising", "falling"] if edge == "auto" else [edge])]):
        return next(iter(edge_errors.values()))
    f = mine[0] if mine else tried[0]
    reason = f.reason or f.status.value
    if reason.startswith(f"{name}:"):
        reason = reason[len(name) + 1 :].strip()
    return LogError(f"{name}: {reason}{hint}")


def _what_fits(log, per_edge) -> str:
    """In words, the wheel that fits the edges read (``wheel="auto"`` on them), or empty."""
    found = []
    for _, _, _, edges, times, _ in per_edge:
        if times is None:
            continue
        pol = None if edges is None else ("falling" if edges.inverted else "rising")
        _, best, _, _ = _fit_edges(log, "", edges, times, None, pol, None, True)
        if best is not None:
            found.append(best)
    if not found:
        return ""
    best = min(found, key=lambda f: (f.repairs, not f.standard, f.jitter))
    e = f" and edge='{best.edge}'" if best.edge else ""
    return f"the {best.spec} wheel fits ({best.describe()}): give wheel='{best.spec}'{e}"
