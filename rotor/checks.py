"""Validation helpers shared by the parameter modules.

Concrete values are checked in NumPy when they arrive (:func:`check_finite`,
:func:`check_positive`: a :class:`rotor.EngineError` at once). A traced value (inside
``jax.jit``, ``jax.vmap`` or ``jax.grad``) has no value to look at while the program is
built: the public functions check it with :func:`guard` (``eqx.error_if``), which raises
when the compiled program runs, under ``vmap`` if any item fails, under ``grad`` on the
primal value. They do so for the values a caller outside rotor hands them
(:func:`called_from_outside`): rotor's own kernels pass on values checked on the host, or
iterates of a solver that looks at them itself, and a program with no host callback in it
can be kept on disk (:mod:`rotor.programs`). JAX is imported where a JAX array is made:
the size and number checks of a log's reading need none.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from .errors import EngineError


def is_tracer(x) -> bool:
    """Whether ``x`` is a JAX tracer (inside ``jit``, ``grad``, ``vmap``); False in a process
    that has not imported JAX."""
    jax = sys.modules.get("jax")
    return jax is not None and isinstance(x, jax.core.Tracer)


def tracing() -> bool:
    """Whether JAX is tracing a program now (inside ``jit``, ``vmap``, ``grad``): only then
    can an argument be a tracer. True where it cannot be told (the caller then looks at
    every argument)."""
    jax = sys.modules.get("jax")
    if jax is None:
        return False
    try:
        from jax._src.core import trace_state_clean
    except ImportError:  # pragma: no cover - another JAX: look at the arguments instead
        return True
    return not trace_state_clean()


def has_tracer(tree) -> bool:
    """Whether any leaf of the pytree ``tree`` is a JAX tracer (False at once where JAX is
    not tracing)."""
    if not tracing():
        return False
    from .jaxconfig import jax

    return any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(tree))


def called_from_outside(depth: int = 2) -> bool:
    """Whether the function ``depth − 1`` frames above this one was called from code outside
    the rotor package (a user's script, notebook or test): its traced arguments are then
    checked (:func:`guard`). rotor's own modules call the public functions with values they
    checked on the host, or with a solver's iterates that the solver judges itself."""
    frame: Any = sys._getframe(depth)
    while frame is not None:  # past the transformations' own frames (jax.jit, vmap, equinox's wrappers)
        module = frame.f_globals.get("__name__", "")
        if module.split(".")[0] not in _TRANSFORM_MODULES:
            return not (module == "rotor" or module.startswith("rotor."))
        frame = frame.f_back
    return True


_TRANSFORM_MODULES = frozenset(
    {"jax", "jaxlib", "equinox", "functools", "contextlib", "lineax", "optimistix", "diffrax"}
)
"""Modules whose frames stand between a transformed function and its caller: skipped to find
who called it."""


TRACED = "the value traced under jax.jit, vmap or grad is not"
"""The end of a traced check's message: the value is known only when the program runs."""


class TracedChecks:
    """The traced checks of one call, gathered to be made at once: a program that holds a
    host callback (``eqx.error_if``) pays a fixed cost each time it runs (about 30 µs on a
    CPU), however many it holds, so a solver makes all its checks in one (:meth:`tie`), or,
    asked for a status instead, none (:meth:`valid`)."""

    def __init__(self) -> None:
        self.items: list[tuple[Any, str]] = []

    def add(self, bad: Any, message: str) -> None:
        """Record the check ``bad`` (true where it fails) with its one-line ``message``."""
        self.items.append((bad, message))

    def valid(self) -> Any:
        """True where every check recorded passes (a traced bool; True with none)."""
        from .jaxconfig import jnp

        ok = jnp.asarray(True)
        for bad, _ in self.items:
            ok = ok & ~jnp.any(jnp.asarray(bad))
        return ok

    def tie(self, tree: Any, more: Sequence[tuple[Any, str]] = ()) -> Any:
        """``tree`` with the recorded checks and ``more`` (the same pairs) made in one
        ``eqx.branched_error_if`` on a scalar zero added to every floating-point leaf: the
        program raises the message of the first that fails when it runs (under ``vmap``, of
        any item), or at once where the checks are known while tracing (as under ``grad``);
        whichever leaf the caller uses carries it, and the leaves it drops cost nothing."""
        import equinox as eqx

        from .jaxconfig import jax, jnp

        items = [*self.items, *more]
        if not items:
            return tree
        bads = jnp.stack([jnp.any(jnp.asarray(bad)) for bad, _ in items])
        zero = eqx.branched_error_if(jnp.zeros(()), jnp.any(bads), jnp.argmax(bads), [m for _, m in items])

        def tied(leaf: Any) -> Any:
            if isinstance(leaf, (jax.Array, np.ndarray)) and jnp.issubdtype(leaf.dtype, jnp.inexact):
                return leaf + zero.astype(leaf.dtype)
            return leaf

        return jax.tree_util.tree_map(tied, tree)


def guard(x, bad, message: str, checks: TracedChecks | None = None):
    """``x`` (an array or a pytree of them) with ``eqx.error_if(x, bad, message)`` where
    ``x`` or ``bad`` is traced: the program raises ``message`` when it runs and ``bad`` is
    true (any item under ``vmap``; at once where ``bad`` is known while tracing, as under
    ``grad``); ``x`` itself where both are concrete (the caller checks concrete values at
    once). With ``checks``, the check is recorded there instead (the caller makes it with
    the others, :class:`TracedChecks`). The returned value must be the one used
    afterwards, or the check is dropped with it."""
    if not (is_tracer(bad) or has_tracer(x)):
        return x
    if checks is not None:
        checks.add(bad, message)
        return x
    import equinox as eqx

    from .jaxconfig import jax

    if not any(eqx.is_array(leaf) for leaf in jax.tree_util.tree_leaves(x)):  # a Python number: an array to carry it
        x = jax.tree_util.tree_map(jax.numpy.asarray, x)
    return eqx.error_if(x, bad, message)


def guard_number(
    x,
    name: str,
    lo: float = -np.inf,
    hi: float = np.inf,
    *,
    above: bool = False,
    unit: str = "",
    expected: str = "",
    checks: TracedChecks | None = None,
):
    """``x`` checked where it is traced (:func:`guard`): every element finite and within
    ``lo`` … ``hi`` (inclusive; ``above``: strictly above ``lo``), or the program raises a
    one-line message naming ``name`` and what it takes (``expected``, e.g. ``"a crank speed
    in rpm, e.g. 3000"``; ``unit`` of the bounds); with ``checks``, recorded there. Concrete
    values pass unchanged: the caller checks them itself."""
    if not is_tracer(x):
        return x
    from .jaxconfig import jnp

    value = jnp.asarray(x)
    bad = ~jnp.isfinite(value)
    has_lo, has_hi = bool(np.isfinite(lo)), bool(np.isfinite(hi))
    if has_lo:
        bad = bad | ((value <= lo) if above else (value < lo))
    if has_hi:
        bad = bad | (value > hi)
    low = f"above {lo:g}" if above else f"{lo:g} or more"
    bounds = f" between {lo:g} and {hi:g}" if has_lo and has_hi else f", {low}" if has_lo else ""
    bounds = bounds if has_lo or not has_hi else f", {hi:g} or less"
    if above and has_lo and has_hi:
        bounds = f", above {lo:g} and at most {hi:g}"
    u = f" {unit}" if unit and (has_lo or has_hi) else ""
    what = f" ({expected})" if expected else ""
    return guard(x, bad, f"{name}: must be finite{bounds}{u}{what}; {TRACED}", checks)


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
