"""Reading logged crankshaft signals: CSV/TSV files, the column spec, clear errors.

Measurement files (MDF 3/4, TDMS, MATLAB ``.mat``, Parquet, Arrow) are told by their
first bytes and read through their own libraries (:mod:`rotor.logs.formats`) into the
same :class:`Log`; their channels are named by role and channel name
(``columns="time=t,encoder_d=CRANK"``, :func:`channel_map`), the form a text file takes
too (its header's names, or its columns' numbers), or recognised by their content.

A log is a table of numbers, one row per sample or per tooth edge, separated by commas,
tabs, semicolons or blanks, with an optional header line; lines starting with ``#``
are comments. The header is the first line that is not a comment, and it holds names
only: a first line that mixes numbers and text is refused (it may be data in another
format, e.g. a decimal comma), as is a header of known names that contradicts the column
spec; a header of other names is skipped when the spec names the columns, and
``Log.notes`` says so. The user names its columns, in file order, from:

==================  =====================================================================
``time``            sample time [s] (with ``encoder_v``, ``pressure_v``, ``cam_v``,
                    ``index_v`` or ``rpm``)
``encoder_v``       the raw trigger-wheel (crank encoder) signal [V, any gain and offset]
``pressure_v``      a cylinder-pressure sensor signal [V, any gain and offset]: only its
                    shape is used (firing revolution and TDC), never its calibration
``cam_v``           a cam/phase sensor signal, one pulse per engine cycle
``index_v``         a once-per-revolution index signal (for wheels without a gap)
``encoder_d``       a digital (0/1) trigger-wheel channel given at its transitions (a
                    logic-analyser or ECU export: one row per transition)
``cam_d``           a digital (0/1) cam/phase channel, the same way
``tooth_time_s``    tooth edge timestamps [s], one per row
``rpm``             an instantaneous speed series [rev/min]
``-``               a column to skip
==================  =====================================================================

A time column in other units says so in its name: ``time_ms``, ``time_us`` (sample time in
milliseconds, microseconds) and ``tooth_time_ms``, ``tooth_time_us``; they are converted
to seconds on reading (``Log.notes`` says so) and named ``time`` and ``tooth_time_s``.

Columns after the last named one are ignored. A file whose header line already holds
these names needs no spec; a file with one column is read as ``tooth_time_s``.

**Known export formats** are recognised by their header (:data:`KNOWN_HEADERS`): a logic
analyser's (Saleae) ``Time[s], Channel 0, Channel 1, …`` is read as
``time, encoder_d, cam_d, -, …`` (channel 0 the crank wheel, channel 1 the cam), and
``Log.notes`` says so; a spec (``--columns time,encoder_d,-``) names them otherwise.

**What is refused, before reading:** a path that is no file (missing, a folder,
unreadable); a file that holds NUL bytes in its first 64 kB (a binary or zero-filled
file, not a text log); a file too large to read in the memory budget
(:func:`rotor.checks.memory_budget_bytes`; reading takes about
:data:`READ_BYTES_PER_FILE_BYTE` bytes per byte of text). A UTF-8 byte-order mark is
skipped. **Decimal commas** (``0,001;1,23``, separated by semicolons, tabs or blanks) are
read as decimal points, and ``Log.notes`` says so; a file that mixes decimal commas and
points in its first lines is refused, as is a comma-separated file (the comma cannot be
both).
"""

from __future__ import annotations

import dataclasses
import io
import math
import os
import re
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..checks import check_size
from ..errors import LogError
from .formats import ROLE_ALIASES, UNIT_COLUMNS

MEASUREMENT_FORMATS = "MDF, TDMS, MATLAB .mat, Parquet, Arrow"
"""The measurement files read besides text, in words (:mod:`rotor.logs.formats`)."""

__all__ = [
    "COLUMN_NAMES",
    "UNIT_COLUMNS",
    "KNOWN_HEADERS",
    "Log",
    "channel_map",
    "parse_columns",
    "read_log",
    "READ_BYTES_PER_FILE_BYTE",
]

READ_BYTES_PER_FILE_BYTE = 12
"""Memory that reading a log takes per byte of the file [bytes]: the text, its lines, the
parser's copy and the columns as float64 (measured on the single-cylinder bench files: about 8)."""

