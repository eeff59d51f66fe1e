"""Arguments of the wrong type or shape: a one-line TypeError or rotor.EngineError that
names the argument and what it takes, never an AttributeError or a NumPy or JAX message.

An engine's name is not an engine: every public function takes a :class:`rotor.Engine`,
and its message names ``rotor.load_engine``, which turns a name or a file into one."""

from __future__ import annotations

import equinox as eqx
import numpy as np
import pytest

import rotor

ENGINE = rotor.load_engine("4chn15")


def _one_line(e: BaseException) -> str:
    text = str(e)
    assert "\n" not in text, text
    return text


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: rotor.steady_state("4chn15"), r"steady_state\(engine\)"),
        (lambda: rotor.simulate("4chn15"), r"simulate\(engine\)"),
        (lambda: rotor.steady_sweep("4chn15"), r"steady_sweep\(engine\)"),
        (lambda: rotor.design_flywheel("4chn15", 0.01), r"design_flywheel\(engine\)"),
        (lambda: rotor.reduced_inertia("4chn15", 0.0), r"reduced_inertia\(engine\)"),
        (lambda: rotor.gas_torque("4chn15", 0.0), r"gas_torque\(engine\)"),
    ],
)
def test_an_engine_name_is_refused_pointing_at_load_engine(call, name):
    with pytest.raises(TypeError, match=name) as info:
        call()
    assert "rotor.load_engine" in _one_line(info.value)


@pytest.mark.parametrize(
    "call, error, name",
    [
        (lambda: rotor.steady_state(ENGINE, rpm="fast"), TypeError, "rpm"),
        (lambda: rotor.steady_state(ENGINE, rpm=1250 + 1j), TypeError, "rpm"),
        (lambda: rotor.steady_state(ENGINE, rpm=np.array([1000.0, 1250.0])), rotor.EngineError, "rpm"),
        (lambda: rotor.steady_state(ENGINE, rpm=None, imep_scale="full"), TypeError, "imep_scale"),
        (lambda: rotor.steady_state(ENGINE, imep_scale=np.ones(3)), rotor.EngineError, "imep_scale"),
        (lambda: rotor.steady_state(ENGINE, load=300.0), TypeError, r"steady_state\(load\)"),
        (lambda: rotor.steady_state(ENGINE, friction=0.5), TypeError, r"steady_state\(friction\)"),
        (lambda: rotor.simulate(ENGINE, "fast", 2), TypeError, "rpm"),
        (lambda: rotor.simulate(ENGINE, 2j, 2), TypeError, "rpm"),
        (lambda: rotor.simulate(ENGINE, 1250.0, 2, load="300"), TypeError, r"simulate\(load\)"),
        (lambda: rotor.steady_sweep(ENGINE, [1000.0, 1250 + 1j]), TypeError, r"steady_sweep\(rpm\)"),
        (lambda: rotor.steady_sweep(ENGINE, "fast"), TypeError, r"steady_sweep\(rpm\)"),
        (lambda: rotor.reduced_inertia(ENGINE, "top"), TypeError, r"reduced_inertia\(theta\)"),
        (lambda: rotor.piston_motion(0.0, 0.1, 1j), TypeError, r"piston_motion\(rod_length_m\)"),
        (lambda: rotor.total_torque(ENGINE, 0.0, "fast"), TypeError, r"total_torque\(omega\)"),
    ],
)
def test_a_wrong_type_names_the_argument(call, error, name):
    with pytest.raises(error, match=name) as info:
        call()
    _one_line(info.value)


def test_an_array_inertia_is_refused_naming_the_key():
    """One crankshaft inertia per engine: an array is refused where the table is built and
    where ``eqx.tree_at`` put it (the solver checks the engine again)."""
    with pytest.raises(rotor.EngineError, match=r"\[crankshaft\] inertia_kgm2: one number") as info:
        rotor.Crankshaft(inertia_kgm2=[1.0, 2.0])
    assert "steady_sweep" in _one_line(info.value)
    engine = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, ENGINE, np.array([1.0, 2.0]))
    with pytest.raises(rotor.EngineError, match=r"\[crankshaft\] inertia_kgm2: one number"):
        rotor.steady_state(engine)
    with pytest.raises(rotor.EngineError, match=r"inertia_kgm2"):
        rotor.steady_state(rotor.prepare(ENGINE).with_inertia(np.array([1.0, 2.0])))


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: rotor.reduced_inertia(ENGINE, np.nan), r"reduced_inertia\(theta\)"),
        (lambda: rotor.gas_torque(ENGINE, np.array([0.0, np.inf])), r"gas_torque\(theta\)"),
        (lambda: rotor.total_torque(ENGINE, 0.0, np.nan), r"total_torque\(omega\)"),
        (lambda: rotor.piston_motion(0.0, 0.1, 0.05), r"piston_motion\(rod_length_m\)"),
        (lambda: rotor.rod_motion(0.0, 0.0, 0.4), r"rod_motion\(crank_radius_m\)"),
        (lambda: rotor.mean_piston_speed(0.0, 130.0), r"mean_piston_speed\(stroke_m\)"),
        (lambda: rotor.combustion_pattern(2, 4, misfire_rate=np.nan), "misfire_rate"),
    ],
)
def test_known_values_are_checked_as_traced_ones_are(call, name):
    """NaN in is an error out, for known values as under jit (tests/dynamics/test_traced_checks.py)."""
    with pytest.raises(rotor.EngineError, match=name) as info:
        call()
    _one_line(info.value)
