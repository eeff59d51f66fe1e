"""Validation helpers shared by the parameter modules.

Checks run only on concrete values: inside ``jax.jit``/``jax.grad`` the fields are
tracers and were already checked when the object was first built from numbers.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .errors import EngineError


def as_f64(x):
    """Converter for numeric fields: a float64 JAX array (float32 and ints are widened).

    Tracers pass through unchanged so that modules can be rebuilt inside ``jax.jit``.
    """
    if isinstance(x, jax.core.Tracer):
        return x
    if isinstance(x, (bool, np.bool_)):
        raise EngineError(f"expected a number, got the boolean {x!r}")
    return jnp.asarray(x, dtype=jnp.float64)


def concrete(x):
    """``x`` as a numpy float64 array, or ``None`` if it is a tracer (not checkable)."""
    if isinstance(x, jax.core.Tracer):
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

    def leaf(x):
        if isinstance(x, (float, int, np.floating, np.integer)) and not isinstance(x, (bool, np.bool_)):
            return jnp.asarray(x, dtype=jnp.float64)
        return x

    return jax.tree_util.tree_map(leaf, tree)
