"""rotor: rotational dynamics of piston engines.

Crank kinematics, reduced inertia I(θ), gas and inertia torques, and the crankshaft's
speed fluctuation, in JAX.

Importing rotor is cheap: the public names are listed once, in ``rotor/__init__.pyi``
(what type checkers and the documentation read), and each is imported from its module on
first use (``rotor.steady_state`` imports :mod:`rotor.dynamics.steady`, and JAX with it),
so that ``rotor --help`` and the commands that compute nothing with JAX start fast.
``dir(rotor)`` and ``__all__`` list every public name all the same.

Importing rotor switches on two process-wide settings. JAX's float64
(``jax_enable_x64``), which rotor's numerics need: where JAX is not imported yet, through
its documented environment variable ``JAX_ENABLE_X64`` (unless the user set it), which JAX
reads when it is imported; where it is, through ``jax.config``. rotor's modules that
compute set it again when they are imported (:mod:`rotor.jaxconfig`). And XLA's elemental
emitters for the CPU, which compile rotor's kernels in about 0.65 of the time, through
``$XLA_FLAGS`` unless the user named that option there (:data:`rotor.cache.XLA_CPU_FLAG`).
JAX's persistent compilation cache stays as the user left it: the ``rotor`` command
switches it on, and :func:`rotor.enable_compilation_cache` does so
in Python.
"""

import os as _os
import sys as _sys
from typing import Any

import lazy_loader as _lazy

from .cache import choose_xla_emitters as _choose_xla_emitters
from .cache import submodules_on_demand as _submodules_on_demand

__version__ = "0.1.0"

if "jax" in _sys.modules:
    _sys.modules["jax"].config.update("jax_enable_x64", True)
else:
    _os.environ.setdefault("JAX_ENABLE_X64", "1")
_choose_xla_emitters()

_public, _, __all__ = _lazy.attach_stub(__name__, __file__)
_submodule = _submodules_on_demand(__name__)


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use (and then kept here), or a
    subpackage or module (``rotor.engine``)."""
    try:
        return _public(name)
    except AttributeError:
        return _submodule(name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
