"""rotor: rotational dynamics of piston engines.

Crank kinematics, reduced inertia I(θ), gas and inertia torques, and the crankshaft's
speed fluctuation, in JAX.

Importing rotor is cheap: the public names are listed once, in ``rotor/__init__.pyi``
(what type checkers and the documentation read), and each is imported from its module on
first use (``rotor.steady_state`` imports :mod:`rotor.dynamics.steady`, and JAX with it),
so that ``rotor --help`` and the commands that compute nothing with JAX start fast.
``dir(rotor)`` and ``__all__`` list every public name all the same.

rotor's modules that compute switch on one process-wide setting of JAX when they are
imported: float64 (``jax_enable_x64``), which rotor's numerics need
(:mod:`rotor.jaxconfig`). JAX's persistent compilation cache stays as the user left it:
the ``rotor`` command switches it on, and :func:`rotor.enable_compilation_cache` does so
in Python.
"""

from typing import Any

import lazy_loader as _lazy

from .cache import submodules_on_demand as _submodules_on_demand

__version__ = "0.1.0"

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
