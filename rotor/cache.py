"""JAX's persistent compilation cache for rotor's kernels.

The ``rotor`` command switches the cache on; in Python, call :func:`enable_compilation_cache`
(importing rotor does not touch JAX's cache settings). Compiling rotor's kernels takes 1–3 s
per method in a fresh process; with the cache the compiled code of an earlier process is
reused and a first call costs mainly tracing (``benchmarks/compile_time.py`` and
``benchmarks/cli_latency.py`` measure both). The cache lives in ``$ROTOR_COMPILATION_CACHE``
if set (``0``, ``off`` or ``no`` switches it off), else in ``$XDG_CACHE_HOME/rotor/jax``
(``~/.cache/rotor/jax``), is capped at 1 GB and is left alone if the user has configured a
JAX cache directory already.

Importing JAX takes about a second, and the commands that compile nothing (``rotor
presets``, ``rotor --help``) never do: :func:`enable_compilation_cache` sets JAX's cache at
once when JAX is imported already, else it keeps the setting, and :mod:`rotor.jaxconfig`,
where rotor imports JAX, applies it (:func:`apply_compilation_cache`).
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

__all__ = ["MAX_BYTES", "apply_compilation_cache", "enable_compilation_cache", "padded_size", "submodules_on_demand"]

_OFF = ("0", "off", "no", "false", "")
MAX_BYTES = 1 << 30
"""The size cap of the persistent compilation cache [bytes]."""


def padded_size(n: int) -> int:
    """The smallest of 1, 2, 3, 4, 6, 8, 12, 16, 24, … (2ᵏ and 3·2ᵏ) that holds ``n`` items.

    A compiled program serves one shape: a batch padded to one of these sizes reuses the
    program of every other batch of that size (a few programs over all record lengths), for
    at most half as much work again as the exact size."""
    if n < 1:
        raise ValueError(f"n = {n!r}: a size of at least 1")
    power = 1 << (n - 1).bit_length()  # the power of two ≥ n
    return 3 * power // 4 if power >= 4 and 3 * power // 4 >= n else power


_WANTED: list[tuple[str, float]] = []  # the cache asked for before JAX was imported (the last one)


def _own_cache_dir() -> str | None:
    """The JAX cache directory the user set (``jax.config`` or ``$JAX_COMPILATION_CACHE_DIR``), if any."""
    jax = sys.modules.get("jax")
    if jax is not None and hasattr(jax, "config"):
        own = getattr(jax.config, "jax_compilation_cache_dir", None)
        return str(own) if own else None
    return os.environ.get("JAX_COMPILATION_CACHE_DIR") or None


def _configure(jax: ModuleType, path: str, min_compile_time_s: float) -> None:
    jax.config.update("jax_compilation_cache_dir", path)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", min_compile_time_s)
    jax.config.update("jax_compilation_cache_max_size", MAX_BYTES)


def enable_compilation_cache(
    path: str | os.PathLike[str] | None = None, *, min_compile_time_s: float = 0.1
) -> str | None:
    """Use JAX's persistent compilation cache at ``path`` (see the module doc for the default).

    ``path``: a folder (created if missing). ``min_compile_time_s``: only what takes at
    least this long to compile is written to the cache [s] (the ``rotor`` command gives 0:
    its few small eager operations, 20–100 ms each to compile, read back in a few ms; a
    long Python session would fill the cache with them). Returns the directory in use, or
    None when the cache is off. Sets JAX's process-wide cache directory, the compile-time
    threshold and the size cap (1 GB) — at once if JAX is imported, else as soon as rotor
    imports it (so that a command that never needs JAX does not import it); the ``rotor`` command
    calls it once per run. Call it again with another ``path`` to move the cache.
    """
    env = os.environ.get("ROTOR_COMPILATION_CACHE")
    if path is None:
        if env is not None and env.strip().lower() in _OFF:
            return None
        own = _own_cache_dir()
        if own:  # the user's own choice wins
            return own
        if env:
            path = env
        else:
            base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
            path = Path(base) / "rotor" / "jax"
    path = Path(path).expanduser()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:  # a read-only home: run without the cache rather than fail
        return None
    folder = str(path)
    _WANTED[:] = [(folder, float(min_compile_time_s))]
    jax = sys.modules.get("jax")
    if jax is not None and hasattr(jax, "config"):
        apply_compilation_cache(jax)
    return folder


def apply_compilation_cache(jax: ModuleType) -> None:
    """Set JAX's persistent cache as :func:`enable_compilation_cache` last asked, if it
    asked before JAX was imported (:mod:`rotor.jaxconfig` calls this once JAX is)."""
    while _WANTED:
        folder, min_compile_time_s = _WANTED.pop()
        _configure(jax, folder, min_compile_time_s)


def submodules_on_demand(package: str) -> Callable[[str], ModuleType]:
    """A module ``__getattr__`` for a subpackage's ``__init__``: ``rotor.diagnostics.calibration``
    imports :mod:`rotor.diagnostics.calibration` on first use, as an eager ``import`` of
    every module once did, while ``import rotor`` stays cheap."""

    def __getattr__(name: str) -> ModuleType:
        if not name.startswith("_"):
            try:
                return importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as e:
                if e.name != f"{package}.{name}":
                    raise
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
