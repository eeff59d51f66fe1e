"""Outputs of the commands that only read an engine (``rotor table``, ``rotor info``), kept
so that the same call again prints them without importing JAX.

Importing JAX alone takes about a second, more than such a command's whole budget. Their
output is a pure function of the engine file's bytes, the command's options, rotor's own
source and the versions of the numerical packages, and is kept under the digest of all of
them (blake2b): any change to one of them is a miss, and the command computes afresh. Only
a whole, successful output is kept; an error is never.

The outputs live in ``$ROTOR_OUTPUT_CACHE`` if set (``0``, ``off`` or ``no`` switches
them off), else in ``$XDG_CACHE_HOME/rotor/outputs`` (``~/.cache/rotor/outputs``); the
newest :data:`MAX_FILES` are kept. Nothing is kept where the folder cannot be written, nor
in one that another user could write (owned by another, or writable by its group or
everyone: :func:`rotor.cache.own_folder`), which is neither read nor written, and rotor
says once on stderr why and what to do; a folder rotor makes is made mode 0700.

**An entry proves itself.** Each is one file named ``rotor-output-<digest>.kept``, written
whole or not at all, whose first line holds the length of the output and a checksum of it
(blake2b, over the digest under which it is kept and the output): an entry that is empty,
cut off, changed or copied under another name is a miss, and the command computes afresh
(and keeps the new output in its place). Pruning touches only files of that name: a folder
shared with other files (the user's own) loses none of them.
"""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path
from typing import Any

from ..cache import own_folder, prune, source_fingerprint, switched_off

__all__ = ["MAX_FILES", "entry_path", "keep_output", "kept_output", "output_key"]

MAX_FILES = 256
_ENTRY = re.compile(r"^rotor-output-[0-9a-f]{40}\.kept$")
_MAGIC = "rotor kept output 1"


def _folder() -> Path | None:
    """The folder of the kept outputs, or None where they are not kept (off, or a folder
    that is not the user's own)."""
    env = os.environ.get("ROTOR_OUTPUT_CACHE")
    if env is not None and switched_off(env):
        return None
    if env:
        folder = Path(env).expanduser()
    else:
        folder = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rotor" / "outputs"
    return folder if own_folder(folder, "the outputs of rotor table and rotor info", "ROTOR_OUTPUT_CACHE") else None


def _engine_bytes(engine: str) -> bytes | None:
    """The engine file's bytes (a preset's own file for a preset name), as
    :func:`rotor.load_engine` resolves ``engine``; None where it cannot be read (the
    command then reports why)."""
    from importlib import resources

    path = Path(engine)
    try:
        if path.suffix != ".toml":
            preset = resources.files("rotor.presets") / f"{engine}.toml"
            if os.sep not in engine and "/" not in engine and preset.is_file():
                return b"preset\0" + preset.read_bytes()
        return b"file\0" + path.read_bytes() if path.is_file() else None
    except (OSError, ValueError):
        return None


def output_key(command: str, engine: str, options: dict[str, Any]) -> str | None:
    """The digest under which ``command``'s output for ``engine`` (a preset name or a path)
    with ``options`` (numbers, strings, None) is kept; None where outputs are not kept or the engine
    cannot be read."""
    if _folder() is None:
        return None
    raw = _engine_bytes(engine)
    if raw is None:
        return None
    h = hashlib.blake2b(digest_size=20)
    for part in (command.encode(), repr(sorted(options.items())).encode(), raw, source_fingerprint()):
        h.update(len(part).to_bytes(8, "little"))
        h.update(part)
    return h.hexdigest()


def entry_path(key: str) -> Path | None:
    """The file of the entry kept under ``key`` (None where outputs are not kept)."""
    folder = _folder()
    return None if folder is None else folder / f"rotor-output-{key}.kept"


def _checksum(key: str, body: bytes) -> str:
    return hashlib.blake2b(key.encode() + b"\0" + body, digest_size=20).hexdigest()


def kept_output(key: str | None) -> str | None:
    """The output kept under ``key``, or None: also where the entry is not whole and
    unchanged (its length and checksum do not match), which is then computed afresh."""
    path = None if key is None else entry_path(key)
    if key is None or path is None:
        return None
    try:
        raw = path.read_bytes()
    except OSError:
        return None
    head, newline, body = raw.partition(b"\n")
    parts = head.decode("ascii", errors="replace").rsplit(" ", 2)
    if not newline or len(parts) != 3 or parts[0] != _MAGIC or parts[1] != str(len(body)):
        return None
    if parts[2] != _checksum(key, body):
        return None
    try:
        return body.decode("utf-8")
    except UnicodeDecodeError:
        return None


def keep_output(key: str | None, text: str) -> None:
    """Keep ``text`` under ``key`` (whole or not at all, with its length and checksum), and
    only the newest :data:`MAX_FILES` of rotor's entries (no other file of the folder);
    silently nothing where the folder cannot be written."""
    path = None if key is None else entry_path(key)
    if key is None or path is None:
        return
    from ..fileio import atomic_path

    body = text.encode("utf-8")
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            f.write(f"{_MAGIC} {len(body)} {_checksum(key, body)}\n".encode("ascii") + body)
        prune(path.parent, _ENTRY, MAX_FILES)
    except OSError:
        return
