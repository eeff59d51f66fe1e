"""The simulator at the edges of its range: a result within its accuracy or a clear error,
never a silent NaN, never a hang."""

import tomllib

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import rotor
from rotor.engine.file import preset_path
from rotor.units import RPM_PER_RAD_S as RPM


def _finite(res):
    return bool(np.all(np.isfinite(np.asarray(res.omega))) and np.all(np.isfinite(np.asarray(res.t))))


def _with(engine, where, value):
    return eqx.tree_at(where, engine, jnp.asarray(value, dtype=jnp.float64))


@pytest.fixture(scope="module")
def single():
    return rotor.load_engine("tue-single")


def test_speed_range_30_to_20000_rpm(diesel, single):
    fast = rotor.steady_state(single, rpm=20000.0)
    assert _finite(fast) and float(fast.mean_rpm) == pytest.approx(20000.0, rel=1e-12)
    # the inertia torque grows with ω², the gas torque does not: δ first falls, then rises again
    assert float(fast.delta) < float(rotor.steady_state(single, rpm=1000.0).delta)
    heavy = _with(diesel, lambda e: e.crankshaft.inertia_kgm2, 1e3)
    slow = rotor.steady_state(heavy, rpm=30.0)
    assert _finite(slow) and 0.1 < float(slow.delta) < 1.0
    with pytest.raises(rotor.NoSteadyStateError, match="30 rpm"):
        rotor.steady_state(diesel, rpm=30.0)
    for rpm, engine in ((30.0, diesel), (20000.0, single)):
        with pytest.warns(UserWarning, match="will accelerate"):  # no load: it runs away, and says so
            assert _finite(rotor.simulate(engine, rpm=rpm, cycles=3))


@pytest.mark.parametrize("lam", [0.15, 0.45])
def test_rod_ratio_extremes(diesel, lam):
    R = float(diesel.geometry.crank_radius_m)
    engine = _with(diesel, lambda e: e.geometry.rod_length_m, R / lam)
    ss = rotor.steady_state(engine)
    assert _finite(ss) and float(ss.periodicity_error if ss.periodicity_error is not None else 0.0) < 1e-10
    coast = rotor.simulate(engine.replace(pressure=rotor.NoPressure()), rpm=1000.0, cycles=20)
    ke = 0.5 * rotor.reduced_inertia(engine, coast.theta) * coast.omega**2
    assert float(jnp.max(jnp.abs(ke / ke[0] - 1))) < 1e-9


def test_pin_offset_of_three_tenths_of_the_crank(diesel):
    R = float(diesel.geometry.crank_radius_m)
    engine = _with(diesel, lambda e: e.geometry.pin_offset_m, 0.3 * R)
    closed = rotor.steady_state(engine)
    shoot = rotor.steady_state(engine, method="shooting")
    np.testing.assert_allclose(np.asarray(shoot.omega), np.asarray(closed.omega), rtol=1e-9)
    # the offset makes the cycle asymmetric about TDC: I(θ) is no longer even
    inertia = rotor.reduced_inertia(engine, jnp.array([0.3, -0.3]))
    assert abs(float(inertia[0] - inertia[1])) > 1e-6


def test_inertia_from_1e_minus_4_to_1e3(single):
    """δ from about 0.5 down to 1e-6, ∝ 1/J where the flywheel dominates; beyond, a clear error."""
    deltas = {}
    for J in (0.003, 0.01, 0.1, 1.0, 10.0, 1e3):
        deltas[J] = float(rotor.steady_state(_with(single, lambda e: e.crankshaft.inertia_kgm2, J)).delta)
    assert 0.2 < deltas[0.003] < 0.8
    assert deltas[1e3] < 2e-6
    Js = sorted(deltas)
    assert all(deltas[a] > deltas[b] for a, b in zip(Js, Js[1:]))
    assert deltas[10.0] / deltas[1e3] == pytest.approx(100.0, rel=1e-3)
    with pytest.raises(rotor.NoSteadyStateError, match="crank angle"):
        rotor.steady_state(_with(single, lambda e: e.crankshaft.inertia_kgm2, 1e-4))


def _inline(n):
    """tue-single's cylinder as an inline n-cylinder engine firing every 720/n degrees."""
    data = tomllib.loads(preset_path("tue-single").read_text())
    data["name"], data["cylinders"] = f"inline {n}", n
    data["layout"] = {
        "throw_angles_deg": [(k * 720.0 / n) % 360.0 for k in range(n)],
        "bank_angles_deg": [0.0] * n,
        "firing_order": list(range(1, n + 1)),
    }
    data["crankshaft"]["inertia_kgm2"] = 0.015 * n
    data.pop("torsion")  # the bench's three-mass chain is the single cylinder's
    return rotor.engine_from_dict(data)


