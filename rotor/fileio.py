"""Writing files whole or not at all, JSON files saved and loaded one way, and the one
CSV writer (no NaN or infinity written).

**Where a file is written.** Every file rotor writes goes through :func:`atomic_path`
(or :func:`atomic_paths`, several files put in place together, all or none), which
checks the target first (:func:`check_writable_file`): a file is written onto a new name
or onto an existing regular file, never onto a folder, a device (``/dev/null``), a named
pipe, a socket or a symbolic link (the link is neither replaced nor written through; the
error names where it points).

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
    "ROUND_OFF",
    "zeros_as_zero",
    "atomic_path",
    "atomic_paths",
    "check_folder_writable",
    "check_writable_file",
    "csv_text",
    "find_nonfinite",
    "json_file_text",
    "key_path_text",
    "load_json",
    "made_folders",
    "save_json",
    "write_text_atomic",
    "write_texts_atomic",
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


def _not_a_file_kind(mode: int) -> str | None:
    """What an existing entry of ``mode`` (``st_mode`` of ``os.lstat``) is, where a file
    cannot be written onto it: ``"a device"``, ``"a named pipe (FIFO)"``, …; ``None`` for a
    regular file."""
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISFIFO(mode):
        return "a named pipe (FIFO)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _check_target(path: str) -> None:
    """A one-line ``OSError`` naming ``path`` where what is there now is not a regular file
    a write may replace: a symbolic link (named with where it points), a folder, a device,
    a named pipe or a socket. Nothing there is fine."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    except OSError:
        return  # a parent that cannot be searched: the folder's own check names it
    if stat.S_ISLNK(mode):
        try:
            where = os.readlink(path)
        except OSError:
            where = "another file"
        raise OSError(
            errno.EEXIST,
            f"is a link to {where}: rotor writes no file through a link; give a file name of its own",
            path,
        )
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, "is a folder: give a file name", path)
    kind = _not_a_file_kind(mode)
    if kind is not None:
        raise OSError(errno.EEXIST, f"is {kind}, not a regular file: give a file name", path)


def check_writable_file(path: PathArg) -> None:
    """A one-line ``OSError`` naming ``path`` when no file can be written there: a folder's
    name, a folder that does not exist, a "folder" that is a file, a folder this user
    cannot write, or something that exists and is not a regular file (a symbolic link,
    named with where it points; a device, a named pipe, a socket). Nothing is made: a check
    before the work starts."""
    path = _check_path(path)
    if path.endswith(("/", os.sep)):
        raise IsADirectoryError(errno.EISDIR, "is a folder: give a file name", path)
    _check_target(path)
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


def _user_error(e: OSError, path: str, tmp: str | None) -> OSError | None:
    """``e`` renamed to name ``path`` where it names the temporary file ``tmp``, the folder
    or nothing; ``None`` where it names another file (then raised as it is)."""
    names_tmp = tmp is not None and (str(e.filename).startswith(tmp) or e.filename2 == tmp)
    if e.filename is None or names_tmp or e.filename == os.path.dirname(os.path.abspath(path)):
        return type(e)(e.errno or errno.EIO, e.strerror or str(e), path)
    return None


def _keep_mode(path: str, tmp: str) -> None:
    """Give ``tmp`` the mode of the regular file ``path`` it will replace, if any."""
    try:
        old_mode = stat.S_IMODE(os.stat(path).st_mode) if os.path.isfile(path) else None
        if old_mode is not None:
            os.chmod(tmp, old_mode)
    except OSError:
        pass  # keeping the old mode is a courtesy; the write goes on with the umask's


@contextmanager
def atomic_path(path: PathArg) -> Iterator[str]:
    """Yield a temporary path beside ``path`` (a file's path); rename it onto ``path`` if
    the block succeeds, delete it if not. A reader never sees half a file, and an error
    leaves an existing file as it was.

    **Mode:** the file ends with the mode a plain ``open(path, "w")`` gives it: a new file
    gets ``0o666 & ~umask``; a file that is replaced keeps its mode.
    **Errors:** an ``OSError`` raised while writing or renaming names ``path``, never the
    temporary file: a folder's name, a missing folder, a "folder" that is a file, and a
    ``path`` that exists and is not a regular file (a symbolic link, a device, a named
    pipe, a socket) are refused before anything is written, and checked again just before
    the rename. A ``path`` that is not a ``str`` or path-like object raises ``TypeError``."""
    path = _check_path(path)
    check_writable_file(path)
    tmp = None
    try:
        tmp = _new_file_beside(path)
        _keep_mode(path, tmp)
        yield tmp
        INTERRUPT.check()  # an interrupt that was dropped still stops the file being put in place
        _check_target(path)  # still a regular file or nothing
        os.replace(tmp, path)
    except OSError as e:
        renamed = _user_error(e, path, tmp)
        if renamed is not None:
            raise renamed from None
        raise
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.remove(tmp)


