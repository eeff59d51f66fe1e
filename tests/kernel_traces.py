"""How often rotor's compiled kernels are traced (and so compiled), counted from JAX's own
monitoring events: each trace of a jitted function at the top level records the function's
name (``/jax/core/compile/jaxpr_trace_duration``). The kernels are the compiled
functions of :mod:`rotor.dynamics` that integrate or solve; small helpers and JAX's own
operations (``add``, ``broadcast_in_dim``) are not counted."""

from __future__ import annotations

import importlib

import jax

_EVENT = "/jax/core/compile/jaxpr_trace_duration"
_COUNT = {"traces": 0}


# the compiled kernels that integrate or solve (what a new number must not compile again),
# by module of rotor.dynamics
_KERNELS = {
    "equation": ("closed_run", "grid_run"),
    "adaptive": ("angle_run", "time_run", "dense_at_angles"),
    "steady": ("_closed_kernel", "_closed_steady", "_shooting_kernel", "_finish_arrays"),
    "transient": ("_samples", "_gather", "_chunk_figures"),
}


def _kernel_names() -> frozenset[str]:
    names = set()
    for module, kernels in _KERNELS.items():
        defined = vars(importlib.import_module(f"rotor.dynamics.{module}"))
        missing = [k for k in kernels if k not in defined]
        assert not missing, f"rotor.dynamics.{module} no longer defines {missing}"
        names.update(kernels)
    return frozenset(names)


KERNELS = _kernel_names()


def _listen(event: str, duration_secs: float, **kwargs: object) -> None:
    if event == _EVENT and kwargs.get("fun_name") in KERNELS:
        _COUNT["traces"] += 1


jax.monitoring.register_event_duration_secs_listener(_listen)


def kernel_traces() -> int:
    """How many times a kernel of :mod:`rotor.dynamics` was traced in this process so far."""
    return _COUNT["traces"]
