"""JAX as rotor computes with it: every module of rotor that imports JAX imports this one
too, directly or through another (:mod:`rotor.checks`, :mod:`rotor.cycles`;
``tests/project/test_architecture.py`` checks), before it computes anything.

Importing it switches on JAX's float64 (``jax_enable_x64``, process-wide), which rotor's
numerics need, and applies the persistent compilation cache that
:func:`rotor.enable_compilation_cache` asked for before JAX was imported. (XLA's CPU
emitters are chosen by ``import rotor``, which runs before this module:
:data:`rotor.cache.XLA_CPU_FLAG`.) ``import rotor``
alone imports neither this module nor JAX, so that the commands that compute nothing start
fast. Base layer: imports nothing from rotor but :mod:`rotor.cache`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .cache import apply_compilation_cache

__all__ = ["jax", "jnp"]

jax.config.update("jax_enable_x64", True)
apply_compilation_cache(jax)
