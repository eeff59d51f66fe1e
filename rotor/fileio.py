"""Writing files whole or not at all, JSON files saved and loaded one way, and the one
CSV writer (no NaN or infinity written).

Ground floor: imports nothing from rotor but :mod:`rotor.errors`.
"""

from __future__ import annotations

import errno
import json
import math
import numbers
import os
import secrets
import stat
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from .errors import InternalError

__all__ = ["atomic_path", "csv_text", "find_nonfinite", "key_path_text", "load_json", "save_json", "write_text_atomic"]

PathArg = str | os.PathLike
"""A file's path: a ``str`` or a path-like object (``pathlib.Path``)."""


def _check_path(path: object, argument: str = "path") -> str:
    """``path`` as a ``str``; a ``TypeError`` naming ``argument`` when it is not a path."""
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{argument} = {path!r}: expected a file's path (a str or pathlib.Path)")
    out = os.fspath(path)
    if not isinstance(out, str):
        raise TypeError(f"{argument} = {path!r}: expected a file's path (a str or pathlib.Path)")
    if not out:
        raise FileNotFoundError(errno.ENOENT, "an empty path: give a file name", out)
    return out


def key_path_text(keys: list) -> str:
    """``["cycles", 3, "mean_rpm"]`` as ``"cycles"[3]["mean_rpm"]``: where a value sits in
    nested JSON data (keys quoted, list indices bare)."""
    out = ""
    for i, k in enumerate(keys):
        if isinstance(k, int):
            out += f"[{k}]"
        else:
            out += f'"{k}"' if i == 0 else f'["{k}"]'
    return out or "the value"


def find_nonfinite(data: Any) -> tuple[list, str] | None:
    """The first NaN or infinity in ``data`` (nested dicts, lists, tuples and numbers): its
    key path (a list of dict keys and list indices, see :func:`key_path_text`) and what it
    is (``"NaN"``, ``"Infinity"`` or ``"-Infinity"``); ``None`` when every number is finite."""
    stack: list[tuple[list, Any]] = [([], data)]
    while stack:
        keys, x = stack.pop()
        if isinstance(x, dict):
            stack.extend((keys + [k], v) for k, v in reversed(list(x.items())))
        elif isinstance(x, (list, tuple)):
            stack.extend((keys + [i], v) for i, v in reversed(list(enumerate(x))))
        elif isinstance(x, numbers.Real) and not isinstance(x, numbers.Integral):
            f = float(x)
            if not math.isfinite(f):
                return keys, "NaN" if math.isnan(f) else ("Infinity" if f > 0 else "-Infinity")
    return None


def _new_file_beside(path: str) -> str:
    """Create an empty file with a fresh name in ``path``'s folder and return its name.

    It is created by ``os.open(..., 0o666)``, so the operating system applies the user's
    umask (and a folder's default ACL) exactly as for a plain ``open(path, "w")``; a
    ``tempfile.mkstemp`` file would be mode 0600 whatever the umask."""
    folder = os.path.dirname(os.path.abspath(path))
    suffix = os.path.splitext(path)[1]
    for _ in range(100):
        tmp = os.path.join(folder, f".rotor-{secrets.token_hex(4)}{suffix}")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return tmp
    raise FileExistsError(errno.EEXIST, "no free temporary name in the folder", path)


def _check_writable_path(path: str) -> None:
    """A one-line ``OSError`` naming ``path`` when no file can be written there: a folder's
    name, a folder that does not exist, or a "folder" that is a file."""
    if path.endswith(("/", os.sep)) or os.path.isdir(path):
        raise IsADirectoryError(errno.EISDIR, "is a folder: give a file name", path)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        parent = folder
        while parent and not os.path.exists(parent) and os.path.dirname(parent) != parent:
            parent = os.path.dirname(parent)
        if os.path.exists(parent) and not os.path.isdir(parent):
            raise NotADirectoryError(errno.ENOTDIR, f"{parent} is a file, not a folder", path)
        raise FileNotFoundError(errno.ENOENT, f"no folder {folder} (make it first)", path)


@contextmanager
def atomic_path(path: PathArg) -> Iterator[str]:
    """Yield a temporary path beside ``path`` (a file's path); rename it onto ``path`` if
    the block succeeds, delete it if not. A reader never sees half a file, and an error
    leaves an existing file as it was.

    **Mode:** the file ends with the mode a plain ``open(path, "w")`` gives it: a new file
    gets ``0o666 & ~umask``; a file that is replaced keeps its mode.
    **Errors:** an ``OSError`` raised while writing or renaming names ``path``, never the
    temporary file: a folder's name, a missing folder or a "folder" that is a file are
    refused before anything is written. A ``path`` that is not a ``str`` or path-like
    object raises ``TypeError``."""
    path = _check_path(path)
    _check_writable_path(path)
    tmp = None
    try:
        tmp = _new_file_beside(path)
        try:
            old_mode = stat.S_IMODE(os.stat(path).st_mode) if os.path.isfile(path) else None
            if old_mode is not None:
                os.chmod(tmp, old_mode)
        except OSError:
            pass  # keeping the old mode is a courtesy; the write goes on with the umask's
        yield tmp
        os.replace(tmp, path)
    except OSError as e:
        names_tmp = tmp is not None and (str(e.filename).startswith(tmp) or e.filename2 == tmp)
        if e.filename is None or names_tmp or e.filename == os.path.dirname(os.path.abspath(path)):
            raise type(e)(e.errno or errno.EIO, e.strerror or str(e), path) from None
        raise
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.remove(tmp)


