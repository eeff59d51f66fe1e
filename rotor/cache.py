"""JAX's persistent compilation cache, for rotor's kernels.

The ``rotor`` command switches it on; in Python, call :func:`enable_compilation_cache`
(importing rotor does not touch JAX's cache settings). Compiling rotor's kernels takes 1–3 s per method in a fresh process; with the cache the
compiled code of an earlier process is reused and a first call costs mainly tracing
(``benchmarks/compile_time.py`` measures both). The cache lives in
``$ROTOR_COMPILATION_CACHE`` if set (``0``, ``off`` or ``no`` switches it off), else in
``$XDG_CACHE_HOME/rotor/jax`` (``~/.cache/rotor/jax``), is capped at 1 GB and is left
alone if the user has configured a JAX cache directory already.
"""

from __future__ import annotations

import os
from pathlib import Path

import jax

_OFF = ("0", "off", "no", "false", "")
MAX_BYTES = 1 << 30


def enable_compilation_cache(path: str | os.PathLike[str] | None = None) -> str | None:
    """Use JAX's persistent compilation cache at ``path`` (see the module doc for the default).

    ``path``: a folder (created if missing). Returns the directory in use, or None when the
    cache is off. Sets JAX's process-wide cache directory, the compile-time threshold
    (0.1 s) and the size cap (1 GB); the ``rotor`` command calls it once per run. Call it
    again with another ``path`` to move the cache.
    """
    env = os.environ.get("ROTOR_COMPILATION_CACHE")
    if path is None:
        if env is not None and env.strip().lower() in _OFF:
            return None
        own = getattr(jax.config, "jax_compilation_cache_dir", None)
        if own:  # the user's own choice wins
            return str(own)
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
    jax.config.update("jax_compilation_cache_dir", str(path))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.1)
    jax.config.update("jax_compilation_cache_max_size", MAX_BYTES)
    return str(path)
