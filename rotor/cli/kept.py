"""Outputs of the commands that only read an engine (``rotor table``, ``rotor info``), kept
so that the same call again prints them without importing JAX.

Importing JAX alone takes about a second, more than such a command's whole budget. Their
output is a pure function of the engine file's bytes, the command's options, rotor's own
source and the versions of the numerical packages, and is kept under the digest of all of
them (blake2b): any change to one of them is a miss, and the command computes afresh. Only
a whole, successful output is kept; an error is never.

The outputs live in ``$ROTOR_OUTPUT_CACHE`` if set (``0``, ``off`` or ``no`` switches
them off), else in ``$XDG_CACHE_HOME/rotor/outputs`` (``~/.cache/rotor/outputs``); the
newest :data:`MAX_FILES` are kept. Nothing is kept where the folder cannot be written.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Any

__all__ = ["MAX_FILES", "keep_output", "kept_output", "output_key"]

MAX_FILES = 256
_OFF = {"0", "off", "no", "false"}
_PACKAGES = ("jax", "jaxlib", "equinox", "numpy")


def _folder() -> Path | None:
    env = os.environ.get("ROTOR_OUTPUT_CACHE")
    if env is not None and env.strip().lower() in _OFF:
        return None
    if env:
        return Path(env).expanduser()
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rotor" / "outputs"


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


def _source_fingerprint() -> bytes:
    """rotor's source files (path, size, modification time) and the versions of the
    numerical packages: what an output depends on besides its inputs."""
    from importlib import metadata

    root = Path(__file__).resolve().parent.parent
    parts = []
    for folder, _, files in sorted(os.walk(root)):
        for name in sorted(files):
            if name.endswith((".py", ".toml")):
                st = os.stat(os.path.join(folder, name))
                parts.append(f"{os.path.relpath(os.path.join(folder, name), root)}:{st.st_size}:{st.st_mtime_ns}")
    for package in _PACKAGES:
        try:
            parts.append(f"{package}=={metadata.version(package)}")
        except metadata.PackageNotFoundError:
            parts.append(f"{package} missing")
    return "\n".join(parts).encode()


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
    for part in (command.encode(), repr(sorted(options.items())).encode(), raw, _source_fingerprint()):
        h.update(len(part).to_bytes(8, "little"))
        h.update(part)
    return h.hexdigest()


def kept_output(key: str | None) -> str | None:
    """The output kept under ``key``, or None."""
    folder = _folder()
    if key is None or folder is None:
        return None
    try:
        return (folder / f"{key}.txt").read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None


def keep_output(key: str | None, text: str) -> None:
    """Keep ``text`` under ``key`` (whole or not at all), and only the newest
    :data:`MAX_FILES` outputs; silently nothing where the folder cannot be written."""
    folder = _folder()
    if key is None or folder is None:
        return
    from ..fileio import write_text_atomic

    try:
        folder.mkdir(parents=True, exist_ok=True)
        write_text_atomic(folder / f"{key}.txt", text)
        kept = sorted(folder.glob("*.txt"), key=lambda p: p.stat().st_mtime_ns)
        for old in kept[:-MAX_FILES]:
            old.unlink(missing_ok=True)
    except OSError:
        return