def write_text_atomic(path: PathArg, text: str) -> None:
    """Write ``text`` to ``path`` (a file's path) whole or not at all; an ``OSError`` names
    ``path``."""
    if not isinstance(text, str):
        raise TypeError(f"text: expected a str, got {type(text).__name__}")
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            f.write(text)


def _check_what_error(what: object, error: object) -> None:
    if not isinstance(what, str):
        raise TypeError(f"what = {what!r}: expected words (a str) saying what the file holds")
    if not (isinstance(error, type) and issubclass(error, Exception)):
        raise TypeError(f"error = {error!r}: expected an exception class such as OSError")


def save_json(path: PathArg, data: dict, *, what: str, error: type[Exception] = OSError) -> None:
    """Write ``data`` as indented JSON (never NaN nor Infinity) to ``path``, whole or not at all.

    **Arguments:** ``path``: the file (a ``str`` or ``pathlib.Path``); ``data``: plain JSON
    data (a dict); ``what``: what the file holds, in words, for the error (e.g. ``"the
    calibration"``); ``error``: the exception class raised, with a one-line message naming
    the file, when the folder is missing, the file cannot be written, or ``data`` holds a
    NaN or an infinity (named by its key path). Arguments of the wrong type raise
    ``TypeError`` naming the argument."""
    path = _check_path(path)
    _check_what_error(what, error)
    if not isinstance(data, dict):
        raise TypeError(f"data: expected a dict of plain JSON data, got {type(data).__name__}")
    found = find_nonfinite(data)
    if found is not None:
        raise error(f"{path}: cannot write {what}: its {key_path_text(found[0])} is {found[1]}, not a number")
    try:
        text = json.dumps(data, indent=1, allow_nan=False) + "\n"
    except TypeError as e:
        raise TypeError(f"data: not plain JSON data ({e})") from None
    try:
        write_text_atomic(path, text)
    except OSError as e:
        raise error(f"{path}: cannot write {what}: {e.strerror or e}") from None


def load_json(path: PathArg, *, what: str, error: type[Exception] = OSError) -> object:
    """Read the JSON file ``path`` (a ``str`` or ``pathlib.Path``); a file that is not JSON
    (or not UTF-8 text) raises ``error`` with a one-line message ("``path``: not ``what``
    (JSON: …)"). ``what``: e.g. ``"a calibration file"``. Arguments of the wrong type raise
    ``TypeError`` naming the argument; a file that cannot be opened, an ``OSError`` naming
    ``path``."""
    path = _check_path(path)
    _check_what_error(what, error)
    if os.path.isdir(path):
        raise IsADirectoryError(errno.EISDIR, "is a folder, not a file", path)
    try:
        with open(path, encoding="utf-8-sig") as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise error(f"{path}: not {what} (JSON: {e})") from None
    except UnicodeDecodeError as e:
        raise error(f"{path}: not {what} (not UTF-8 text: {e.reason} at byte {e.start})") from None
    except RecursionError:
        raise error(f"{path}: not {what} (JSON nested too deep)") from None


def csv_text(header: Sequence[str], rows: Iterable[Sequence[float]], what: str = "the table") -> str:
    """A table as CSV text: the ``header`` line, then one line per row of numbers (each
    with 10 significant digits, never ``-0``), ending in a newline.

    A NaN or an infinity is refused, never written: an :class:`rotor.errors.InternalError`
    names its column and row (counted from 1), e.g. ``the table's "s_m" in row 3 is NaN``
    (``what`` names the table). Numbers keep the units of their column's name."""
    header = [str(h) for h in header]
    lines = [",".join(header)]
    for i, row in enumerate(rows, start=1):
        values = [float(v) for v in row]
        if len(values) != len(header):
            raise InternalError(f"{what}'s row {i} has {len(values)} values for {len(header)} columns")
        for name, v in zip(header, values):
            if not math.isfinite(v):
                kind = "NaN" if math.isnan(v) else ("Infinity" if v > 0 else "-Infinity")
                raise InternalError(f'{what}\'s "{name}" in row {i} is {kind}: a number that should exist does not')
        lines.append(",".join(f"{v + 0.0:.10g}" for v in values))  # + 0.0: no "-0"
    return "\n".join(lines) + "\n"
