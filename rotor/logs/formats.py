"""Measurement files: MDF 3/4, TDMS, MATLAB ``.mat`` (v5 and v7.3), Parquet and Arrow.

Each format is read through the library made for it, an optional extra of rotor
(:data:`FORMATS`): ``pip install '.[mdf]'`` in rotor's clone for MDF (asammdf), ``[tdms]``
(npTDMS), ``[mat]`` (h5py for v7.3; v5 is read by SciPy, always installed), ``[parquet]``
(pyarrow, also for Arrow/Feather files), ``[formats]`` for all. A file is recognised by its
first bytes (its format's magic), else by its suffix; a file of a format whose library is
missing is refused in one line naming the extra and the command that installs it.

**Channels.** A file holds named channels, in groups that share a time base: an MDF channel
group with its master channel, a TDMS group (its waveform timing, ``wf_increment``), the
vectors of one length of a ``.mat`` file (a matrix's columns are ``name[1]``, ``name[2]``,
…; a struct's fields ``struct.field``), a Parquet or Arrow table's columns. They become a
:class:`rotor.logs.reader.Log` as a text file's columns do:

- with no column spec, by their content (:func:`rotor.logs.channels.recognise_columns`,
  as for a text file), group by group from the longest, the first group whose channels
  hold a wheel signal; ``Log.notes`` says which group and which channel became what;
- with a spec of roles and the file's channel names, ``"time=t,encoder_d=CRANK"``
  (:func:`rotor.logs.reader.channel_map`), those channels; the time is the one named, else
  the group's time base, else the only channel named as a time (``time``, ``t``,
  ``timestamp``, any case, a unit after it; a struct's field by its own name), else the
  only one that increases on every row. The roles ``crank`` and ``cam`` take an analog or a digital channel as its content says
  (two levels: ``encoder_d``/``cam_d``), ``pressure`` is ``pressure_v``, ``speed`` is
  ``rpm``.

**Units** from the file's metadata (MDF channel units, TDMS ``unit_string``, Parquet/Arrow
field metadata ``unit``; a ``.mat`` file has none): a time in s, ms, µs or ns is read in
seconds, a speed in rpm, 1/min, rev/s, Hz or rad/s in rpm, and ``Log.notes`` says each
conversion; a time or speed channel in a unit that is no time or speed is refused, naming
it. A signal's own unit (V, bar, counts) is not used: only its shape is.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import os
import re
from collections.abc import Callable, Collection

import numpy as np

from ..checks import check_size
from ..errors import LogError

__all__ = [
    "FORMATS",
    "Format",
    "Channel",
    "ChannelGroup",
    "ROLE_ALIASES",
    "TIME_UNITS",
    "UNIT_COLUMNS",
    "SPEED_UNITS",
    "detect_format",
    "read_channels",
    "channels_to_read",
    "columns_from_groups",
]


@dataclasses.dataclass(frozen=True)
class Format:
    """A measurement format: its name in words, the file suffixes it is known by, the extra
    that installs its library and the modules that library provides."""

    name: str
    suffixes: tuple[str, ...]
    extra: str
    modules: tuple[str, ...]


FORMATS = {
    "mdf": Format("MDF (ASAM MDF 3/4)", (".mf4", ".mdf", ".mf3", ".dat"), "mdf", ("asammdf",)),
    "tdms": Format("TDMS (NI LabVIEW)", (".tdms",), "tdms", ("nptdms",)),
    "mat": Format("MATLAB v5", (".mat",), "mat", ("scipy.io",)),
    "mat73": Format("MATLAB v7.3 (HDF5)", (".mat",), "mat", ("h5py",)),
    "hdf5": Format("HDF5", (".h5", ".hdf5", ".hdf"), "mat", ("h5py",)),
    "parquet": Format("Parquet", (".parquet", ".pq"), "parquet", ("pyarrow.parquet",)),
    "arrow": Format("Arrow IPC / Feather", (".arrow", ".feather", ".ipc"), "parquet", ("pyarrow.feather",)),
}
"""Format key → :class:`Format`. ``.dat`` is read as MDF only when its first bytes say so
(a text ``.dat`` is a text log)."""

READ_BYTES_PER_VALUE_BYTE = 3
"""Memory that reading a channel takes per byte of its values as float64 [bytes]: the
library's copy, the float64 array and the log's own."""

_HDF5 = b"\x89HDF\r\n\x1a\n"
_MAGIC: tuple[tuple[int, bytes, str], ...] = (
    (0, b"MDF     ", "mdf"),
    (0, b"UnFinMF ", "mdf"),
    (0, b"TDSm", "tdms"),
    (0, b"PAR1", "parquet"),
    (0, b"ARROW1", "arrow"),
    (0, b"FEA1", "arrow"),
    (0, _HDF5, "hdf5"),
)

TIME_UNITS = {"s": 1.0, "sec": 1.0, "second": 1.0, "seconds": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9}
"""A time channel's unit (lower case, as the file's metadata writes it) → seconds per unit."""
TIME_UNITS["μs"] = 1e-6  # the Greek letter mu, beside the micro sign
SPEED_UNITS = {
    "rpm": 1.0,
    "1/min": 1.0,
    "min-1": 1.0,
    "min^-1": 1.0,
    "r/min": 1.0,
    "rev/min": 1.0,
    "u/min": 1.0,
    "rev/s": 60.0,
    "rps": 60.0,
    "hz": 60.0,
    "rad/s": 30.0 / math.pi,
}
"""A speed channel's unit (lower case) → rpm per unit."""