def _same_target(a: str, b: str) -> bool:
    """Whether the paths ``a`` and ``b`` name one file (the same name, or one existing file)."""
    if os.path.abspath(a) == os.path.abspath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _set_aside(path: str) -> str | None:
    """A second name (a hard link, else a copy) beside the existing regular file ``path``,
    so that it can be put back; ``None`` where ``path`` does not exist."""
    if not os.path.lexists(path):
        return None
    for _ in range(100):
        aside = os.path.join(os.path.dirname(os.path.abspath(path)), f".rotor-{secrets.token_hex(4)}.old")
        if os.path.lexists(aside):
            continue
        try:
            os.link(path, aside)
        except FileExistsError:
            continue
        except OSError:  # a file system without hard links: a copy
            import shutil

            shutil.copy2(path, aside)
        return aside
    raise FileExistsError(errno.EEXIST, "no free temporary name in the folder", path)


@contextmanager
def atomic_paths(paths: Sequence[PathArg]) -> Iterator[list[str]]:
    """:func:`atomic_path` for several files that belong together (a log and the file
    beside it that describes it): yield a temporary path beside each of ``paths``; if the
    block succeeds, put them all in place, else none. Every target is checked (as
    :func:`check_writable_file` does) before anything is made; they are renamed in order,
    and where a later rename fails the earlier ones are undone (the file each replaced is
    put back, a new one removed), so that a reader finds all the old files or all the new.
    Two of ``paths`` naming one file are refused (``ValueError``). An ``OSError`` names the
    user's path that failed."""
    targets = [_check_path(p) for p in paths]
    for i, a in enumerate(targets):
        for b in targets[:i]:
            if _same_target(a, b):
                raise ValueError(f"{b} and {a}: one file given twice for two outputs")
    for path in targets:
        check_writable_file(path)
    tmps: list[str] = []
    try:
        for path in targets:
            tmps.append(_new_file_beside(path))
            _keep_mode(path, tmps[-1])
        yield list(tmps)
        INTERRUPT.check()
        for path in targets:
            _check_target(path)  # still a regular file or nothing
        _put_in_place(targets, tmps)
    except OSError as e:
        # an error that names a temporary file names its target instead
        which = next((i for i, t in enumerate(tmps) if str(e.filename).startswith(t)), 0)
        renamed = _user_error(e, targets[which], tmps[which] if tmps else None) if targets else None
        if renamed is not None:
            raise renamed from None
        raise
    finally:
        for tmp in tmps:
            if os.path.exists(tmp):
                os.remove(tmp)


def _put_in_place(targets: list[str], tmps: list[str]) -> None:
    """Rename each of ``tmps`` onto its target; where one fails, undo those done before it
    and raise its ``OSError`` naming its target."""
    done: list[tuple[str, str | None]] = []  # (target, its old file set aside)
    asides: list[str] = []
    try:
        for path, tmp in zip(targets, tmps):
            try:
                aside = _set_aside(path) if len(targets) > 1 else None
                if aside is not None:
                    asides.append(aside)
                os.replace(tmp, path)
            except OSError as e:
                raise type(e)(e.errno or errno.EIO, e.strerror or str(e), path) from None
            done.append((path, aside))
    except BaseException:
        for path, aside in reversed(done):
            try:
                if aside is None:
                    os.remove(path)
                else:
                    os.replace(aside, path)
            except OSError:
                pass  # undone as far as the file system lets it
        raise
    finally:
        for aside in asides:
            if os.path.lexists(aside):
                os.remove(aside)


def write_text_atomic(path: PathArg, text: str) -> None:
    """Write ``text`` to ``path`` (a file's path) whole or not at all; an ``OSError`` names
    ``path``."""
    if not isinstance(text, str):
        raise TypeError(f"text: expected a str, got {type(text).__name__}")
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            f.write(text)


def write_texts_atomic(texts: Sequence[tuple[PathArg, str]]) -> None:
    """Write each ``(path, text)`` of ``texts``, all whole or none at all
    (:func:`atomic_paths`); an ``OSError`` names the path that failed."""
    for _, text in texts:
        if not isinstance(text, str):
            raise TypeError(f"text: expected a str, got {type(text).__name__}")
    with atomic_paths([p for p, _ in texts]) as tmps:
        for tmp, (_, text) in zip(tmps, texts):
            with open(tmp, "w", encoding="utf-8", newline="") as f:
                f.write(text)


