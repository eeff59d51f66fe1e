"""Writing files whole or not at all, JSON files saved and loaded one way, and the one
CSV writer (no NaN or infinity written).

Base layer: imports nothing from rotor but :mod:`rotor.errors`.
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

__all__ = [
    "INTERRUPT",
    "atomic_path",
    "check_folder_writable",
    "check_writable_file",
    "csv_text",
    "find_nonfinite",
    "key_path_text",
    "load_json",
    "made_folders",
    "save_json",
    "write_text_atomic",
]

PathArg = str | os.PathLike
"""A file's path: a ``str`` or a path-like object (``pathlib.Path``)."""


class _Interrupt:
    """Whether an interrupt (Ctrl-C) has arrived, kept as a flag: a ``KeyboardInterrupt``
    raised where Python cannot pass it on (inside a garbage collector's callback, which
    JAX registers) is only printed and dropped, and the flag is what is left of it.

    The command line sets it from its SIGINT handler (:meth:`set`); every writer of this
    module asks it (:meth:`check`) before it puts a file in place, and the command line
    again before it exits 0, so that a dropped interrupt still stops the run (exit 130)
    with nothing put in place."""

    def __init__(self) -> None:
        self._set = False

    def set(self) -> None:
        self._set = True

    def clear(self) -> None:
        self._set = False

    def __bool__(self) -> bool:
        return self._set

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if an interrupt has arrived."""
        if self._set:
            raise KeyboardInterrupt


INTERRUPT = _Interrupt()
"""The interrupt flag of this process (see :class:`_Interrupt`)."""


def _writable_folder(folder: str) -> bool:
    """Whether files can be made in the existing ``folder``: by this user, on this file
    system (read-only, or one that refuses new files whatever the permissions say). Tried:
    a hidden folder of a fresh name is made and removed at once."""
    if not os.access(folder, os.W_OK | os.X_OK):
        return False
    for _ in range(10):
        probe = os.path.join(folder, f".rotor-probe-{secrets.token_hex(4)}")
        try:
            os.mkdir(probe)
        except FileExistsError:
            continue
        except OSError:
            return False
        try:
            os.rmdir(probe)
        except OSError:
            pass
        return True
    return True


def check_folder_writable(folder: PathArg, what: str = "the output") -> None:
    """A one-line ``OSError`` naming ``folder`` where ``what`` could not be written into it:
    a link that points nowhere, a file, or a folder (the nearest existing one above a new
    folder) that this user cannot write. Nothing is made: a check before the work starts."""
    folder = _check_path(folder, "folder")
    if os.path.islink(folder) and not os.path.exists(folder):
        raise FileNotFoundError(
            errno.ENOENT, f"is a link to {os.readlink(folder)}, which does not exist: give a folder for {what}", folder
        )
    if os.path.exists(folder):
        if not os.path.isdir(folder):
            raise NotADirectoryError(errno.ENOTDIR, f"is a file, not a folder for {what}: give a folder", folder)
        if not _writable_folder(folder):
            raise PermissionError(errno.EACCES, f"cannot write {what} into this folder (permission denied)", folder)
        return
    parent = os.path.dirname(os.path.abspath(folder))
    while not os.path.exists(parent) and os.path.dirname(parent) != parent:
        if os.path.islink(parent):
            raise FileNotFoundError(errno.ENOENT, f"{parent} is a link to nothing: give a folder for {what}", folder)
        parent = os.path.dirname(parent)
    if not os.path.isdir(parent):
        raise NotADirectoryError(errno.ENOTDIR, f"{parent} is a file, not a folder", folder)
    if not _writable_folder(parent):
        raise PermissionError(errno.EACCES, f"cannot make the folder for {what}: {parent} is not writable", folder)


@contextmanager
def made_folders(folder: PathArg) -> Iterator[str]:
    """Make ``folder`` and its missing parents (``os.makedirs``); yield it; if the block
    fails (an error or Ctrl-C), remove again every folder made here that is still empty,
    so that a failed command leaves none of its folders behind. An ``OSError`` while
    making them names ``folder``."""
    folder = _check_path(folder, "folder")
    made = []
    here = os.path.abspath(folder)
    while not os.path.exists(here) and os.path.dirname(here) != here:
        made.append(here)
        here = os.path.dirname(here)
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as e:
        _remove_empty(made)
        raise type(e)(e.errno or errno.EIO, e.strerror or str(e), folder) from None
    try:
        yield folder
    except BaseException:
        _remove_empty(made)
        raise


def _remove_empty(folders: list[str]) -> None:
    """Remove ``folders`` (deepest first) where they are empty; leave the others."""
    for f in folders:
        try:
            os.rmdir(f)
        except OSError:
            break


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
        except OSError as e:  # named by the user's path, never the temporary name
            raise type(e)(e.errno or errno.EIO, e.strerror or str(e), path) from None
        os.close(fd)
        return tmp
    raise FileExistsError(errno.EEXIST, "no free temporary name in the folder", path)


def check_writable_file(path: PathArg) -> None:
    """A one-line ``OSError`` naming ``path`` when no file can be written there: a folder's
    name, a folder that does not exist, a "folder" that is a file, or a folder this user
    cannot write. Nothing is made: a check before the work starts."""
    path = _check_path(path)
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
    if not _writable_folder(folder):
        raise PermissionError(errno.EACCES, f"cannot write into the folder {folder} (permission denied)", path)


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
    check_writable_file(path)
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
        INTERRUPT.check()  # an interrupt that was dropped still stops the file being put in place
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