COLUMN_NAMES = {
    "time": "sample time [s]",
    "encoder_v": "trigger-wheel signal [V]",
    "pressure_v": "cylinder-pressure signal [V] (shape only)",
    "cam_v": "cam/phase signal [V]",
    "index_v": "once-per-revolution index signal [V]",
    "encoder_d": "digital trigger-wheel channel (0/1), one row per transition",
    "cam_d": "digital cam/phase channel (0/1), one row per transition",
    "tooth_time_s": "tooth edge time [s]",
    "rpm": "instantaneous speed [rev/min]",
    "time_ms": "sample time [ms] (read as 'time' in seconds)",
    "time_us": "sample time [µs] (read as 'time' in seconds)",
    "tooth_time_ms": "tooth edge time [ms] (read as 'tooth_time_s')",
    "tooth_time_us": "tooth edge time [µs] (read as 'tooth_time_s')",
    "-": "skipped",
}


KNOWN_HEADERS = {
    "Saleae logic analyser (Time[s], Channel 0, Channel 1, …)": (
        re.compile(r"time\s*\[s\]", re.IGNORECASE),
        re.compile(r"channel\s*(\d+)", re.IGNORECASE),
        ("time", "encoder_d", "cam_d"),
    ),
}
"""Export formats recognised by their header: name → (first column's pattern, the other
columns' pattern with the channel's number, the columns read: the first column's name,
then that of channel 0, channel 1, …). The channels are mapped by their numbers, wherever
their columns stand (``Time[s], Channel 1, Channel 0``: the second column is the cam);
further channels are skipped."""


_TIME_NAME = re.compile(r"(time|timestamp|t)\s*(\[\s*[mµu]?s\s*\]|\(\s*[mµu]?s\s*\))?", re.IGNORECASE)
"""A first column's name that makes its line a header, whatever the other columns are named."""


def _known_header(tokens: list) -> tuple[str, list] | None:
    """(format name, column spec) of a known export's header, or None."""
    for fmt, (first, rest, names) in KNOWN_HEADERS.items():
        if not (tokens and first.fullmatch(tokens[0]) and len(tokens) > 1):
            continue
        found = [rest.fullmatch(x) for x in tokens[1:]]
        if not all(found):
            continue
        spec = [names[0]]
        for m in found:
            k = int(m.group(1)) if m is not None and len(m.group(1)) < 4 else len(names)
            spec.append(names[1 + k] if 1 + k < len(names) else "-")
        if len(set(n for n in spec if n != "-")) != len([n for n in spec if n != "-"]):
            continue  # one channel named twice: not such an export
        return fmt, spec
    return None


def _canonical(name: str) -> str:
    return UNIT_COLUMNS[name][0] if name in UNIT_COLUMNS else name


def _to_seconds(cols: dict, notes: list) -> dict:
    """``cols`` with the time columns in other units converted to seconds under their SI names."""
    out = {}
    for k, v in cols.items():
        if k in UNIT_COLUMNS:
            canon, factor = UNIT_COLUMNS[k]
            out[canon] = v * factor
            notes.append(f"column {k!r} read as {canon!r} in seconds (× {factor:g})")
        else:
            out[k] = v
    return out


def _items(spec: object) -> list[str]:
    if isinstance(spec, str):
        return [s.strip() for s in spec.split(",")]
    if isinstance(spec, Sequence) and not isinstance(spec, bytes):
        return [str(s).strip() for s in spec]
    raise TypeError(
        f"columns = {spec!r}: the column names as a string ('time,encoder_v' or 'time=t,encoder_d=CRANK'), a list "
        f"of strings or a dict of roles and channel names, not {type(spec).__name__}"
    )


