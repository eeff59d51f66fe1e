"""Channels recognised by their content: which column of a recording is the time, the
trigger wheel, the cam, a cylinder pressure or a speed, where no column spec names them.

A header's names are read as they come (``Time [s]``, ``Channel 0``, ``crank``, ``RefTime``,
numbers), but the content decides, and :func:`recognise_columns` says where it overrode a
name. The rules, in order:

- **time**: a column that increases on every row; one whose name says time (``time``,
  ``t``, ``timestamp``, ``RefTime``, …) first, else the first such column. Its unit from
  its name or a units row (``ms``, ``us``/``µs``, ``s``); without one, seconds (the
  plausibility checks of :mod:`rotor.logs.plausibility` then question a time base in ms).
- **digital channels** (two levels, e.g. 0/1, one row per transition): the one with the
  most transitions is the wheel (``encoder_d``); where another has nearly as many (at
  least :data:`RIVAL` of them) the choice is refused, naming both, for ``columns`` to
  pin; the next is the cam (``cam_d``) where it has at most :data:`CAM_SHARE` of the
  wheel's transitions; the rest are skipped.
- **sampled analog channels** (evenly spaced time): the one that crosses its mid-level
  most often is the wheel (``encoder_v``; refused where another crosses nearly as often);
  one that crosses at most :data:`PRESSURE_SHARE` as often and peaks above its median (a
  compression peak a cycle) is a pressure (``pressure_v``); a column named ``rpm`` or
  ``speed`` whose values are speeds is the speed (``rpm``).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from ..errors import LogError

__all__ = ["recognise_columns", "RIVAL", "CAM_SHARE", "PRESSURE_SHARE"]

RECOGNITION_ROWS = 1_000_000
"""Of a long recording, the channels are told apart on its first this many rows [-]."""
RIVAL = 0.8
"""A second channel with at least this share of the wheel's transitions (or crossings) could
be the wheel too: the choice is refused, naming both [-]."""
CAM_SHARE = 0.6
"""A digital channel with at most this share of the wheel's transitions is read as the cam [-]."""
PRESSURE_SHARE = 0.05
"""An analog channel that crosses its mid-level at most this share as often as the wheel,
and peaks above its median, is read as a cylinder pressure [-]."""

_TIME = re.compile(r"(ref)?(time|timestamp|t|zeit|temps)\b.*", re.IGNORECASE)
_MS = re.compile(r"(\bms\b|\[\s*ms\s*\]|\(\s*ms\s*\)|_ms\b|msec)", re.IGNORECASE)
_US = re.compile(r"(\bus\b|µs|μs|\[\s*us\s*\]|\(\s*us\s*\)|_us\b|usec)", re.IGNORECASE)
_RPM = re.compile(r".*\b(rpm|speed|n_?eng|engine_?speed)\b.*", re.IGNORECASE)


def _unit_of(name: str | None, unit: str | None) -> str:
    """``"s"``, ``"ms"`` or ``"us"`` from a column's name and its units-row entry."""
    for text in (unit, name):
        if text is None:
            continue
        if _US.search(text):
            return "us"
        if _MS.search(text):
            return "ms"
    return "s"


def _shown(name: str | None, j: int) -> str:
    return repr(name) if name else f"column {j + 1}"


def _crossings(v: np.ndarray) -> int:
    """Crossings of the mid-level with a hysteresis of a tenth of the swing (noise does not count)."""
    lo, hi = np.percentile(v, [2, 98])
    if not hi > lo:
        return 0
    mid, band = 0.5 * (lo + hi), 0.1 * (hi - lo)
    state = np.where(v > mid + band, 1, np.where(v < mid - band, -1, 0))
    s = state[state != 0]
    return int(np.count_nonzero(np.diff(s) != 0))


