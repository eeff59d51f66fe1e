"""Plausibility of a log's time base: the speed its time column implies, and the resolution
of its time stamps against the tooth period.

**Time base.** A tooth period that implies a mean speed under :data:`MIN_RPM` (10 rpm) or
over :data:`MAX_RPM` (30,000 rpm) is refused: no piston engine runs there (a cranking
starter turns it at about 100–300 rpm, racing engines stay below about 20,000 rpm), and a
time column in milliseconds or microseconds (3000 rpm read as 3 rpm or 0.003 rpm) lands
there. The message says the speed implied and the unit the column is likely in; the way
out is seconds, or a column name that says the unit (``time_ms``, ``tooth_time_us``, …;
:data:`rotor.logs.reader.UNIT_COLUMNS`). A speed log (``time``, ``rpm``) whose samples lie
more than half a revolution apart at the logged speed is refused the same way.

**Resolution of the stamps.** Time stamps stored with too few digits (float32 near
t = 1000 s resolves only 6.1e-5 s, a fifth of a 60-2 wheel's tooth period at 3000 rpm)
put a quantisation noise on every tooth period that δ and the orders take for speed. The
resolution is read from the stamps themselves (:func:`time_resolution_s`): where the
tooth periods (or the sample intervals) take few distinct values, all whole multiples of
one step, that step is the resolution. Against the median tooth period: above
:data:`RESOLUTION_REFUSE` (2 %) the log is refused, above :data:`RESOLUTION_NOTE` (0.2 %)
a note says so. (On a simulated 60-2 log with a 2 % fluctuation, stamps rounded to 0.3 %,
1 %, 3 % and 10 % of the tooth period raised δ by 4 %, 13 %, 26 % and 4.6×.)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import LogError
from ..units import RPM_PER_RAD_S

__all__ = [
    "MIN_RPM",
    "MAX_RPM",
    "RESOLUTION_NOTE",
    "RESOLUTION_REFUSE",
    "check_time_base",
    "check_speed_time_base",
    "time_resolution_s",
    "check_time_resolution",
]

MIN_RPM = 10.0
MAX_RPM = 30_000.0
RESOLUTION_NOTE = 0.002
RESOLUTION_REFUSE = 0.02
RESOLUTION_SAMPLE = 2**17  # time differences read for the resolution of a long log
_UNITS = (("milliseconds", 1e3, "time_ms", "tooth_time_ms"), ("microseconds", 1e6, "time_us", "tooth_time_us"))


def _median_period(times: np.ndarray) -> float:
    d = np.diff(np.asarray(times, dtype=np.float64))
    d = d[d > 0]
    return float(np.median(d)) if d.size else float("nan")


def _unit_hint(rpm: float, kind: str) -> str:
    """What the time column is probably in, and how to say so."""
    col = "time" if kind != "teeth" else "tooth_time_s"
    for unit, factor, name_t, name_teeth in _UNITS:
        if MIN_RPM <= rpm * factor <= MAX_RPM:
            name = name_teeth if kind == "teeth" else name_t
            return (
                f"is it in {unit} ({rpm * factor:.4g} rpm if so)? give seconds, or name the column {name!r} "
                f"(columns='…,{name},…')"
            )
    if rpm > MAX_RPM:
        return f"is the {col!r} column in seconds, and the wheel right?"
    return f"is the {col!r} column in seconds?"


def check_time_base(tooth_times: ArrayLike, teeth: int, source: str, kind: str = "teeth") -> float:
    """The mean speed [rpm] that the tooth edges imply; a :class:`LogError` outside
    :data:`MIN_RPM` … :data:`MAX_RPM` (see the module doc).

    **Arguments:** ``tooth_times``: edge times [s]; ``teeth``: tooth pitches per revolution
    of the wheel [-]; ``source``: the log's name, for the message; ``kind``: the log's kind
    (``"teeth"``: a tooth-time column, else a sampled ``time`` column), for the hint.
    """
    dt = _median_period(np.asarray(tooth_times))
    if not (np.isfinite(dt) and dt > 0):
        return float("nan")
    rpm = 60.0 / (dt * teeth)
    if not (MIN_RPM <= rpm <= MAX_RPM):
        col = "tooth-time" if kind == "teeth" else "time"
        raise LogError(
            f"{source}: the {col} column implies {rpm:.3g} rpm (a tooth period of {dt:.4g} s on a wheel of "
            f"{teeth} teeth), outside {MIN_RPM:g} … {MAX_RPM:,.0f} rpm; {_unit_hint(rpm, kind)}"
        )
    return rpm


def check_speed_time_base(t: ArrayLike, rpm: ArrayLike, source: str) -> None:
    """Refuse a speed log whose median speed lies outside :data:`MIN_RPM` … :data:`MAX_RPM`
    (another column read as the speed: a pressure table's, say), or whose samples lie more
    than half a revolution apart at the logged speed (a time column in milliseconds, read as
    seconds). ``t`` [s], ``rpm`` [rev/min];
    ``source`` names the log in the message."""
    t = np.asarray(t, dtype=np.float64)
    w = np.asarray(rpm, dtype=np.float64) / RPM_PER_RAD_S
    if t.size < 2:
        return
    med = float(np.median(np.asarray(rpm, dtype=np.float64)))
    if not (MIN_RPM <= med <= MAX_RPM):
        raise LogError(
            f"{source}: the 'rpm' column's median is {med:.4g} rpm, outside {MIN_RPM:g} … {MAX_RPM:g} rpm, where piston "
            f"engines run: is that column the engine speed in rpm? (check which column is which: columns=)"
        )
    rev = np.median(0.5 * (w[1:] + w[:-1]) * np.diff(t)) / (2 * np.pi)
    if rev > 0.5:
        hint = next(
            (
                f"if the time column is in {unit}, give seconds or name it {name!r} (columns='{name},rpm')"
                for unit, factor, name, _ in _UNITS
                if rev / factor <= 0.5
            ),
            "is the time column in seconds?",
        )
        raise LogError(
            f"{source}: the samples lie {rev:.3g} revolutions apart at {float(np.median(w)) * RPM_PER_RAD_S:.4g} rpm, too far to "
            f"follow the speed within a cycle (half a revolution at most); {hint}"
        )


def time_resolution_s(t: ArrayLike, *, evenly_spaced: bool = False) -> float:
    """The resolution of the time stamps ``t`` [s], read from their differences: the step
    of which the distinct differences are whole multiples, where they take few distinct
    values (at most half as many as there are differences) and the differences that should
    be alike take two or more (``evenly_spaced``: all of them, as a sampled time column's;
    else those within 1.5× of the median, a wheel's regular tooth periods: a wheel at
    exactly constant speed gives one tooth period and one gap period, no rounding); 0 where
    no such step is seen (stamps of full precision).

    A long log is read from the :data:`RESOLUTION_SAMPLE` differences at the end where
    the stamps are largest in magnitude: a float's resolution is coarsest there, and a
    timer's tick is the same everywhere."""
    t = np.asarray(t, dtype=np.float64)
    if t.size > RESOLUTION_SAMPLE + 1:
        t = t[-RESOLUTION_SAMPLE - 1 :] if abs(t[-1]) >= abs(t[0]) else t[: RESOLUTION_SAMPLE + 1]
    d = np.diff(t)
    d = d[d > 0]
    if d.size < 8:
        return 0.0
    tol = 64 * np.finfo(np.float64).eps * float(np.max(np.abs(t)))
    u = np.sort(d)
    vals = u[np.concatenate([[True], np.diff(u) > tol])]  # the distinct differences
    if vals.size < 2 or vals.size > 0.5 * d.size:
        return 0.0
    if not evenly_spaced:
        med = 0.5 * float(u[(u.size - 1) // 2] + u[u.size // 2])  # the median, from the sorted differences
        vals_alike = vals[(vals > med / 1.5) & (vals < med * 1.5)]
    else:
        vals_alike = vals
    if vals_alike.size < 2:
        return 0.0
    q = float(np.min(np.diff(vals_alike)))
    steps = vals / q
    if np.max(np.abs(steps - np.round(steps))) > 0.05 or np.min(np.round(steps)) < 1:
        return 0.0
    return q


def check_time_resolution(
    tooth_times: ArrayLike, source: str, sample_times: ArrayLike | None = None, column: str = "tooth_time_s"
) -> str | None:
    """Check the resolution of the time stamps against the median tooth period (see the
    module doc): a :class:`LogError` above :data:`RESOLUTION_REFUSE`, a note (returned)
    above :data:`RESOLUTION_NOTE`, else None.

    **Arguments:** ``tooth_times``: edge times [s]; ``source``: the log's name;
    ``sample_times``: the sampled ``time`` column [s] the edges were found in, if any;
    ``column``: the column named in the message.
    """
    dt = _median_period(np.asarray(tooth_times))
    if not (np.isfinite(dt) and dt > 0):
        return None
    q = time_resolution_s(tooth_times)
    if sample_times is not None:
        qs = time_resolution_s(sample_times, evenly_spaced=True)
        if qs > q:
            q, column = qs, "time"
    ratio = q / dt
    if ratio <= RESOLUTION_NOTE:
        return None
    where = np.asarray(sample_times if column == "time" and sample_times is not None else tooth_times)
    f32 = float(np.spacing(np.float32(np.max(np.abs(where)))))
    hint = f" (float32 near {np.max(np.abs(where)):.4g} s resolves {f32:.2g} s)" if 0.5 * q <= f32 <= 2 * q else ""
    text = (
        f"the {column!r} stamps resolve {q:.3g} s{hint}, {ratio:.1%} of the tooth period {dt:.4g} s: "
        f"store time as float64, or as offsets from the start of the log"
    )
    if ratio > RESOLUTION_REFUSE:
        raise LogError(f"{source}: {text} (δ and the orders would carry the rounding)")
    return text + " (δ may be a few per cent high)"