def channel_map(spec: str | Sequence[str] | Mapping[str, str] | None) -> dict[str, str] | None:
    """Role → the file's channel name of a spec that names channels, ``"time=t,encoder_d=CRANK"``
    (or a dict ``{"time": "t", "encoder_d": "CRANK"}``); None for no spec or a spec of column
    names in file order (:func:`parse_columns`).

    The roles: :data:`COLUMN_NAMES` (a time in ms or µs as ``time_ms``, ``time_us``, …) and
    :data:`rotor.logs.formats.ROLE_ALIASES` (``crank``, ``cam``: analog or digital as the
    channel's content says; ``pressure``, ``speed``). A channel name is the file's (a text
    file's header names, or its columns' numbers 1, 2, … where it has no header line).
    Raises :class:`LogError` naming an unknown or repeated role, a spec that mixes both
    forms, or a role without a name."""
    if spec is None:
        return None
    if isinstance(spec, Mapping):
        pairs = [(str(k).strip(), str(v).strip()) for k, v in spec.items()]
    else:
        items = [s for s in _items(spec) if s]
        if not any("=" in s for s in items):
            return None
        loose = [s for s in items if "=" not in s]
        if loose:
            raise LogError(
                f"columns {spec!r}: {loose[0]!r} has no '='; name every column as role=channel "
                "(time=t,encoder_d=CRANK), or give the names in file order without '='"
            )
        pairs = [tuple(x.strip() for x in s.split("=", 1)) for s in items]  # type: ignore[misc]
    roles = [n for n in COLUMN_NAMES if n != "-"] + list(ROLE_ALIASES)
    out: dict[str, str] = {}
    kinds: dict[str, str] = {}
    for role, name in pairs:
        if role not in roles:
            raise LogError(f"columns {spec!r}: {role!r} is no role; roles: {', '.join(roles)}")
        if not name:
            raise LogError(f"columns {spec!r}: {role}= names no channel (role=the file's channel name)")
        kind = _canonical(role)
        kind = {"crank": "encoder_v", "encoder_d": "encoder_v", "cam": "cam_v", "cam_d": "cam_v"}.get(kind, kind)
        kind = {"pressure": "pressure_v", "speed": "rpm"}.get(kind, kind)
        if kind in kinds:
            raise LogError(f"columns {spec!r}: {role!r} names the channel of {kinds[kind]!r} a second time")
        kinds[kind] = role
        out[role] = name
    if not out:
        raise LogError(f"columns {spec!r}: name at least one channel (role=name, e.g. encoder_d=CRANK)")
    return out


def parse_columns(spec: str | Sequence[str]) -> tuple[str, ...]:
    """The column names of a spec such as ``"time,encoder_v,pressure_v"`` (or a list).

    Raises :class:`LogError` naming an unknown or repeated name.
    """
    names = _items(spec)
    if any("=" in n for n in names):
        raise LogError(f"columns {spec!r}: a spec of channel names (role=name) is read by read_log, not here")
    if not names or all(n in ("", "-") for n in names):
        raise LogError(f"columns {spec!r}: name at least one column ({', '.join(n for n in COLUMN_NAMES if n != '-')})")
    seen = set()
    for i, n in enumerate(names):
        if n not in COLUMN_NAMES:
            raise LogError(
                f"columns {spec!r}: column {i + 1} is named {n!r}; known names: "
                f"{', '.join(COLUMN_NAMES)} ('-' skips a column)"
            )
        c = _canonical(n)
        if n != "-" and c in seen:
            raise LogError(
                f"columns {spec!r}: {n!r} is named twice"
                if n == c or n in seen
                else f"columns {spec!r}: {n!r} names the {c!r} column a second time"
            )
        seen.add(c)
        seen.add(n)
    return tuple(names)


@dataclasses.dataclass(frozen=True, eq=False)
class Log:
    """The named columns of a recording, checked.

    **Attributes:** ``columns``: name → float64 array (one entry per row; no ``-``
    columns); ``lines``: the file line number of each row (1-based; ``None`` for arrays
    given in Python), for messages; ``source``: the file name or ``"arrays"``; ``notes``:
    what the reader did that the user should know (e.g. a header line of names it does not
    know, skipped because the column spec names the columns).
    """

    columns: dict
    lines: np.ndarray | None = None
    source: str = "arrays"
    notes: tuple = ()

    def __post_init__(self):
        _check(self)

    @classmethod
    def from_arrays(cls, **columns: ArrayLike) -> Log:
        """A log from arrays, e.g. ``Log.from_arrays(time=t, encoder_v=v)`` or
        ``Log.from_arrays(tooth_time_s=edges)``; the names are those of :data:`COLUMN_NAMES`."""
        parse_columns(list(columns))
        cols = {}
        for k, v in columns.items():
            try:
                a = np.asarray(v, dtype=np.float64)
            except (TypeError, ValueError):
                raise TypeError(f"column {k!r}: an array of numbers, not {type(v).__name__}") from None
            if a.ndim != 1:
                raise LogError(f"column {k!r}: expected a 1-d array, got shape {a.shape}")
            cols[k] = a
        notes: list[str] = []
        cols = _to_seconds(cols, notes)
        return cls(cols, notes=tuple(notes))

    @property
    def kind(self) -> str:
        """``"teeth"`` (tooth timestamps), ``"encoder"`` (sampled wheel signal), ``"digital"``
        (a 0/1 wheel channel at its transitions) or ``"speed"``."""
        if "tooth_time_s" in self.columns:
            return "teeth"
        if "encoder_v" in self.columns:
            return "encoder"
        if "encoder_d" in self.columns:
            return "digital"
        return "speed"

    @property
    def rows(self) -> int:
        return len(next(iter(self.columns.values())))

    def where(self, i: int) -> str:
        """'line L' (file) or 'row i' (arrays) for row index ``i`` (0-based)."""
        if self.lines is not None:
            return f"{self.source}: line {int(self.lines[i])}"
        return f"row {i}"

    def __getitem__(self, name):
        try:
            return self.columns[name]
        except KeyError:
            raise LogError(f"{self.source}: no column {name!r} (the log has {', '.join(self.columns)})") from None

    def __contains__(self, name):
        return name in self.columns