UNIT_COLUMNS = {
    "time_ms": ("time", 1e-3),
    "time_us": ("time", 1e-6),
    "tooth_time_ms": ("tooth_time_s", 1e-3),
    "tooth_time_us": ("tooth_time_s", 1e-6),
}
"""Column names of a time in other units (:data:`rotor.logs.reader.COLUMN_NAMES`): name →
(the name it is read as, seconds per unit)."""

ROLE_ALIASES = {
    "crank": ("encoder_v", "encoder_d"),
    "cam": ("cam_v", "cam_d"),
    "pressure": ("pressure_v",),
    "speed": ("rpm",),
}
"""Roles a column spec may use beside :data:`rotor.logs.reader.COLUMN_NAMES`: the analog or
digital form (two levels) as the channel's content says."""

_TIME_NAME = re.compile(r"\s*(time|t|timestamp|timestamps)\s*([\[(]\s*\w*\s*[\])]|_\w+)?\s*", re.IGNORECASE)
_MAX_LISTED = 40


@dataclasses.dataclass(frozen=True, eq=False)
class Channel:
    """One channel of a file: its ``name``, ``values`` (float64, one per sample) and
    ``unit`` as the file's metadata writes it (``""``: none)."""

    name: str
    values: np.ndarray
    unit: str = ""


@dataclasses.dataclass(frozen=True, eq=False)
class ChannelGroup:
    """Channels sampled on one time base: ``name`` (for messages), ``channels`` and
    ``time``, the group's time base as a channel (an MDF master, a TDMS waveform's timing),
    or None where one of the channels is the time; ``others``: the names of its channels
    not read (a spec named none of them)."""

    name: str
    channels: tuple[Channel, ...]
    time: Channel | None = None
    others: tuple[str, ...] = ()

    @property
    def rows(self) -> int:
        first = self.time if self.time is not None else (self.channels[0] if self.channels else None)
        return 0 if first is None else int(first.values.size)


