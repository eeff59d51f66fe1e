"""A second engine of the same shape (cylinders, tables, grid) runs the first one's compiled
programs with its own numbers: nothing is compiled again (counted from JAX's monitoring
events, in the test only)."""

import re
from pathlib import Path

import equinox as eqx
import jax
import numpy as np
import pytest
from jax import monitoring

import rotor

COMPILE_EVENT = "/jax/core/compile/backend_compile_duration"
_compiled: list[float] = []
_counting = [False]


def _listener(name, duration, **_):
    if name == COMPILE_EVENT and _counting[0]:
        _compiled.append(duration)


monitoring.register_event_duration_secs_listener(_listener)


def _other_engine_file(folder):
    """Another engine file of the same shape: another name, bore, masses and flywheel."""
    text = (Path(rotor.__file__).parent / "presets" / "4chn15.toml").read_text()
    for old, new in (
        (r"^name = .*$", 'name = "another engine of the same shape"'),
        (r"^bore_m = 0\.1497", "bore_m = 0.1440"),
        (r"^reciprocating_kg = [0-9.]+", "reciprocating_kg = 8.9"),
        (r"^inertia_kgm2 = [0-9.]+", "inertia_kgm2 = 7.5"),
    ):
        text, n = re.subn(old, new, text, count=1, flags=re.M)
        assert n == 1, old
    path = folder / "other.toml"
    path.write_text(text)
    return path


def _everything(engine):
    r = rotor.steady_state(engine)
    rotor.steady_state(engine, rpm=900.0, load=rotor.PropellerLoad(300.0, 1250.0))
    rotor.steady_sweep(engine, rpm=np.linspace(900.0, 1500.0, 16), progress=False)
    flywheel = rotor.inertia_for_delta(engine, 0.01)
    J = float(engine.crankshaft.inertia_kgm2)

    def delta(j):
        return rotor.steady_state(eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, j)).delta

    return float(r.delta), flywheel, float(jax.grad(delta)(J))


def test_a_second_engine_of_the_same_shape_compiles_nothing(tmp_path):
    first = rotor.load_engine("4chn15")
    second = rotor.load_engine(str(_other_engine_file(tmp_path)))
    assert second.cylinders == first.cylinders and second.name != first.name
    a = _everything(first)
    _compiled.clear()
    _counting[0] = True
    try:
        b = _everything(second)
    finally:
        _counting[0] = False
    assert _compiled == [], f"{len(_compiled)} programs compiled for the second engine"
    assert a[0] != pytest.approx(b[0], rel=1e-3)  # its own numbers, not the first engine's answer
    assert a[2] != pytest.approx(b[2], rel=1e-3)