MAX_SAMPLE_GAP = 20.0
"""The longest step between two rows of a sampled signal (``encoder_v``), in median sample
periods; a longer one is samples missing from the recording, refused by name."""


def _check(log: Log) -> None:
    cols = log.columns
    if not cols:
        raise LogError(f"{log.source}: no columns")
    lengths = {k: len(v) for k, v in cols.items()}
    if len(set(lengths.values())) != 1:
        raise LogError(f"{log.source}: columns of different lengths {lengths}")
    names = set(cols)
    if "encoder_d" in names or "cam_d" in names:
        if "time" not in names:
            raise LogError(f"{log.source}: a 'time' column is needed with the digital channels (encoder_d, cam_d)")
        clash = names & {"tooth_time_s", "encoder_v", "rpm"}
        if "encoder_d" in names and clash:
            raise LogError(f"{log.source}: 'encoder_d' and {sorted(clash)} in one log; name one kind of signal")
    if "tooth_time_s" in names:
        clash = names & {"encoder_v", "rpm"}
        if clash:
            raise LogError(f"{log.source}: 'tooth_time_s' and {sorted(clash)} in one log; name one kind of signal")
    elif "encoder_d" in names:
        pass
    elif "encoder_v" in names or "rpm" in names:
        if "time" not in names:
            need = "encoder_v" if "encoder_v" in names else "rpm"
            raise LogError(f"{log.source}: a 'time' column is needed with {need!r}")
        if {"encoder_v", "rpm"} <= names:
            raise LogError(f"{log.source}: 'encoder_v' and 'rpm' in one log; name one kind of signal")
    else:
        raise LogError(
            f"{log.source}: name a 'tooth_time_s', 'encoder_v' (with 'time'), 'encoder_d' (with 'time') or 'rpm' "
            f"(with 'time') "
            f"column; the log has {', '.join(sorted(names))}"
        )
    for k, v in cols.items():
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            i = int(bad[0])
            raise LogError(
                f"{log.where(i)}, column {k!r}: {float(v[i])} is not a finite number"
                + (f" ({bad.size} such rows)" if bad.size > 1 else "")
            )
    for k in ("time", "tooth_time_s"):
        if k in cols:
            d = np.diff(cols[k])
            bad = np.flatnonzero(d <= 0)
            if bad.size:
                i = int(bad[0]) + 1
                same = cols[k][i] == cols[k][i - 1]
                raise LogError(
                    f"{log.where(i)}, column {k!r}: {cols[k][i]:.9g} s is not after the previous row's "
                    f"{cols[k][i - 1]:.9g} s (time must increase)"
                    + (
                        "; equal stamps: the time's resolution may be too coarse (float32 near "
                        f"{abs(cols[k][i]):.4g} s resolves {_f32_spacing(cols[k][i]):.2g} s): store time as "
                        "float64 or as offsets from the start"
                        if same
                        else ""
                    )
                )
    if "encoder_v" in cols and cols["time"].size > 10:  # a sampled signal: evenly spaced samples
        dt = np.diff(cols["time"])
        period = float(np.median(dt))
        gaps = np.flatnonzero(dt > MAX_SAMPLE_GAP * period)
        if gaps.size:
            i = int(gaps[0]) + 1
            raise LogError(
                f"{log.where(i)}: the samples stop for {dt[i - 1] * 1e3:.3g} ms ({dt[i - 1] / period:.0f} sample "
                f"periods of {period * 1e6:.3g} µs) before this row: samples are missing from the recording"
                + (f" ({gaps.size} such gaps)" if gaps.size > 1 else "")
                + "; cut the log there, or give its parts as separate logs"
            )
    for k in ("encoder_d", "cam_d"):
        if k in cols:
            v = cols[k]
            two = np.unique(v[: min(v.size, 64)])[:2]
            bad = np.flatnonzero(~np.isin(v, two)) if two.size == 2 else np.zeros(0, np.int64)
            if bad.size:
                i = int(bad[0])
                raise LogError(
                    f"{log.where(i)}, column {k!r}: {v[i]:g} where the channel's levels are {two[0]:g} and "
                    f"{two[1]:g}; a digital channel has two levels (an analog signal? name it "
                    f"{k[:-2] + '_v'})"
                )
    if "rpm" in cols:
        bad = np.flatnonzero(cols["rpm"] <= 0)
        if bad.size:
            i = int(bad[0])
            raise LogError(
                f"{log.where(i)}, column 'rpm': {cols['rpm'][i]:g} rpm; the speed must stay positive "
                f"(angle is its integral)"
            )
    n = log.rows
    if n < 3:
        raise LogError(f"{log.source}: {n} row{'s' if n != 1 else ''}; far too short for one revolution")


