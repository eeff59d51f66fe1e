"""JAX as rotor computes with it: every module of rotor that imports JAX imports this one
too, directly or through another (:mod:`rotor.checks`, :mod:`rotor.cycles`;
``tests/project/test_architecture.py`` checks), before it computes anything.

Importing it switches on JAX's float64 (``jax_enable_x64``, process-wide), which rotor's
numerics need, and applies the persistent compilation cache that
:func:`rotor.enable_compilation_cache` asked for before JAX was imported. It also chooses
XLA's elemental emitters for the CPU (:data:`rotor.cache.XLA_CPU_FLAG`, process-wide) unless
``$XLA_FLAGS`` names that option already. ``import rotor``
alone imports neither this module nor JAX, so that the commands that compute nothing start
fast. Base layer: imports nothing from rotor but :mod:`rotor.cache`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .cache import apply_compilation_cache, choose_xla_emitters

__all__ = ["jax", "jnp"]

choose_xla_emitters()
jax.config.update("jax_enable_x64", True)
apply_compilation_cache(jax)
