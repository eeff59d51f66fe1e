"""Few shapes: runs and records padded to a standard size reuse one compiled program, and the
padding changes no result (relative difference ≤ 1e-12)."""

import jax
import numpy as np
import pytest

import rotor
import rotor.diagnostics.identification as identification
import rotor.dynamics.transient as transient
from rotor.cache import padded_size

_TRACES: list[str] = []


def _listen(event: str, duration_secs: float, **kwargs: object) -> None:
    if event == "/jax/core/compile/jaxpr_trace_duration":
        _TRACES.append(str(kwargs.get("fun_name")))


jax.monitoring.register_event_duration_secs_listener(_listen)


def test_standard_sizes():
    assert [padded_size(n) for n in range(1, 26)] == [
        1, 2, 3, 4, 6, 6, 8, 8, 12, 12, 12, 12, 16, 16, 16, 16, 24, 24, 24, 24, 24, 24, 24, 24, 32,
    ]  # fmt: skip
    for n in range(1, 5000):
        p = padded_size(n)
        assert n <= p < 1.5 * n or p == n  # at most half as much work again
    with pytest.raises(ValueError, match="at least 1"):
        padded_size(0)


def _figures(r):
    return {f: np.asarray(getattr(r, f)) for f in ("theta", "t", "omega", "torque", "delta_per_cycle")}


def _worst(a, b):
    return max(float(np.max(np.abs(a[k] - b[k]) / np.maximum(np.abs(b[k]), 1e-300))) for k in a)


@pytest.mark.parametrize("method", ["closed", "grid"])
def test_a_run_of_another_length_reuses_the_program_and_padding_changes_nothing(diesel, method, monkeypatch):
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")  # traced as jit traces: a kept program would trace nothing
    load = rotor.ConstantLoad(rotor.steady_state(diesel, rpm=1250).load_torque_Nm)
    rotor.simulate(diesel, cycles=6, rpm=1250, load=load, method=method)
    _TRACES.clear()
    padded = rotor.simulate(diesel, cycles=5, rpm=1250, load=load, method=method)  # one chunk of 6 cycles, cut to 5
    kernel = f"{method}_run"
    assert kernel not in _TRACES, _TRACES
    assert "_gather" not in _TRACES, _TRACES  # the samples gathered at the padded length too
    assert padded.uniform_cycles == 5 and padded.theta.shape == (5 * padded.points_per_cycle + 1,)
    monkeypatch.setattr(transient, "padded_size", lambda n: n)  # a chunk of exactly the run
    exact = rotor.simulate(diesel, cycles=5, rpm=1250, load=load, method=method)
    assert kernel in _TRACES  # a program of its own size
    assert _worst(_figures(padded), _figures(exact)) <= 1e-12


def test_identification_blocks_padded_change_nothing(diesel, monkeypatch):
    load = rotor.ConstantLoad(rotor.steady_state(diesel, rpm=1250).load_torque_Nm)
    run = rotor.simulate(diesel, cycles=10, rpm=1250, load=load, method="closed")
    padded = rotor.identify(diesel, run, block_cycles=2)  # 5 blocks, fitted as 6
    assert padded.blocks == 5 and padded_size(5) == 6
    monkeypatch.setattr(identification, "padded_size", lambda n: n)
    exact = rotor.identify(diesel, run, block_cycles=2)
    for f in ("scale", "imep_pa", "load_torque_Nm", "omega_model"):
        a, b = np.asarray(getattr(padded, f)), np.asarray(getattr(exact, f))
        assert a.shape == b.shape
        assert float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300))) <= 1e-12, f


def test_a_table_of_another_cylinder_reuses_the_program(diesel, monkeypatch):
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")  # traced as jit traces: a kept program would trace nothing
    first = rotor.crank_table(diesel, cylinder=1)
    _TRACES.clear()
    other = rotor.crank_table(diesel, cylinder=3)
    assert "_table_columns" not in _TRACES, _TRACES
    # the textbook forces of that cylinder at its own cycle angle (the firing angle's shift)
    table = other.to_pandas()
    theta = (
        np.deg2rad(table["angle_deg"].to_numpy())
        + diesel.firing_angles_rad[2]
        - (2 * np.pi if diesel.strokes == 4 else 0.0)
    )
    forces = rotor.crank_forces(diesel, theta, other.rpm * np.pi / 30, cylinder=3, model=other.kinematics)
    for column in ("s_m", "pg_N", "t_N", "m_Nm"):
        np.testing.assert_allclose(table[column], np.asarray(forces[column]), rtol=1e-12, atol=1e-9)
    assert first.cylinder == 1 and other.cylinder == 3
