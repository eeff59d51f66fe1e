"""Writing files whole or not at all, and JSON files saved and loaded one way.

Ground floor: imports nothing from rotor.
"""

from __future__ import annotations

import json
import os
import tempfile
from contextlib import contextmanager


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; rename it onto ``path`` if the block
    succeeds, delete it if not. A reader never sees half a file, and an error leaves
    an existing file as it was."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".rotor-", suffix=os.path.splitext(path)[1])
    os.close(fd)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
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
