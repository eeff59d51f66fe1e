"""JAX as rotor computes with it: every module of rotor that imports JAX imports this one
too, directly or through another (:mod:`rotor.checks`, :mod:`rotor.cycles`;
``tests/project/test_architecture.py`` checks), before it computes anything.

Importing it switches on JAX's float64 (``jax_enable_x64``, process-wide), which rotor's
numerics need, and applies the persistent compilation cache that
:func:`rotor.enable_compilation_cache` asked for before JAX was imported. It also chooses
XLA's elemental emitters for the CPU (:data:`XLA_CPU_FLAG`, process-wide) unless
``$XLA_FLAGS`` names that option already. ``import rotor``
alone imports neither this module nor JAX, so that the commands that compute nothing start
fast. Base layer: imports nothing from rotor but :mod:`rotor.cache`.
"""

from __future__ import annotations

import os

import jax
import jax.numpy as jnp

from .cache import apply_compilation_cache

__all__ = ["XLA_CPU_FLAG", "jax", "jnp"]

XLA_CPU_FLAG = "--xla_cpu_use_fusion_emitters=false"
"""The XLA option rotor adds to ``$XLA_FLAGS``. XLA compiles rotor's kernels for the CPU
in about 60 % of the time with its elemental emitters than with its fusion emitters (the
default of jaxlib 0.7 and later), and they run as fast, to the same results within the
last bits (``benchmarks/xla_emitters.py`` measures both). XLA reads ``$XLA_FLAGS`` once,
when JAX starts its first backend: the option applies when rotor is imported before the
process computes anything with JAX (the usual case), and child processes inherit it.
Set ``XLA_FLAGS=--xla_cpu_use_fusion_emitters=true`` to keep XLA's default."""


def _choose_xla_emitters() -> None:
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_cpu_use_fusion_emitters" not in flags:
        os.environ["XLA_FLAGS"] = f"{flags} {XLA_CPU_FLAG}".strip()


_choose_xla_emitters()
jax.config.update("jax_enable_x64", True)
apply_compilation_cache(jax)
