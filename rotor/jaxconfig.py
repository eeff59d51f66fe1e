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

import os

import jax
import jax.numpy as jnp

from .cache import apply_compilation_cache

__all__ = ["ASYNC_DISPATCH_ENV", "jax", "jnp"]

ASYNC_DISPATCH_ENV = "JAX_CPU_ENABLE_ASYNC_DISPATCH"
"""JAX's environment variable for its ``jax_cpu_enable_async_dispatch`` option. Unless it is
set, rotor runs compiled programs on the CPU inline, in the calling thread (the option
False), where JAX would hand each to a worker thread and wait for it: rotor's calls need
their results at once, and the hand-over costs more than a small program runs (the
closed-form steady state compiled with its engine closed over 63–107 → 20 µs on a 2-core
machine, ``benchmarks/steady_limit.py``). It applies where JAX's CPU backend starts
after rotor is imported."""

jax.config.update("jax_enable_x64", True)
if ASYNC_DISPATCH_ENV not in os.environ:
    jax.config.update("jax_cpu_enable_async_dispatch", False)
apply_compilation_cache(jax)