def recognise_columns(
    header: Sequence[str] | None, data: np.ndarray, *, units: Sequence[str] | None = None, source: str = "the log"
) -> tuple[list[str], list[str]]:
    """The column names (:data:`rotor.logs.reader.COLUMN_NAMES`, in file order) that the
    columns of ``data`` (rows × columns, numbers) hold by their content, and notes saying
    which column was taken for what and where a header name was overridden.

    ``header``: the header's names (or None); ``units``: a units row's entries (or None).
    Raises :class:`LogError` naming the columns and what each looks like where no time, or
    no signal, can be told, or where two columns could be the wheel."""
    n_rows, n_cols = data.shape
    if n_rows > RECOGNITION_ROWS:  # the channels told apart on the start of a long recording
        data = data[:RECOGNITION_ROWS]
        n_rows = RECOGNITION_ROWS
    names = list(header) if header is not None else [None] * n_cols
    units_l = list(units) if units is not None else [None] * n_cols
    if n_rows < 3:
        raise LogError(f"{source}: {n_rows} rows; far too short to tell its columns apart")
    inc = [bool(np.all(np.diff(data[:, j]) > 0)) for j in range(n_cols)]
    for j in range(n_cols):
        if names[j] and _TIME.fullmatch(str(names[j]).strip()) and not inc[j]:
            i = int(np.flatnonzero(np.diff(data[:, j]) <= 0)[0]) + 1
            raise LogError(
                f"{source}: column {names[j]!r} is named a time but does not increase (data row {i + 1}: "
                f"{data[i, j]:.9g} after {data[i - 1, j]:.9g}); sort the rows, or name the columns"
            )
    cand = [j for j in range(n_cols) if inc[j]]
    if not cand:
        raise LogError(
            f"{source}: no column increases on every row, so none is a time; name the columns "
            "(columns='time,encoder_d,…')"
        )
    named_t = [j for j in cand if names[j] and _TIME.fullmatch(str(names[j]).strip())]
    tj = named_t[0] if named_t else cand[0]
    unit = _unit_of(names[tj], units_l[tj])
    out = ["-"] * n_cols
    out[tj] = {"s": "time", "ms": "time_ms", "us": "time_us"}[unit]
    said = [f"{_shown(names[tj], tj)} → {out[tj]} (increases on every row{'' if unit == 's' else ', in ' + unit})"]
    others = [j for j in range(n_cols) if j != tj]
    levels = {j: np.unique(data[:, j]) for j in others}
    digital = [j for j in others if levels[j].size == 2]
    flat = [j for j in others if levels[j].size < 2]
    for j in flat:
        said.append(f"{_shown(names[j], j)} skipped (constant)")
    t = data[:, tj]
    if digital:
        trans = {j: int(np.count_nonzero(np.diff(data[:, j]) != 0)) for j in digital}
        ranked = sorted(digital, key=lambda j: -trans[j])
        wheel = ranked[0]
        if trans[wheel] < 4:
            raise LogError(f"{source}: the digital channels change at most {trans[wheel]} times; no wheel signal")
        if len(ranked) > 1 and trans[ranked[1]] >= RIVAL * trans[wheel]:
            a, b = ranked[0], ranked[1]
            raise LogError(
                f"{source}: {_shown(names[a], a)} ({trans[a]} transitions) and {_shown(names[b], b)} "
                f"({trans[b]}) could both be the wheel; name the columns (e.g. columns="
                f"'{','.join('time' if j == tj else 'encoder_d' if j == a else '-' for j in range(n_cols))}')"
            )
        out[wheel] = "encoder_d"
        said.append(f"{_shown(names[wheel], wheel)} → encoder_d (digital, {trans[wheel]} transitions, the most)")
        if len(ranked) > 1 and trans[ranked[1]] <= CAM_SHARE * trans[wheel] and trans[ranked[1]] >= 2:
            cam = ranked[1]
            out[cam] = "cam_d"
            said.append(f"{_shown(names[cam], cam)} → cam_d (digital, {trans[cam]} transitions)")
            rest = ranked[2:]
        else:
            rest = ranked[1:]
        for j in rest:
            said.append(f"{_shown(names[j], j)} skipped (digital, {trans[j]} transitions)")
        for j in others:
            if j not in digital and j not in flat:
                said.append(f"{_shown(names[j], j)} skipped (not a two-level channel beside digital ones)")
    else:
        analog = [j for j in others if j not in flat]
        if not analog:
            raise LogError(f"{source}: beside the time ({_shown(names[tj], tj)}) no column holds a signal")
        rpm = [
            j
            for j in analog
            if names[j] and _RPM.fullmatch(str(names[j])) and np.all((data[:, j] > 0) & (data[:, j] < 40_000))
        ]
        dt = np.diff(t)
        even = dt.size > 10 and float(np.percentile(dt, 99)) < 1.5 * float(np.median(dt))
        if rpm:
            out[rpm[0]] = "rpm"
            said.append(f"{_shown(names[rpm[0]], rpm[0])} → rpm (named so; speeds)")
            analog = [j for j in analog if j != rpm[0]]
            for j in analog:
                said.append(f"{_shown(names[j], j)} skipped")
        else:
            if not even:
                raise LogError(
                    f"{source}: {len(analog)} analog column(s) whose time steps are uneven, and no digital or "
                    f"speed column; name the columns (columns='time,encoder_v,…')"
                )
            cross = {j: _crossings(data[:, j]) for j in analog}
            ranked = sorted(analog, key=lambda j: -cross[j])
            wheel = ranked[0]
            if cross[wheel] < 8:
                raise LogError(
                    f"{source}: no column crosses its mid-level more than {cross[wheel]} times: no wheel "
                    f"signal; name the columns"
                )
            if len(ranked) > 1 and cross[ranked[1]] >= RIVAL * cross[wheel]:
                a, b = ranked[0], ranked[1]
                raise LogError(
                    f"{source}: {_shown(names[a], a)} ({cross[a]} crossings) and {_shown(names[b], b)} "
                    f"({cross[b]}) could both be the wheel; name the columns"
                )
            out[wheel] = "encoder_v"
            said.append(f"{_shown(names[wheel], wheel)} → encoder_v (analog, {cross[wheel]} crossings, the most)")
            for j in ranked[1:]:
                v = data[:, j]
                med = float(np.median(v))
                peaky = float(np.max(v) - med) > 2.0 * float(med - np.min(v))
                if "pressure_v" not in out and cross[j] <= PRESSURE_SHARE * cross[wheel] and peaky:
                    out[j] = "pressure_v"
                    said.append(f"{_shown(names[j], j)} → pressure_v (a peak a few times a second above its median)")
                elif j in rpm:
                    out[j] = "-"
                    said.append(f"{_shown(names[j], j)} skipped (a speed beside a wheel signal)")
                else:
                    said.append(f"{_shown(names[j], j)} skipped ({cross[j]} crossings)")
    overrides = []
    for j, name in enumerate(names):
        if not name:
            continue
        low = str(name).strip().lower()
        if low in ("crank", "cam", "encoder", "pressure") and not out[j].startswith(
            low[:3] if low != "crank" else "enc"
        ):
            overrides.append(f"the header names {_shown(name, j)} but its content reads as {out[j]}")
    notes = ["columns recognised by their content: " + "; ".join(said)]
    if overrides:
        notes.append("; ".join(overrides) + " (the content decides; columns=… pins them)")
    return out, notes
