"""A chain without damping at a critical speed: said before any solving."""

import equinox as eqx
import jax.numpy as jnp
import pytest
from jax import monitoring

import rotor

_compiled: list[str] = []


def _listener(name, duration, fun_name="", **_):
    if name == "/jax/core/compile/jaxpr_trace_duration":
        _compiled.append(fun_name)


monitoring.register_event_duration_secs_listener(_listener)


@pytest.fixture(scope="module")
def undamped():
    return make_undamped()


def make_undamped():
    e = rotor.load_engine("mwm6")
    t = e.torsion
    return eqx.tree_at(
        lambda e: (e.torsion.absolute_damping_Nms_per_rad, e.torsion.relative_damping_Nms_per_rad),
        e,
        (jnp.zeros_like(t.absolute_damping_Nms_per_rad), jnp.zeros_like(t.relative_damping_Nms_per_rad)),
    )


def test_undamped_chain_at_a_critical_speed_is_refused_before_solving(undamped):
    c = rotor.campbell(undamped, rpm=(550.0, 2750.0))
    rpm = float(c.critical_rpm[0]) * (1 + 5e-5)
    _compiled.clear()
    with pytest.raises(rotor.NoSteadyStateError, match=r"order 12 excites mode 1 .* no damping"):
        rotor.torsional_response(undamped, rpm=rpm)
    assert not any("kernel" in name for name in _compiled), _compiled  # the harmonic balance never traced