@pytest.mark.parametrize("n", [1, 16])
def test_one_to_sixteen_cylinders(n):
    engine = _inline(n)
    ss = rotor.steady_state(engine)
    run = rotor.simulate(
        engine,
        rpm=float(ss.omega[0]) * RPM,
        cycles=2,
        load=rotor.ConstantLoad(ss.load_torque_Nm),
        step_deg=0.25,
    )
    P = run.points_per_cycle
    np.testing.assert_allclose(np.asarray(run.omega[P : 2 * P]), np.asarray(ss.omega), rtol=1e-10)
    o = ss.orders(max_order=n / 2 + 0.5)
    amp = dict(zip(np.round(o.order, 3), np.asarray(o.speed_amplitude_rad_s)))
    # an even-firing n-cylinder four-stroke has speed harmonics only at multiples of n/2
    main = amp[n / 2]
    assert all(a < 1e-6 * main for k, a in amp.items() if (2 * k) % n)


def test_a_hundred_thousand_cycles_keep_the_phase(diesel):
    """The neutral constant load: 1e5 cycles from the steady state stay on it (θ ≈ 1.3e6 rad)."""
    ss = rotor.steady_state(diesel, grid_deg=2.0)
    load = rotor.ConstantLoad(ss.load_torque_Nm)
    cycles = 100_000
    run = rotor.simulate(diesel, rpm=float(ss.omega[0]) * RPM, cycles=cycles, load=load, grid_deg=2.0, step_deg=90.0)
    assert float(run.t[-1]) == pytest.approx(cycles * float(ss.period_s), rel=1e-10)
    assert float(run.omega[-1]) == pytest.approx(float(ss.omega[0]), rel=1e-10)


def test_reversal_runs_on_through_zero_speed(diesel):
    run = rotor.simulate(
        diesel, rpm=300.0, cycles=3, load=rotor.ConstantLoad(3000.0), stop_at_stall=False, max_time_s=1.0
    )
    w = np.asarray(run.omega)
    assert _finite(run) and not run.stalled
    assert w.min() < 0  # the load drives it backwards
    assert "before reaching the end" in run.incomplete


def test_a_pressure_table_with_a_one_degree_rise(diesel):
    angle = np.arange(0.0, 720.0, 1.0)
    p = np.full_like(angle, 1.0e5)
    p[(angle > 360.0) & (angle <= 420.0)] = 60e5  # 1 bar to 60 bar within 1°, held 60°
    table = rotor.PressureTable(angle, p)
    engine = diesel.replace(pressure=table)
    ss = rotor.steady_state(engine)
    fine = rotor.steady_state(engine, grid_deg=0.125)
    assert float(ss.delta) == pytest.approx(float(fine.delta), rel=1e-6)
    load = rotor.PropellerLoad(float(rotor.mean_gas_torque(engine)), 1250.0)
    runs = [rotor.simulate(engine, rpm=1200.0, cycles=3, load=load, method=m) for m in ("closed", "grid", "angle")]
    for r in runs:
        assert _finite(r)
        assert float(jnp.max(jnp.abs(r.omega[-721:] / runs[0].omega[-721:] - 1))) < 1e-6


def test_tolerances_from_1e_minus_3_to_1e_minus_13(diesel):
    load = rotor.PropellerLoad(1100.0, 1250.0)
    ref = rotor.simulate(diesel, rpm=1200.0, cycles=2, load=load, method="closed", grid_deg=0.125, step_deg=1.0)
    for rtol in (1e-3, 1e-6, 1e-9, 1e-13):
        r = rotor.simulate(diesel, rpm=1200.0, cycles=2, load=load, method="angle", rtol=rtol)
        assert _finite(r)
        error = float(jnp.max(jnp.abs(r.omega / ref.omega - 1)))
        # rtol bounds each step's error; over two cycles the error is 10–60× rtol
        # (benchmarks/simulator_accuracy.py), and the 4° step limit holds loose ones near 1e-6;
        # the 0.25° tables differ from the 0.125° reference by 3e-11, the floor at rtol 1e-13
        assert error < 100 * rtol + 1e-10, (rtol, error)
    with pytest.raises(rotor.EngineError, match="rtol"):
        rotor.simulate(diesel, cycles=1, load=load, method="angle", rtol=1e-16)


def test_float32_inputs_are_widened(diesel):
    engine = _with(diesel, lambda e: e.crankshaft.inertia_kgm2, np.float32(10.2))
    load = rotor.PropellerLoad(np.float32(1100.0), np.float32(1250.0))
    r32 = rotor.simulate(engine, rpm=np.float32(1200.0), cycles=2, load=load)
    r64 = rotor.simulate(diesel, rpm=1200.0, cycles=2, load=rotor.PropellerLoad(1100.0, 1250.0))
    assert r32.omega.dtype == jnp.float64
    # 10.2 and 1200 are not float32 numbers: they arrive rounded, and the result says so
    assert float(jnp.max(jnp.abs(r32.omega / r64.omega - 1))) < 1e-6
    assert load.torque_Nm.dtype == jnp.float64
