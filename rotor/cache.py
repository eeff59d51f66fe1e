"""JAX's persistent compilation cache for rotor's kernels, and JAX's process-wide settings
applied when JAX is imported.

The ``rotor`` command switches the cache on; in Python, call :func:`enable_compilation_cache`
(importing rotor does not touch JAX's cache settings). Compiling rotor's kernels takes 1–3 s per method in a fresh process; with the cache the
compiled code of an earlier process is reused and a first call costs mainly tracing
(``benchmarks/compile_time.py`` and ``benchmarks/cli_latency.py`` measure both). The cache lives in
``$ROTOR_COMPILATION_CACHE`` if set (``0``, ``off`` or ``no`` switches it off), else in
``$XDG_CACHE_HOME/rotor/jax`` (``~/.cache/rotor/jax``), is capped at 1 GB and is left
alone if the user has configured a JAX cache directory already.

Importing JAX takes about a second, and the commands that compile nothing (``rotor
presets``, ``rotor --help``) never do: :func:`on_jax_import` runs a setting (float64, the
cache) at once when JAX is imported already, else right after JAX's own import, whoever
imports it.
"""

from __future__ import annotations

import importlib
import importlib.abc
import os
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["MAX_BYTES", "enable_compilation_cache", "on_jax_import", "submodules_on_demand"]

_OFF = ("0", "off", "no", "false", "")
MAX_BYTES = 1 << 30
"""The size cap of the persistent compilation cache [bytes]."""

_PENDING: list[Callable[[ModuleType], Any]] = []


class _AfterJaxImport(importlib.abc.MetaPathFinder):
    """An import hook that finds nothing itself: when ``jax`` is about to be imported it
    lets the other finders find it and runs the pending callbacks once JAX's ``__init__``
    has run (before the ``import`` statement returns), then leaves ``sys.meta_path``."""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> Any:
        if fullname != "jax":
            return None
        for finder in sys.meta_path:
            find = getattr(finder, "find_spec", None)
            if finder is self or find is None:
                continue
            spec = find(fullname, path, target)
            if spec is not None:
                break
        else:
            return None
        loader = spec.loader
        exec_module = getattr(loader, "exec_module", None)
        if exec_module is None:  # not a loader of today's protocol: import first, then run
            return None

        def exec_module_then_settle(module: ModuleType) -> None:
            exec_module(module)
            _run_pending(module)

        loader.exec_module = exec_module_then_settle  # this spec's own loader object
        return spec


_HOOK = _AfterJaxImport()


def _run_pending(jax: ModuleType) -> None:
    if _HOOK in sys.meta_path:
        sys.meta_path.remove(_HOOK)
    while _PENDING:
        _PENDING.pop(0)(jax)


def on_jax_import(callback: Callable[[ModuleType], Any]) -> None:
    """Run ``callback(jax)`` now if JAX is imported, else right after JAX is imported
    (its package ``__init__`` run, before anything else uses it). Callbacks run in the
    order given, once each."""
    jax = sys.modules.get("jax")
    if jax is not None and hasattr(jax, "config"):
        _run_pending(jax)
        callback(jax)
        return
    _PENDING.append(callback)
    if _HOOK not in sys.meta_path:
        sys.meta_path.insert(0, _HOOK)


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
    threshold and the size cap (1 GB) — at once if JAX is imported, else as soon as it is
    (so that a command that never needs JAX does not import it); the ``rotor`` command
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
    on_jax_import(lambda jax: _configure(jax, folder, float(min_compile_time_s)))
    return folder


def submodules_on_demand(package: str) -> Callable[[str], ModuleType]:
    """A module ``__getattr__`` for a room's ``__init__``: ``rotor.diagnostics.calibration``
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