def _check_what_error(what: object, error: object) -> None:
    if not isinstance(what, str):
        raise TypeError(f"what = {what!r}: expected words (a str) saying what the file holds")
    if not (isinstance(error, type) and issubclass(error, Exception)):
        raise TypeError(f"error = {error!r}: expected an exception class such as OSError")


def json_file_text(path: PathArg, data: dict, *, what: str, error: type[Exception] = OSError) -> str:
    """The text :func:`save_json` writes to ``path`` for ``data`` (indented JSON, never NaN
    nor Infinity), with its checks: ``error`` names ``path`` where ``data`` holds a NaN or
    an infinity (by its key path); data that is not plain JSON raises ``TypeError``."""
    path = _check_path(path)
    _check_what_error(what, error)
    if not isinstance(data, dict):
        raise TypeError(f"data: expected a dict of plain JSON data, got {type(data).__name__}")
    found = find_nonfinite(data)
    if found is not None:
        raise error(f"{path}: cannot write {what}: its {key_path_text(found[0])} is {found[1]}, not a number")
    try:
        return json.dumps(data, indent=1, allow_nan=False) + "\n"
    except TypeError as e:
        raise TypeError(f"data: not plain JSON data ({e})") from None


def save_json(path: PathArg, data: dict, *, what: str, error: type[Exception] = OSError) -> None:
    """Write ``data`` as indented JSON (never NaN nor Infinity) to ``path``, whole or not at all.

    **Arguments:** ``path``: the file (a ``str`` or ``pathlib.Path``); ``data``: plain JSON
    data (a dict); ``what``: what the file holds, in words, for the error (e.g. ``"the
    calibration"``); ``error``: the exception class raised, with a one-line message naming
    the file, when the folder is missing, the file cannot be written (a folder, a link, a
    device, …: :func:`check_writable_file`), or ``data`` holds a NaN or an infinity (named
    by its key path). Arguments of the wrong type raise ``TypeError`` naming the argument."""
    path = _check_path(path)
    text = json_file_text(path, data, what=what, error=error)
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


ROUND_OFF = 1e-12
"""A number within this share of the largest magnitude of its column is the round-off of a
zero (float64 carries about 16 digits; the kinematics of a throw at TDC give 5.7e-18 m
for a stroke of 0.2 m) and is written as 0."""


def _zeroed(rows: Iterable[Sequence[float]], width: int) -> list:
    """``rows`` through :func:`zeros_as_zero` where every row has ``width`` numbers (else as
    they are, for :func:`csv_text` to name the row that does not)."""
    rows = [list(r) for r in rows]
    return zeros_as_zero(rows) if all(len(r) == width for r in rows) else rows


def zeros_as_zero(rows: Iterable[Sequence[float]]) -> list[list[float]]:
    """The rows of a table with every value within :data:`ROUND_OFF` of its column's largest
    magnitude set to 0 (a column of zeros and round-off reads as zeros; NaN and infinities
    are kept, for the writer to refuse by name)."""
    table = [[float(v) for v in row] for row in rows]
    if not table:
        return table
    scale = [max((abs(v) for v in column if math.isfinite(v)), default=0.0) for column in zip(*table)]
    return [[0.0 if abs(v) <= ROUND_OFF * s else v for v, s in zip(row, scale)] for row in table]


def csv_text(header: Sequence[str], rows: Iterable[Sequence[float]], what: str = "the table") -> str:
    """A table as CSV text: the ``header`` line, then one line per row of numbers (each
    with 10 significant digits, never ``-0``, zeros written as 0 where the computation left
    round-off: :func:`zeros_as_zero`), ending in a newline.

    A NaN or an infinity is refused, never written: an :class:`rotor.errors.InternalError`
    names its column and row (counted from 1), e.g. ``the table's "s_m" in row 3 is NaN``
    (``what`` names the table). Numbers keep the units of their column's name."""
    header = [str(h) for h in header]
    lines = [",".join(header)]
    for i, row in enumerate(_zeroed(rows, len(header)), start=1):
        values = [float(v) for v in row]
        if len(values) != len(header):
            raise InternalError(f"{what}'s row {i} has {len(values)} values for {len(header)} columns")
        for name, v in zip(header, values):
            if not math.isfinite(v):
                kind = "NaN" if math.isnan(v) else ("Infinity" if v > 0 else "-Infinity")
                raise InternalError(f'{what}\'s "{name}" in row {i} is {kind}: a number that should exist does not')
        lines.append(",".join(f"{v + 0.0:.10g}" for v in values))  # + 0.0: no "-0"
    return "\n".join(lines) + "\n"
