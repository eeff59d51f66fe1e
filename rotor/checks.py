"""Validation helpers shared by the parameter modules.

Checks run only on concrete values: inside ``jax.jit``/``jax.grad`` the fields are
tracers and were already checked when the object was first built from numbers. JAX is
imported where a JAX array is made: the size and number checks of a log's reading need none.
"""

from __future__ import annotations

import sys

import numpy as np

from .errors import EngineError


def is_tracer(x) -> bool:
    """Whether ``x`` is a JAX tracer (inside ``jit``, ``grad``, ``vmap``); False in a process
    that has not imported JAX."""
    jax = sys.modules.get("jax")
    return jax is not None and isinstance(x, jax.core.Tracer)


def as_f64(x):
    """Converter for numeric fields: a float64 JAX array (float32 and ints are widened).

    Tracers pass through unchanged so that modules can be rebuilt inside ``jax.jit``.
    """
    if is_tracer(x):
        return x
    if isinstance(x, (bool, np.bool_)):
        raise EngineError(f"expected a number, got the boolean {x!r}")
    from .jaxconfig import jax

    if not isinstance(x, jax.Array):
        try:  # numbers and lists of them: put on the device as they are (no program compiled)
            return jax.device_put(np.asarray(x, dtype=np.float64))
        except (TypeError, ValueError):
            pass  # JAX says what it cannot convert
    return jax.numpy.asarray(x, dtype=np.float64)


def concrete(x):
    """``x`` as a numpy float64 array, or ``None`` if it is a tracer (not checkable)."""
    if is_tracer(x):
        return None
    return np.asarray(x, dtype=np.float64)


def where(table: str, key: str) -> str:
    return f"[{table}] {key}" if table else key


def fmt(v) -> str:
    a = np.asarray(v)
    if a.ndim == 0:
        return f"{float(a):g}"
    return "[" + ", ".join(f"{float(x):g}" for x in a.ravel()) + "]"


def check_finite(table: str, key: str, value) -> None:
    v = concrete(value)
    if v is not None and not np.all(np.isfinite(v)):
        raise EngineError(f"{where(table, key)} = {fmt(v)}: must be finite (no NaN or inf)")


def check_positive(table: str, key: str, value, *, allow_zero: bool = False) -> None:
    check_finite(table, key, value)
    v = concrete(value)
    if v is None:
        return
    bad = np.any(v < 0) if allow_zero else np.any(v <= 0)
    if bad:
        need = "zero or positive" if allow_zero else "positive"
        raise EngineError(f"{where(table, key)} = {fmt(v)}: must be {need}")


def arrays_only(tree):
    """``tree`` with every Python number leaf made a float64 array.

    ``eqx.tree_at(..., engine, 12.0)`` puts a Python float into a module; ``eqx.filter_jit``
    would treat it as a constant and compile again for every new value.
    """

    if tree is None:
        return None
    from .jaxconfig import jax

    def leaf(x):
        if isinstance(x, (float, int, np.floating, np.integer)) and not isinstance(x, (bool, np.bool_)):
            return jax.numpy.asarray(x, dtype=np.float64)
        return x

    return jax.tree_util.tree_map(leaf, tree)


# ----------------------------------------------------------------------------- sizes
MEMORY_ENV = "ROTOR_MEMORY_LIMIT_GB"
"""Environment variable that caps the memory one array of rotor may take [GB] (default:
half of the memory available when the check runs)."""


def memory_budget_bytes() -> int:
    """The most memory one computation of rotor plans to take [bytes].

    ``ROTOR_MEMORY_LIMIT_GB`` if set, else half of what the operating system reports as
    available (``MemAvailable`` on Linux, the physical memory elsewhere), at least 256 MB."""
    import os

    env = os.environ.get(MEMORY_ENV)
    if env:
        try:
            gb = float(env)
        except ValueError:
            raise EngineError(f"{MEMORY_ENV} = {env!r}: must be a number of gigabytes, e.g. 4") from None
        if not (np.isfinite(gb) and gb > 0):
            raise EngineError(f"{MEMORY_ENV} = {env!r}: must be a positive number of gigabytes")
        return int(gb * 1e9)
    available = None
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    available = int(line.split()[1]) * 1024
                    break
    except OSError:
        pass
    if available is None:
        try:
            available = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
        except (ValueError, OSError, AttributeError):
            available = 8 * 1024**3
    return max(int(available // 2), 256 * 1024**2)


def check_size(n_bytes: float, what: str, way_out: str, *, error: type[Exception] = EngineError) -> None:
    """Refuse, before allocating, a computation that needs more memory than
    :func:`memory_budget_bytes`.

    **Arguments:** ``n_bytes``: the memory it would take [bytes]; ``what``: what would be
    allocated, in words (e.g. ``"cycles = 100000 at 720 samples per cycle"``); ``way_out``:
    what the user can do (e.g. ``"keep fewer cycles with keep_cycles="``); ``error``: the
    exception class raised. The message is one line with the need, the limit and the way out.
    """
    budget = memory_budget_bytes()
    try:
        need_bytes = float(n_bytes)  # a Python int past 2**1024 does not convert: too big
    except OverflowError:
        need_bytes = float("inf")
    if not np.isfinite(need_bytes) or need_bytes > budget:
        need = "more than can be counted" if not np.isfinite(need_bytes) else f"{need_bytes / 1e9:.3g} GB"
        raise error(
            f"{what} needs {need} of memory, over the {budget / 1e9:.3g} GB this machine allows "
            f"(half of what is available, or {MEMORY_ENV}); {way_out}"
        )