def detect_format(path: str) -> str | None:
    """The :data:`FORMATS` key of the file at ``path`` by its first bytes, else by its
    suffix; None for a text log (or a path that is no readable file: the text reader
    names why). A file whose suffix names a format its first bytes are not is refused."""
    try:
        with open(path, "rb") as f:
            head = f.read(1024)
    except OSError:
        return None
    for at, magic, key in _MAGIC:
        if head[at : at + len(magic)] == magic:
            return key
    if head.startswith(b"MATLAB"):
        return "mat73" if head[512:520] == _HDF5 else "mat"
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".mat":
        return "mat" if head else None  # a version 4 MAT file has no text header: SciPy reads it
    for fmt in FORMATS.values():
        if suffix in fmt.suffixes and suffix != ".dat":
            raise LogError(
                f"{path}: named as a {fmt.name} file but its first bytes ({head[:8]!r}) are not one "
                f"(a damaged or renamed file?)"
            )
    return None


def _library(path: str, key: str, module: str):
    """The module ``module`` of the format ``key``'s library, or a LogError naming the extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        fmt = FORMATS[key]
        top = module.split(".")[0]
        raise LogError(
            f"{path}: reading a {fmt.name} file needs {top}, which is not installed: install rotor's "
            f"{fmt.extra!r} extra (pip install '.[{fmt.extra}]' in rotor's folder, or pip install {_package(top)})"
        ) from None


def _package(module: str) -> str:
    return {"nptdms": "npTDMS", "scipy": "scipy"}.get(module, module)


def _as_float(values, name: str, source: str) -> np.ndarray | None:
    """A channel's values as a 1-d float64 array (a timestamp as seconds from its first),
    or None for values that are no numbers (text, nested)."""
    a = np.asarray(values)
    if a.dtype.kind == "M":
        a = (a - a.reshape(-1)[0]).astype("timedelta64[ns]").astype(np.int64) * 1e-9 if a.size else a
    elif a.dtype.kind == "m":
        a = a.astype("timedelta64[ns]").astype(np.int64) * 1e-9
    if a.dtype.kind not in "biuf":
        return None
    a = np.squeeze(a)
    if a.ndim != 1:
        return None
    return a.astype(np.float64, copy=False)


# ---------------------------------------------------------------------------- the readers
def _read_mdf(path: str, wanted: frozenset[str] | None) -> list[ChannelGroup]:
    asammdf = _library(path, "mdf", "asammdf")
    try:
        mdf = asammdf.MDF(path)
    except Exception as e:  # the library's own error on a damaged file: its words, one line
        raise LogError(f"{path}: not a readable MDF file ({type(e).__name__}: {e})") from None
    groups = []
    try:
        plan = []
        for gi, group in enumerate(mdf.groups):
            master = mdf.masters_db.get(gi)
            names = [ch.name for ch in group.channels]
            take = [ci for ci in range(len(names)) if ci != master and _wanted(names[ci], wanted)]
            rest = tuple(names[ci] for ci in range(len(names)) if ci != master and ci not in take)
            plan.append((gi, group, master, names, take, rest))
        _budget(path, "mdf", sum(8.0 * int(g.channel_group.cycles_nr) * (len(t) + 1) for _, g, _, _, t, _ in plan))
        for gi, group, master, names, take, rest in plan:
            channels = []
            time = None
            for sig in mdf.select([(None, gi, ci) for ci in take]) if take else ():
                v = _as_float(sig.samples, sig.name, path)
                if v is None:
                    continue
                channels.append(Channel(str(sig.name), v, str(sig.unit or "").strip()))
                if time is None:
                    time = Channel(
                        names[master] if master is not None else "time", np.asarray(sig.timestamps, np.float64), "s"
                    )
            comment = str(getattr(group.channel_group, "comment", "") or "").strip()
            comment = "" if comment == "Python" else comment  # asammdf's own, where its writer gave none
            label = f"group {gi + 1}" + (f" ({comment[:40]})" if comment else "")
            groups.append(ChannelGroup(label, tuple(channels), time, rest))
    finally:
        mdf.close()
    return groups


def _read_tdms(path: str, wanted: frozenset[str] | None) -> list[ChannelGroup]:
    nptdms = _library(path, "tdms", "nptdms")
    try:
        tdms = nptdms.TdmsFile.open(path)  # the channels' data read on access
    except Exception as e:
        raise LogError(f"{path}: not a readable TDMS file ({type(e).__name__}: {e})") from None
    groups = []
    with tdms:
        chosen = [(g, ch) for g in tdms.groups() for ch in g.channels() if _wanted(ch.name, wanted)]
        _budget(path, "tdms", sum(8.0 * len(ch) for _, ch in chosen))
        for g in tdms.groups():
            by_base: dict[tuple, list[Channel]] = {}
            times: dict[tuple, Channel | None] = {}
            rest = []
            for ch in g.channels():
                if not _wanted(ch.name, wanted):
                    rest.append(str(ch.name))
                    continue
                v = _as_float(ch[:], ch.name, path)
                if v is None:
                    continue
                props = ch.properties
                inc = props.get("wf_increment")
                base = (v.size, float(props.get("wf_start_offset", 0.0)), float(inc) if inc else None)
                if base not in times:
                    times[base] = None
                    if inc:
                        unit = str(props.get("wf_xunit_string", "s") or "s")
                        times[base] = Channel("time", base[1] + float(inc) * np.arange(v.size, dtype=np.float64), unit)
                by_base.setdefault(base, []).append(Channel(str(ch.name), v, str(props.get("unit_string", "") or "")))
            for k, (base, chans) in enumerate(by_base.items()):
                label = f"group {g.name!r}" + (f" ({k + 1})" if len(by_base) > 1 else "")
                groups.append(ChannelGroup(label, tuple(chans), times[base], tuple(rest) if k == 0 else ()))
            if not by_base and rest:
                groups.append(ChannelGroup(f"group {g.name!r}", (), None, tuple(rest)))
    return groups


def _read_mat(path: str, wanted: frozenset[str] | None) -> list[ChannelGroup]:
    sio = _library(path, "mat", "scipy.io")
    _budget(path, "mat", float(os.path.getsize(path)) * 2)  # read whole, then copied as float64
    try:
        data = sio.loadmat(path, simplify_cells=True)
    except NotImplementedError:  # a v7.3 file without the text header SciPy looks for
        return _read_hdf5(path, wanted, "mat73")
    except Exception as e:
        raise LogError(f"{path}: not a readable MATLAB file ({type(e).__name__}: {e})") from None
    flat: list[tuple[str, object]] = []

    def walk(prefix: str, value: object) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                if not k.startswith("__"):
                    walk(f"{prefix}.{k}" if prefix else k, v)
        else:
            flat.append((prefix, value))

    walk("", data)
    return _vectors(path, flat)


def _read_hdf5(path: str, wanted: frozenset[str] | None, key: str = "hdf5") -> list[ChannelGroup]:
    h5py = _library(path, key, "h5py")
    flat: list[tuple[str, object]] = []
    try:
        with h5py.File(path, "r") as f:
            found = []

            def visit(name: str, obj: object) -> None:
                if isinstance(obj, h5py.Dataset) and not name.startswith("#"):
                    cls = obj.attrs.get("MATLAB_class", b"")
                    cls = cls.decode() if isinstance(cls, bytes) else str(cls)
                    if cls in ("char", "cell", "struct", "function_handle") or obj.dtype.kind not in "biuf":
                        return
                    found.append((name.replace("/", "."), obj))

            f.visititems(visit)
            # a matrix's columns are named name[j]: it is read where its own name or a column's is wanted
            chosen = [(n, d) for n, d in found if wanted is None or _wanted(n, wanted) or n.lower() in _stems(wanted)]
            _budget(path, key, sum(8.0 * d.size for _, d in chosen))
            for name, d in chosen:
                a = d[()]
                flat.append((name, a.T if key == "mat73" else a))  # MATLAB writes column-major
            rest = tuple(n for n, _ in found if all(n != c for c, _ in chosen))
    except OSError as e:
        raise LogError(f"{path}: not a readable HDF5 file ({e})") from None
    return _vectors(path, flat) + ([ChannelGroup("arrays not read", (), None, rest)] if rest else [])


def _vectors(path: str, flat: list[tuple[str, object]]) -> list[ChannelGroup]:
    """Channel groups of a ``.mat``/HDF5 file's numeric arrays: vectors (a row or a column)
    and the columns of matrices of more rows than columns, grouped by their length."""
    by_len: dict[int, list[Channel]] = {}
    for name, value in flat:
        a = np.asarray(value)
        if a.dtype.kind not in "biuf" or a.size < 3:
            continue
        if a.ndim == 2 and min(a.shape) == 1 or a.ndim == 1:
            v = a.reshape(-1).astype(np.float64)
            by_len.setdefault(v.size, []).append(Channel(name, v))
        elif a.ndim == 2 and a.shape[1] < a.shape[0] and a.shape[1] <= 256:
            for j in range(a.shape[1]):
                by_len.setdefault(a.shape[0], []).append(Channel(f"{name}[{j + 1}]", a[:, j].astype(np.float64)))
    return [ChannelGroup(f"arrays of {n} values", tuple(ch)) for n, ch in by_len.items()]


def _read_arrow(path: str, wanted: frozenset[str] | None, key: str) -> list[ChannelGroup]:
    module = "pyarrow.parquet" if key == "parquet" else "pyarrow.feather"
    pa = _library(path, key, module)
    try:
        if key == "parquet":
            meta = pa.ParquetFile(path)
            names, rows = list(meta.schema_arrow.names), int(meta.metadata.num_rows)
        else:
            names, rows = _arrow_names(path), None
        take = [n for n in names if _wanted(n, wanted)]
        _budget(path, key, 8.0 * (rows if rows is not None else os.path.getsize(path) / 8) * max(len(take), 1))
        table = pa.read_table(path, columns=take)
    except LogError:
        raise
    except Exception as e:
        raise LogError(f"{path}: not a readable {FORMATS[key].name} file ({type(e).__name__}: {e})") from None
    rest = tuple(n for n in names if n not in take)
    channels = []
    for field, column in zip(table.schema, table.columns):
        meta = {
            k.decode(errors="replace").lower(): v.decode(errors="replace") for k, v in (field.metadata or {}).items()
        }
        try:
            values = column.to_numpy(zero_copy_only=False)
        except Exception:  # a nested or text column: not a channel
            continue
        if values.dtype == object:
            continue
        v = _as_float(values, field.name, path)
        if v is None:
            continue
        if column.null_count:
            v = v.copy()
            v[np.asarray(column.is_null(), dtype=bool)] = np.nan  # refused by the log's checks, naming the row
        channels.append(Channel(str(field.name), v, meta.get("unit", meta.get("units", "")).strip()))
    return [ChannelGroup("the table", tuple(channels), None, rest)] if channels or rest else []


def _arrow_names(path: str) -> list[str]:
    """The column names of an Arrow IPC / Feather file, from its schema alone."""
    import pyarrow.ipc as ipc

    try:
        with ipc.open_file(path) as reader:
            return list(reader.schema.names)
    except Exception:  # Feather version 1: the whole table is read to learn its names
        import pyarrow.feather as feather

        return list(feather.read_table(path).schema.names)


def _wanted(name: str, wanted: frozenset[str] | None) -> bool:
    """Whether the channel ``name`` is to be read: every channel without a spec, else the
    ones it names (in any case)."""
    return wanted is None or str(name).lower() in wanted


def _stems(wanted: frozenset[str]) -> set[str]:
    """The matrices whose columns ``wanted`` names (``data[2]`` → ``data``)."""
    return {w.rsplit("[", 1)[0] for w in wanted if w.endswith("]")}


def _budget(path: str, key: str, n_bytes: float) -> None:
    """Refuse reading ``n_bytes`` of channels (float64) beyond the memory budget, before reading."""
    check_size(
        float(n_bytes) * READ_BYTES_PER_VALUE_BYTE,
        f"{path}: reading the channels of this {os.path.getsize(path) / 1e6:.3g} MB {FORMATS[key].name} file",
        "name only the channels needed (columns='time=…,encoder_v=…'), export the part of the recording needed, or "
        "set ROTOR_MEMORY_LIMIT_GB [GB] higher on a machine with the memory",
        error=LogError,
    )


_READERS: dict[str, Callable[[str, frozenset[str] | None], list[ChannelGroup]]] = {
    "mdf": _read_mdf,
    "tdms": _read_tdms,
    "mat": _read_mat,
    "mat73": lambda p, w: _read_hdf5(p, w, "mat73"),
    "hdf5": _read_hdf5,
    "parquet": lambda p, w: _read_arrow(p, w, "parquet"),
    "arrow": lambda p, w: _read_arrow(p, w, "arrow"),
}


def channels_to_read(key: str, spec: dict[str, str] | None) -> list[str] | None:
    """The channel names a spec (role → name) needs read from a file of format ``key``:
    those it names; every channel (None) without a spec, or where it names no time and
    the format has no time base of its own (a table's time is found among its columns)."""
    if spec is None:
        return None
    timed = any(UNIT_COLUMNS.get(role, (role,))[0] in ("time", "tooth_time_s") for role in spec)
    if not timed and key not in ("mdf", "tdms"):
        return None
    return list(spec.values())


def read_channels(path: str, key: str, names: Collection[str] | None = None) -> list[ChannelGroup]:
    """The channel groups of the file at ``path`` of format ``key`` (:func:`detect_format`),
    read through its library: every channel, or with ``names`` only those (in any case;
    the others' names are kept for messages). A LogError naming the file where it cannot
    be read, holds no numeric channel, or its channels would not fit the memory budget."""
    wanted = frozenset(str(n).lower() for n in names) if names is not None else None
    groups = [g for g in _READERS[key](path, wanted) if (g.channels and g.rows > 0) or g.others]
    if not any(g.channels for g in groups) and wanted is None:
        raise LogError(f"{path}: a {FORMATS[key].name} file without a channel of numbers")
    return groups


# ---------------------------------------------------------------------------- the log
def _listing(groups: list[ChannelGroup]) -> str:
    """The file's channel names, group by group, for a message."""
    parts, shown = [], 0
    for g in groups:
        names = [c.name for c in g.channels] + list(g.others)
        room = max(0, _MAX_LISTED - shown)
        text = ", ".join(repr(n) for n in names[:room]) + (
            f", … ({len(names) - room} more)" if len(names) > room else ""
        )
        shown += len(names)
        parts.append(f"{g.name}: {text}" if len(groups) > 1 else text)
    return "; ".join(parts)


def _find(source: str, groups: list[ChannelGroup], name: str, role: str) -> list[tuple[int, Channel]]:
    """(group index, channel) of each channel called ``name``: by its exact name, else in
    another case (a group's time base too); a LogError listing the file's channels where
    there is none."""
    hits = [(i, c) for i, g in enumerate(groups) for c in g.channels if c.name == name]
    if not hits:
        hits = [(i, c) for i, g in enumerate(groups) for c in g.channels if c.name.lower() == name.lower()]
    if not hits:
        hits = [(i, g.time) for i, g in enumerate(groups) if g.time is not None and g.time.name.lower() == name.lower()]
    if not hits:
        raise LogError(f"{source}: no channel {name!r} (named for {role}); the file's channels: {_listing(groups)}")
    return hits


def _one_group(source: str, groups: list[ChannelGroup], spec: dict[str, str]) -> tuple[int, dict[str, Channel]]:
    """The group of the channels ``spec`` names and each role's channel: a name found in
    several groups (an MDF file's master channels are all ``time``) is the one in the group
    of the others."""
    found = {role: _find(source, groups, name, role) for role, name in spec.items()}
    sure = {role: hits[0][0] for role, hits in found.items() if len({i for i, _ in hits}) == 1}
    where = set(sure.values())
    if len(where) > 1:
        shown = "; ".join(f"{spec[r]!r} in {groups[i].name}" for r, i in sure.items())
        raise LogError(
            f"{source}: the channels named are sampled on different time bases ({shown}); name channels of one "
            f"group, or resample them onto one time base when exporting"
        )
    common = set.intersection(*({i for i, _ in hits} for hits in found.values()))
    gi = where.pop() if where else min(common) if len(common) == 1 else None
    if gi is None or gi not in common:
        role = next(r for r, hits in found.items() if gi is None or gi not in {i for i, _ in hits})
        shown = ", ".join(groups[i].name for i, _ in found[role])
        raise LogError(
            f"{source}: channel {spec[role]!r} is in "
            + (f"several groups ({shown})" if len(found[role]) > 1 else f"{shown}, the other channels named in another")
            + "; name channels of one group"
        )
    return gi, {role: next(c for i, c in hits if i == gi) for role, hits in found.items()}


def _role_of(role: str, channel: Channel) -> str:
    """The column name of a role of the spec: an alias takes the digital form for a
    channel of two levels."""
    if role not in ROLE_ALIASES:
        return role
    forms = ROLE_ALIASES[role]
    if len(forms) == 1:
        return forms[0]
    two = np.unique(channel.values[: min(channel.values.size, 100_000)]).size == 2
    return forms[1] if two else forms[0]


def _unit_factor(source: str, channel: Channel, column: str, notes: list[str]) -> tuple[str, float]:
    """(the column's SI name, the factor to it) of a time or speed channel by its unit."""
    unit = channel.unit.strip()
    low = unit.lower()
    canon = UNIT_COLUMNS[column][0] if column in UNIT_COLUMNS else column
    if canon in ("time", "tooth_time_s"):
        if column in UNIT_COLUMNS:  # the spec states the unit
            factor = UNIT_COLUMNS[column][1]
            if low and TIME_UNITS.get(low, factor) != factor:
                raise LogError(
                    f"{source}: channel {channel.name!r} is in {unit!r} by the file, but the column spec reads it as "
                    f"{column!r}; name it {canon!r} to take the file's unit"
                )
            return canon, factor
        if not low:
            return canon, 1.0
        if low not in TIME_UNITS:
            raise LogError(
                f"{source}: channel {channel.name!r} is in {unit!r}, not a time unit ({', '.join(TIME_UNITS)}); "
                f"is it the {canon!r} channel?"
            )
        return canon, TIME_UNITS[low]
    if canon == "rpm" and low and low not in SPEED_UNITS:
        raise LogError(
            f"{source}: channel {channel.name!r} is in {unit!r}, not a speed unit rotor converts "
            f"({', '.join(SPEED_UNITS)}); is it the speed channel?"
        )
    if canon == "rpm" and low:
        return canon, SPEED_UNITS[low]
    return canon, 1.0


def _time_of(source: str, group: ChannelGroup, taken: set[str]) -> Channel:
    """The time of a group whose spec names none: its time base, else the only channel named
    as a time, else the only channel that increases on every row."""
    if group.time is not None:
        return group.time
    rest = [c for c in group.channels if c.name not in taken]
    named = [c for c in rest if _TIME_NAME.fullmatch(c.name.rsplit(".", 1)[-1])]  # a struct's field: its own name
    if len(named) == 1:
        return named[0]
    rising = [c for c in rest if c.values.size > 1 and bool(np.all(np.diff(c.values) > 0))]
    if len(rising) == 1:
        return rising[0]
    which = named or rising
    raise LogError(
        f"{source}: the column spec names no time, and "
        + (
            f"{', '.join(repr(c.name) for c in which)} could each be it"
            if which
            else f"no channel of {group.name} increases on every row"
        )
        + "; name it (time=…)"
    )


def _pinned(source: str, groups: list[ChannelGroup], spec: dict[str, str], notes: list[str]) -> dict[str, np.ndarray]:
    """The columns a spec of roles and channel names gives."""
    gi, found = _one_group(source, groups, spec)
    group = groups[gi]
    columns = {_role_of(role, ch): ch for role, ch in found.items()}
    canon = {_unit_factor(source, ch, col, notes)[0] for col, ch in columns.items()}
    if not canon & {"time", "tooth_time_s"}:
        t = _time_of(source, group, {c.name for c in columns.values()})
        columns = {"time": t, **columns}
    said = []
    out: dict[str, np.ndarray] = {}
    for col, ch in columns.items():
        name, factor = _unit_factor(source, ch, col, notes)
        out[name] = ch.values * factor if factor != 1.0 else ch.values
        unit = f" [{ch.unit}]" if ch.unit else ""
        conv = f", × {factor:g} to {'s' if name in ('time', 'tooth_time_s') else 'rpm'}" if factor != 1.0 else ""
        said.append(f"{ch.name!r}{unit} → {name}{conv}")
    notes.append(f"channels read ({group.name}): " + "; ".join(said))
    return out


def _recognised(source: str, groups: list[ChannelGroup], notes: list[str]) -> dict[str, np.ndarray]:
    """The columns of the first group, longest first, whose channels are recognised by their
    content (:func:`rotor.logs.channels.recognise_columns`)."""
    from .channels import recognise_columns

    order = sorted(range(len(groups)), key=lambda i: -groups[i].rows)
    first_error: LogError | None = None
    for i in order:
        g = groups[i]
        chans = ([g.time] if g.time is not None else []) + list(g.channels)
        if len(chans) < 2 or g.rows < 3:
            continue
        data = np.column_stack([c.values for c in chans])
        units = [c.unit for c in chans]
        try:
            names, said = recognise_columns([c.name for c in chans], data, units=units, source=source)
        except LogError as e:
            first_error = first_error or e
            continue
        out: dict[str, np.ndarray] = {}
        conv = []
        for col, ch in zip(names, chans):
            if col == "-":
                continue
            name, factor = _unit_factor(source, ch, col, notes)
            if col in ("time_ms", "time_us") and ch.unit:  # the name said ms/µs; the file's unit decides
                name, factor = _unit_factor(source, ch, "time", notes)
            out[name] = ch.values * factor if factor != 1.0 else ch.values
            if factor != 1.0:
                conv.append(
                    f"{ch.name!r} [{ch.unit or col[5:]}] read in {'s' if name == 'time' else 'rpm'} (× {factor:g})"
                )
        if len(groups) > 1:
            notes.append(f"{g.name} read ({g.rows} samples), the first whose channels hold a wheel signal")
        notes.extend(said)
        notes.extend(conv)
        return out
    if first_error is not None and len(groups) == 1:
        raise first_error
    raise LogError(
        f"{source}: no group of channels holds a wheel signal that can be told by its content"
        + (f" ({first_error})" if first_error is not None else "")
        + f"; name the channels (columns='time=…,encoder_v=…'); the file's channels: {_listing(groups)}"
    )


def columns_from_groups(
    source: str, groups: list[ChannelGroup], spec: dict[str, str] | None, notes: list[str]
) -> dict[str, np.ndarray]:
    """The columns (:data:`rotor.logs.reader.COLUMN_NAMES`, times in seconds, speeds in
    rpm) of a file's channel groups, for a :class:`rotor.logs.reader.Log`: the channels
    ``spec`` (role → channel name, :func:`rotor.logs.reader.channel_map`) names, or with
    ``spec`` None those recognised by their content (see the module doc). ``source``: the
    file's name for messages; what was read as what is appended to ``notes``."""
    return _pinned(source, groups, spec, notes) if spec else _recognised(source, groups, notes)
