"""Writing files whole or not at all, and JSON files saved and loaded one way.

Ground floor: imports nothing from rotor.
"""

from __future__ import annotations

import errno
import json
import os
import secrets
import stat
from contextlib import contextmanager


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


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; rename it onto ``path`` if the block
    succeeds, delete it if not. A reader never sees half a file, and an error leaves
    an existing file as it was.

    **Mode:** the file ends with the mode a plain ``open(path, "w")`` gives it: a new file
    gets ``0o666 & ~umask``; a file that is replaced keeps its mode.
    **Errors:** an ``OSError`` raised while writing or renaming names ``path``, never the
    temporary file."""
    path = os.fspath(path)
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
        if e.errno is not None and (e.filename is None or names_tmp):
            raise type(e)(e.errno, e.strerror, path) from None
        raise
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.remove(tmp)


def write_text_atomic(path, text: str) -> None:
    """Write ``text`` to ``path`` whole or not at all."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            f.write(text)


def save_json(path, data: dict, *, what: str, error: type[Exception] = OSError) -> None:
    """Write ``data`` as indented JSON (never NaN) to ``path``, whole or not at all.

    **Arguments:** ``path``: the file; ``data``: plain JSON data; ``what``: what the file
    holds, in words, for the error (e.g. ``"the calibration"``); ``error``: the exception
    class raised, with a one-line message naming the file, when the folder is missing or
    the file cannot be written."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise error(f"{path}: cannot write {what}: no folder {folder}")
    try:
        write_text_atomic(path, json.dumps(data, indent=1, allow_nan=False) + "\n")
    except OSError as e:
        raise error(f"{path}: cannot write {what}: {e.strerror or e}") from None


def load_json(path, *, what: str, error: type[Exception] = OSError) -> object:
    """Read the JSON file ``path``; a file that is not JSON raises ``error`` with a one-line
    message ("``path``: not ``what`` (JSON: …)"). ``what``: e.g. ``"a calibration file"``."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise error(f"{path}: not {what} (JSON: {e})") from None