def _f32_spacing(x: float) -> float:
    """The spacing of float32 numbers near ``x`` [same unit as x]."""
    return float(np.spacing(np.float32(abs(x))))


def _delimiter(line: str) -> str | None:
    for d in ("\t", ";", ","):
        if d in line:
            return d
    return None  # blanks


def _is_number(tok: str) -> bool:
    try:
        float(tok)
        return True
    except ValueError:
        return False


def _data_lines(text: str):
    """(line number, stripped line) of the non-blank, non-comment lines."""
    for n, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if s and not s.startswith("#"):
            yield n, s


def read_log(
    path: str | os.PathLike,
    columns: str | Sequence[str] | Mapping[str, str] | None = None,
    *,
    delimiter: str | None = None,
) -> Log:
    """Read a log: a CSV/TSV/blank-separated text file, or a measurement file (MDF 3/4,
    TDMS, MATLAB ``.mat``, Parquet, Arrow; :mod:`rotor.logs.formats`), told by its first
    bytes, else by its suffix.

    **Arguments:**
    - ``path``: the file.
    - ``columns``: the column names in file order (``"time,encoder_v,pressure_v"`` or a
      list; see :data:`COLUMN_NAMES`); or roles and the file's channel names,
      ``"time=t,encoder_d=CRANK"`` (or a dict; :func:`channel_map`), the one form for a
      measurement file; ``None``: the header line's names if they are all
      known, or ``tooth_time_s`` for a one-column file; else the columns recognised by
      their content (:func:`rotor.logs.channels.recognise_columns`), a measurement file's
      channels too.
    - ``delimiter``: ``","``, ``"\\t"``, ``";"`` or ``" "`` (blanks); default: found
      from the first data line (tab, then semicolon, then comma, else blanks).

    **Returns:** a :class:`Log`. Raises :class:`LogError` naming the line and column of
    anything it cannot use: a cell that is not a number, NaN, time not increasing, a
    column the spec names but the file lacks; and naming ``path`` for a file that is
    missing, a folder, unreadable, binary or too large for the memory budget (see the
    module doc). A ``TypeError`` for a ``path`` or ``columns`` of the wrong type.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path = {path!r}: the log's file name (a str or os.PathLike), not {type(path).__name__}")
    path = os.fspath(path)
    if not isinstance(path, str):
        path = os.fsdecode(path)
    if delimiter is not None and delimiter not in (",", "\t", ";", " "):
        raise LogError(f"delimiter = {delimiter!r}: ',', '\\t', ';' or ' ' (blanks)")
    spec = channel_map(columns)
    fmt = _measurement_format(path)
    if fmt is not None:
        from .formats import channels_to_read, columns_from_groups, read_channels

        if columns is not None and spec is None:
            raise LogError(
                f"{path}: a measurement file's columns are named by role and channel name (columns='time=t,"
                f"encoder_d=CRANK'), not by their order; or leave the spec out to recognise them by content"
            )
        notes: list[str] = []
        source = os.path.basename(path)
        groups = read_channels(path, fmt, channels_to_read(fmt, spec))
        return Log(columns_from_groups(source, groups, spec, notes), source=source, notes=tuple(notes))
    text = _read_text(path)
    notes = []
    lines = _data_lines(text)
    first = next(lines, None)
    if first is None:
        raise LogError(f"{path}: no data (the file is empty or all comments)")
    sep = delimiter if delimiter is not None else _delimiter(first[1])
    if sep == " ":
        sep = None
    second = next(lines, None)
    if sep != "," and _decimal_commas(path, [first] + ([second] if second else []), sep):
        text = text.replace(",", ".")
        notes.append(
            f"decimal commas read as decimal points (line {(second or first)[0]}: {_short((second or first)[1])})"
        )
        first = next(_data_lines(text))
    tokens = [t.strip() for t in (first[1].split(sep) if sep else first[1].split())]
    numeric = [_is_number(t) for t in tokens if t != ""]
    header = not any(numeric)
    if not header and not all(numeric) and tokens and _TIME_NAME.fullmatch(tokens[0]):
        header = True  # a time column's name, then channels named by numbers (e.g. ``Time[s], 0, 1``)
    if not header and not all(numeric):
        bad = next(t for t in tokens if t != "" and not _is_number(t))
        raise LogError(
            f"{path}: line {first[0]} ({_short(first[1])}) mixes numbers and text ({bad!r} is not a number): "
            f"a header line holds column names only and a data line numbers only (decimal point '.'); "
            f"start a line with '#' to make it a comment"
        )
    ncols = len(tokens)
    if spec is not None:
        return _named(path, text, sep, header, tokens, ncols, first, notes, spec)
    assert not isinstance(columns, Mapping)  # a dict is a spec of channel names (channel_map)
    known = _known_header(tokens) if header else None
    if columns is None and known is not None:
        notes.append(f"header line {first[0]} ({_short(first[1])}) read as a {known[0]} export")
        return _recognised(path, text, sep, header, tokens, ncols, first, notes)
    elif columns is None:
        if header and all(t in COLUMN_NAMES for t in tokens):
            columns = tokens
        elif ncols == 1 and not header:
            columns = ["tooth_time_s"]
        else:
            return _recognised(path, text, sep, header, tokens, ncols, first, notes)
    elif header and known is None:
        order = parse_columns(columns)
        clash = [
            (i, h, n)
            for i, (h, n) in enumerate(zip(tokens, order))
            if h in COLUMN_NAMES and h != "-" and n != "-" and h != n
        ]
        if clash:
            i, h, n = clash[0]
            raise LogError(
                f"{path}: line {first[0]}: the header names column {i + 1} {h!r} but the column spec names "
                f"it {n!r}; make them agree, or leave the spec out to use the header's names"
            )
        if not all(t in COLUMN_NAMES for t in tokens):
            notes.append(
                f"header line {first[0]} ({_short(first[1])}) skipped: the columns are named by the spec "
                f"({', '.join(order)})"
            )
    names = parse_columns(columns)
    if len(names) > ncols:
        missing = [n for n in names[ncols:] if n != "-"]
        raise LogError(
            f"{path}: line {first[0]} has {ncols} column{'s' if ncols != 1 else ''}, but the column spec "
            f"names {len(names)}; no column for {', '.join(map(repr, missing)) or 'the last names'}"
        )
    use = [i for i, n in enumerate(names) if n != "-"]
    data = _parse(path, text, sep, header, ncols, use)
    # line numbers of the data rows (only needed for messages, cheap enough)
    nums = np.fromiter((n for n, _ in _data_lines(text)), dtype=np.int64)
    if header:
        nums = nums[1:]
    if known is not None and any(n != k for n, k in zip(parse_columns(columns), known[1])):
        notes.append(f"header line {first[0]} ({_short(first[1])}) skipped: the columns are named by the spec")
    cols = _to_seconds({names[i]: data[:, j] for j, i in enumerate(use)}, notes)
    return Log(cols, nums[: data.shape[0]], source=os.path.basename(path), notes=tuple(notes))


def _recognised(path, text, sep, header, tokens, ncols, first, notes) -> Log:
    """A log whose columns no spec and no header of known names gives: every column read,
    then named by its content (:func:`rotor.logs.channels.recognise_columns`)."""
    from .channels import recognise_columns

    units, data, nums = _table(path, text, sep, header, ncols, first)
    finite = data[np.all(np.isfinite(data), axis=1)]  # a row that is not numbers is named by the checks below
    names, said = recognise_columns(tokens if header else None, finite, units=units, source=os.path.basename(path))
    if units is not None:
        said.insert(0, f"line {first[0] + 1} read as the columns' units ({_short(', '.join(units))})")
    use = [i for i, n in enumerate(names) if n != "-"]
    cols = _to_seconds({names[i]: data[:, i] for i in use}, notes)
    return Log(cols, nums[: data.shape[0]], source=os.path.basename(path), notes=tuple(notes + said))


def _named(path, text, sep, header, tokens, ncols, first, notes, spec: dict[str, str]) -> Log:
    """A log whose spec names the file's columns by role (``time=t,encoder_d=CRANK``): the
    header's names, or the columns' numbers (1, 2, …) in a file without a header line."""
    from .formats import Channel, ChannelGroup, columns_from_groups

    units, data, nums = _table(path, text, sep, header, ncols, first)
    names = tokens if header else [str(j + 1) for j in range(ncols)]
    chans = tuple(Channel(str(n), data[:, j], units[j] if units else "") for j, n in enumerate(names))
    what = "its header's names" if header else "their numbers (no header line)"
    source = os.path.basename(path)
    cols = columns_from_groups(source, [ChannelGroup(f"columns named by {what}", chans)], spec, notes)
    return Log(cols, nums[: data.shape[0]], source=source, notes=tuple(notes))


def _table(path, text, sep, header, ncols, first) -> tuple[list | None, np.ndarray, np.ndarray]:
    """(a units row's entries or None, every column as floats, each row's line number)."""
    units = None
    lines = _data_lines(text)
    if header:
        next(lines, None)
        second = next(lines, None)
        if second is None:
            raise LogError(f"{path}: line {first[0]} ({_short(first[1])}) and no data rows: not a recording")
        if second is not None:
            toks = [t.strip() for t in (second[1].split(sep) if sep else second[1].split())]
            if len(toks) == ncols and not any(_is_number(t) for t in toks if t):
                units = toks  # a units row under the names (e.g. ``ms, Flag, …``)
                text = "\n".join("# units" if n == second[0] else line for n, line in _raw_lines(text))
    data = _parse(path, text, sep, header, ncols, list(range(ncols)))
    nums = np.fromiter((n for n, _ in _data_lines(text)), dtype=np.int64)
    if header:
        nums = nums[1:]
    return units, data, nums


def _measurement_format(path: str) -> str | None:
    """The :data:`rotor.logs.formats.FORMATS` key of a measurement file at ``path``, None
    for a text log (or no file: :func:`_read_text` says why)."""
    if not os.path.isfile(path):
        return None
    from .formats import detect_format

    return detect_format(path)


def _raw_lines(text: str):
    """(line number, line) of every line of ``text``, counted from 1."""
    return enumerate(text.splitlines(), start=1)


_DECIMAL_COMMA = re.compile(r"^[+-]?\d*,\d+(?:[eE][+-]?\d+)?$")
_DECIMAL_POINT = re.compile(r"^[+-]?(?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?$")


def _decimal_commas(path: str, lines: list, sep: str | None) -> bool:
    """Whether the first data lines (``(number, text)`` pairs, split at ``sep``) write
    numbers with a decimal comma; a LogError if they mix decimal commas and points."""
    comma = point = None
    for n, line in lines:
        for tok in (t.strip() for t in (line.split(sep) if sep else line.split())):
            if comma is None and _DECIMAL_COMMA.match(tok):
                comma = (n, tok)
            elif point is None and _DECIMAL_POINT.match(tok):
                point = (n, tok)
    if comma is not None and point is not None:
        raise LogError(
            f"{path}: line {comma[0]} writes {comma[1]!r} with a decimal comma and line {point[0]} {point[1]!r} "
            f"with a decimal point; write every number one way (a decimal point is safest)"
        )
    return comma is not None


def _read_text(path: str) -> str:
    """The text of the log at ``path``, after the checks of the module doc (a LogError naming
    ``path`` for a missing, unreadable, binary or too large file)."""
    if os.path.isdir(path):
        raise LogError(f"{path}: is a folder, not a log file")
    if os.path.exists(path) and not os.path.isfile(path):
        import stat

        mode = os.stat(path).st_mode
        kind = (
            "a named pipe"
            if stat.S_ISFIFO(mode)
            else "a device"
            if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
            else "a socket"
        )
        raise LogError(
            f"{path}: is {kind}, not a log file: save the recording to a file first (rotor monitor reads a stream: "
            f"rotor monitor - < {os.path.basename(path)})"
        )
    try:
        size = os.path.getsize(path)
        with open(path, "rb") as f:
            head = f.read(65536)
    except FileNotFoundError:
        raise LogError(f"{path}: No such file or directory (no log there)") from None
    except PermissionError:
        raise LogError(f"{path}: cannot be read (permission denied)") from None
    except OSError as e:
        raise LogError(f"{path}: cannot be read ({e.strerror or e})") from None
    if b"\0" in head:
        raise LogError(
            f"{path}: not a text log: it holds NUL bytes (a binary or zero-filled file); give a CSV/TSV/text "
            f"table of numbers, or a measurement file ({MEASUREMENT_FORMATS})"
        )
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise LogError(f"{path}: is UTF-16 text; save it as UTF-8 (or ASCII)")
    check_size(
        float(size) * READ_BYTES_PER_FILE_BYTE,
        f"{path}: reading this {size / 1e6:.3g} MB log",
        "split it into shorter logs, or set ROTOR_MEMORY_LIMIT_GB [GB] higher on a machine with the memory",
        error=LogError,
    )
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as f:
            text = f.read()
    except OSError as e:
        raise LogError(f"{path}: cannot be read ({e.strerror or e})") from None
    if "\0" in text:
        raise LogError(f"{path}: not a text log: it holds NUL bytes (a binary file); give a CSV/TSV/text table")
    return text


def _short(line: str, width: int = 60) -> str:
    """``line`` quoted, cut to about ``width`` characters, for a message."""
    return repr(line if len(line) <= width else line[: width - 1] + "…")


def _parse(path, text, sep, header, ncols, use) -> np.ndarray:
    """The used columns as a float array; on failure, a LogError naming the first bad line."""
    import pandas as pd

    kw = dict(
        header=None,
        skiprows=1 if header else 0,
        comment="#",
        skip_blank_lines=True,
        usecols=use,
        dtype=np.float64,
        engine="c",
    )
    if sep is None:
        kw["sep"] = r"\s+"
    else:
        kw["sep"] = sep
        kw["skipinitialspace"] = True  # ", " separators: the blank belongs to the separator
    # drop the header line ourselves: comment/blank lines before it shift skiprows
    body = text
    if header:
        kept = 0
        out = []
        for line in text.splitlines(keepends=True):
            s = line.strip()
            if not kept and s and not s.startswith("#"):
                kept = 1
                continue
            out.append(line)
        body = "".join(out)
        kw["skiprows"] = 0
    if not any(True for _ in _data_lines(body)):
        raise LogError(f"{path}: no data rows (only a header line)")
    try:
        df = pd.read_csv(io.StringIO(body), **kw)
        arr = df.to_numpy(dtype=np.float64)
    except (ValueError, pd.errors.ParserError) as e:
        _find_bad_line(path, text, sep, header, ncols, use, e)
        raise LogError(f"{path}: cannot read the table ({e})") from None
    # rows with fewer fields come back as NaN: find them with their line numbers
    if arr.shape[0] == 0:
        raise LogError(f"{path}: no data rows")
    if np.isnan(arr).any():
        _find_bad_line(path, text, sep, header, ncols, use, None)
    return arr


def _find_bad_line(path, text, sep, header, ncols, use, err):
    first = True
    for n, s in _data_lines(text):
        if first and header:
            first = False
            continue
        first = False
        toks = [t.strip() for t in (s.split(sep) if sep else s.split())]
        if len(toks) < ncols and max(use) >= len(toks):
            raise LogError(
                f"{path}: line {n}: {len(toks)} column{'s' if len(toks) != 1 else ''} where the first line has {ncols}"
            )
        for i in use:
            try:
                x = float(toks[i])
            except ValueError:
                raise LogError(f"{path}: line {n}, column {i + 1}: {toks[i]!r} is not a number") from None
            if err is not None and not math.isfinite(x):  # the reader stumbled on it
                raise LogError(
                    f"{path}: line {n}, column {i + 1}: {toks[i]!r} is not a finite number; remove the line, or "
                    "start it with '#' to make it a comment"
                )
    return None
