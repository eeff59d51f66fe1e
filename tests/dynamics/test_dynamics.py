"""The simulator against invariants, an independent scipy reference, and itself.

Tolerances: energy 1e-9, formulations 1e-6 at default settings,
periodicity 1e-10, steady state vs a settled run 1e-6, gradients 1e-5.
"""

import sys

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import ROOT
from kernel_traces import kernel_traces

import rotor
from rotor.units import RPM_PER_RAD_S as RPM

sys.path.insert(0, str(ROOT / "benchmarks"))
from reference import scipy_angle_reference  # noqa: E402


def _with_inertia(engine, J):
    return eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, J)


@pytest.fixture(scope="module")
def single():
    """tue-single without gas pressure: the free-coasting case."""
    return rotor.load_engine("tue-single").replace(pressure=rotor.NoPressure())


@pytest.fixture(scope="module")
def propeller():
    return rotor.PropellerLoad(1100.0, 1250.0)


# ----------------------------------------------------------------------------- invariants
def test_free_coasting_keeps_kinetic_energy(single):
    """1000 cycles from 1000 rpm: ½·I(θ)·ω² constant to 1e-9 while ω follows I(θ)."""
    res = rotor.simulate(single, rpm=1000.0, cycles=1000)
    assert res.method == "closed" and not res.stalled
    inertia = rotor.reduced_inertia(single, res.theta)  # the exact I(θ), not the tables
    ke = 0.5 * inertia * res.omega**2
    assert float(jnp.max(jnp.abs(ke / ke[0] - 1))) < 1e-9
    # ω fluctuates by what I(θ) implies: ω_max/ω_min = sqrt(I_max/I_min)
    expected = np.sqrt(float(jnp.max(inertia) / jnp.min(inertia)))
    assert float(jnp.max(res.omega) / jnp.min(res.omega)) == pytest.approx(expected, rel=1e-9)
    assert float(res.delta) > 1e-3  # a light single: the fluctuation is real, not numerical noise


@pytest.mark.parametrize("method, rtol", [("grid", None), ("angle", None), ("time", 1e-12)])
def test_free_coasting_adaptive_methods(single, method, rtol):
    """The time domain drifts like any non-symplectic solver (its drift at the default rtol:
    benchmarks/simulator_accuracy.py, part 1); at rtol 1e-12 it holds 1e-9."""
    res = rotor.simulate(single, rpm=1000.0, cycles=20, method=method, rtol=rtol)
    ke = 0.5 * rotor.reduced_inertia(single, res.theta) * res.omega**2
    assert float(jnp.max(jnp.abs(ke / ke[0] - 1))) < 1e-9


# ----------------------------------------------------------------------------- scipy reference
@pytest.mark.parametrize("preset", ["4chn15", "mwm6"])
def test_formulations_agree_with_scipy_dop853(preset, propeller):
    engine = rotor.load_engine(preset)
    cycles = 4
    load = propeller if preset == "4chn15" else rotor.PropellerLoad(400.0, 2200.0)
    rpm = 0.95 * float(engine.operating.rpm)
    results = {
        m: rotor.simulate(engine, rpm=rpm, cycles=cycles, load=load, method=m)
        for m in ("closed", "grid", "angle", "time")
    }
    P = results["closed"].points_per_cycle
    last = slice((cycles - 1) * P, cycles * P)
    theta = np.asarray(results["closed"].theta[last])
    w_ref, t_ref = scipy_angle_reference(engine, rpm, cycles, float(load.c), theta)
    scale = float(np.mean(w_ref))
    for method, res in results.items():
        assert res.uniform_cycles == cycles, method
        # every method: the uniform grid and then the end of the run, nothing else
        assert res.theta.shape == (cycles * P + 1,), method
        assert float(res.theta[-1]) == pytest.approx(cycles * res.cycle_rad, rel=1e-12), method
        np.testing.assert_allclose(np.asarray(res.theta[last]), theta, rtol=0, atol=1e-9)
        err = np.max(np.abs(np.asarray(res.omega[last]) - w_ref)) / scale
        assert err < 1e-6, (method, err)
        # the time at a fixed crank angle: phase, not just shape
        assert abs(float(res.t[last][0]) - t_ref[0]) < 1e-6 * t_ref[0], method


def test_fidelity_levels_differ_by_the_pinned_amounts(diesel):
    """4chn15 at 1250 rpm: how δ and the orders move between fidelity levels (README table)."""
    res = {f: rotor.steady_state(diesel, fidelity=f) for f in ("variable", "coefficients", "constant")}

    def orders(r):
        o = r.orders(max_order=4)
        return dict(zip(np.round(o.order, 3), np.asarray(o.speed_amplitude_rad_s)))

    v = res["variable"]
    ov = orders(v)
    assert float(v.delta) == pytest.approx(0.006665, rel=1e-3)
    rel = {f: float(r.delta / v.delta) - 1 for f, r in res.items()}
    assert rel["coefficients"] == pytest.approx(0.0323, abs=5e-4)  # the A/B/C form drops order 4 of I(θ)
    assert rel["constant"] == pytest.approx(0.0052, abs=5e-4)
    oc, ok = orders(res["coefficients"]), orders(res["constant"])
    assert oc[4.0] / ov[4.0] - 1 == pytest.approx(0.1148, abs=2e-3)
    assert oc[2.0] / ov[2.0] - 1 == pytest.approx(-0.0008, abs=5e-4)
    assert ok[2.0] / ov[2.0] - 1 == pytest.approx(0.0103, abs=5e-4)
    # a balanced inline four: no half orders, no first order
    for o in (0.5, 1.0, 1.5):
        assert ov[o] < 1e-9 * ov[2.0]
    # the textbook estimate (Shishkov, "Dinamika dvigatelei") is within 0.5 % of the simulated δ here
    assert float(v.textbook_delta / v.delta) - 1 == pytest.approx(0.0043, abs=5e-4)


def test_series_fidelity_is_the_lambda_series_and_converges_as_lambda_cubed(diesel):
    """``fidelity="series"``: I(θ) = J + Σ(m_rot·R² + m_rec·s′²) with the λ-series s′ (closed
    form, checked on the table), and its δ error against exact kinematics shrinks as λ³."""
    from rotor.dynamics.crank_train import crank_train

    g = diesel.geometry
    R, L = float(g.crank_radius_m), float(g.rod_length_m)
    tr = crank_train(diesel, "series")
    th = np.asarray(tr.nodes())
    lam = R / L
    m_rec, m_rot = (float(m) for m in diesel.masses.two_mass_split(L))
    tdc = np.deg2rad(np.asarray(diesel.tdc_angles_deg))[:, None]
    a = th[None, :] - tdc
    ds = R * (np.sin(a) + lam / 2 * np.sin(2 * a))  # central mechanism
    expected = float(diesel.crankshaft.inertia_kgm2) + np.sum(m_rot * R**2 + m_rec * ds**2, axis=0)
    np.testing.assert_allclose(np.asarray(tr.values[:, 0]), expected, rtol=1e-12)

    def gap(lam_):
        e = eqx.tree_at(lambda e: e.geometry.rod_length_m, diesel, R / lam_)
        d = {f: float(rotor.steady_state(e, fidelity=f).delta) for f in ("variable", "series")}
        return abs(d["series"] / d["variable"] - 1)

    g1, g2 = gap(0.3), gap(0.15)
    assert 1e-4 < g1 < 2e-2  # a real model error at λ = 0.3 …
    assert 4 < g1 / g2 < 16  # … that halving λ divides by about 2³


# ----------------------------------------------------------------------------- steady state
def test_steady_state_is_periodic_and_methods_agree(diesel):
    closed = rotor.steady_state(diesel)
    shoot = rotor.steady_state(diesel, method="shooting")
    assert closed.method == "closed" and shoot.method == "shooting"
    assert float(shoot.periodicity_error) < 1e-10
    assert float(closed.mean_rpm) == pytest.approx(1250.0, rel=1e-12)
    np.testing.assert_allclose(np.asarray(shoot.omega), np.asarray(closed.omega), rtol=1e-9)
    # one more cycle from the closed-form start returns to the same state
    load = rotor.ConstantLoad(closed.load_torque_Nm)
    run = rotor.simulate(diesel, rpm=float(closed.omega[0]) * RPM, cycles=2, load=load, step_deg=0.25)
    P = run.points_per_cycle
    assert run.omega.shape[0] == 2 * P + 1  # two whole cycles and the sample that ends them
    np.testing.assert_allclose(np.asarray(run.omega[P : 2 * P + 1]), np.asarray(run.omega[: P + 1]), rtol=1e-10)
    np.testing.assert_allclose(np.asarray(run.omega[:P]), np.asarray(closed.omega), rtol=1e-10)
    # the load is the mean engine torque: n·IMEP·Vh/Θ
    assert float(closed.load_torque_Nm) == pytest.approx(float(rotor.mean_gas_torque(diesel)), rel=1e-6)


def test_steady_state_matches_a_settled_run(diesel, propeller):
    ss = rotor.steady_state(diesel, rpm=1250.0, load=propeller)
    fuel = float(ss.fuel_scale)
    run = rotor.simulate(
        diesel, rpm=1150.0, cycles=300, load=propeller, combustion=np.full((300, diesel.cylinders), fuel)
    )
    assert float(run.cycle_mean_omega[-1]) * RPM == pytest.approx(1250.0, rel=1e-9)
    assert float(run.delta_per_cycle[-1]) == pytest.approx(float(ss.delta), rel=1e-6)


def test_steady_state_with_speed_linear_friction_balances_its_mean(diesel):
    fr = rotor.Friction(fmep_pa=0.6e5, fmep_per_speed_pa_s_per_m=0.1e5)
    ss = rotor.steady_state(diesel, friction=fr)
    assert ss.method == "closed" and ss.note is None
    # the balancing load is the engine's mean torque minus the friction at the mean speed, to O(δ²)
    a, b, c = (float(x) for x in fr.torque_coefficients(diesel))
    w = 1250 / RPM
    expected = float(rotor.mean_gas_torque(diesel)) - a - b * w
    assert float(ss.load_torque_Nm) == pytest.approx(expected, rel=1e-4)


def test_no_steady_state_says_where(diesel):
    light = _with_inertia(diesel, 0.01)
    with pytest.raises(rotor.NoSteadyStateError, match=r"kinetic energy would reach zero at crank angle \d+\.\d°"):
        rotor.steady_state(light, rpm=300.0)


def test_steady_state_rejects_a_time_dependent_load(diesel):
    step = rotor.LoadStep(rotor.ConstantLoad(100.0), rotor.ConstantLoad(200.0), 1.0)
    with pytest.raises(rotor.EngineError, match="does not change in time"):
        rotor.steady_state(diesel, load=step)


# ----------------------------------------------------------------------------- stall, start
def test_stall_ends_cleanly_and_methods_agree(diesel):
    load = rotor.ConstantLoad(3000.0)  # far above the engine's 1132 N·m
    runs = [
        rotor.simulate(diesel, rpm=1250.0, cycles=50, load=load, method=m) for m in ("closed", "grid", "angle", "time")
    ]
    for r in runs:
        assert r.stalled
        assert np.all(np.isfinite(np.asarray(r.omega)))
        assert abs(float(r.omega[-1])) < 1e-6
        assert r.stall_time_s == pytest.approx(runs[0].stall_time_s, rel=1e-5)
        assert r.stall_angle_rad == pytest.approx(runs[0].stall_angle_rad, rel=1e-5)
    assert runs[0].method == "closed+time"


def test_start_from_rest_with_a_starter(diesel):
    res = rotor.simulate(diesel, rpm=0.0, cycles=3, load=rotor.ConstantLoad(-2000.0))
    assert res.method == "time" and not res.stalled
    assert float(res.omega[0]) == 0.0
    assert res.uniform_cycles == 3
    assert float(res.omega[-1]) > 0


def test_no_or_a_weak_starter_stalls(single):
    wiebe = rotor.load_engine("tue-single")
    # at θ = 0 the piston is at TDC and nothing drives it: it never turns
    still = rotor.simulate(wiebe, rpm=0.0, cycles=2, load=rotor.ConstantLoad(0.0))
    assert still.stalled and abs(still.stall_angle_rad) < 1e-6
    # 5 N·m turns it, but not through the first compression
    weak = rotor.simulate(wiebe, rpm=0.0, cycles=2, load=rotor.ConstantLoad(-5.0))
    assert weak.stalled and 0.1 < weak.stall_angle_rad < wiebe.cycle_rad
    assert weak.uniform_cycles == 0 and np.all(np.isfinite(np.asarray(weak.omega)))
    assert float(jnp.max(weak.omega)) > 1.0


# ----------------------------------------------------------------------------- JAX
def test_no_recompile_for_new_numbers(diesel, propeller):
    rotor.simulate(diesel, rpm=1200.0, cycles=3, load=propeller)
    rotor.steady_state(diesel, rpm=1250.0)
    before = kernel_traces()
    rotor.simulate(_with_inertia(diesel, 12.0), rpm=1100.0, cycles=3, load=rotor.PropellerLoad(900.0, 1200.0))
    rotor.steady_state(_with_inertia(diesel, 8.0), rpm=1000.0)
    assert kernel_traces() == before


def _fd(f, x, h):
    return (f(x + h) - f(x - h)) / (2 * h)


def test_gradients_of_delta_and_orders_match_finite_differences(diesel, propeller):
    def steady(J, what):
        r = rotor.steady_state(_with_inertia(diesel, J))
        return r.delta if what == "delta" else r.orders().speed_amplitude_rad_s[3]  # order 2

    for what in ("delta", "order2"):
        g = float(jax.grad(lambda J: steady(J, what))(10.2))
        assert g == pytest.approx(float(_fd(lambda J: steady(J, what), 10.2, 1e-3)), rel=1e-5)

    # a geometry field reaches δ through I(θ), the kinematics and the gas torque at once
    def by_rod(L):
        return rotor.steady_state(eqx.tree_at(lambda e: e.geometry.rod_length_m, diesel, L)).delta

    g = float(jax.grad(by_rod)(0.3839))
    assert g == pytest.approx(float(_fd(by_rod, 0.3839, 1e-5)), rel=1e-5)

    def transient(T):
        return rotor.simulate(diesel, rpm=1200.0, cycles=3, load=rotor.PropellerLoad(T, 1250.0)).delta

    g = float(jax.grad(transient)(1100.0))
    assert g == pytest.approx(float(_fd(transient, 1100.0, 0.1)), rel=1e-5)


def test_vmap_over_flywheels(diesel):
    Js = jnp.array([5.0, 10.0, 20.0])
    deltas = jax.vmap(lambda J: rotor.steady_state(_with_inertia(diesel, J)).delta)(Js)
    for J, d in zip(Js, deltas):
        assert float(d) == pytest.approx(float(rotor.steady_state(_with_inertia(diesel, float(J))).delta), rel=1e-10)
    # δ ∝ 1/(J + mean inertia of the crank train) to first order
    rest = float(rotor.mean_reduced_inertia(diesel)) - 10.2
    assert float(deltas[0] / deltas[2]) == pytest.approx((20.0 + rest) / (5.0 + rest), rel=0.01)


def test_no_steady_state_is_a_solver_outcome_and_a_status_under_jit(diesel):
    light = _with_inertia(diesel, 0.01)
    with pytest.raises(rotor.NoSteadyStateError) as info:
        rotor.steady_state(light, rpm=300.0)
    assert isinstance(info.value, rotor.errors.SolverError) and not isinstance(info.value, rotor.EngineError)
    # under jit no error can be raised: the result says so
    ok = jax.jit(lambda r: rotor.steady_state(light, rpm=r).converged)(300.0)
    assert not bool(ok)
    assert bool(rotor.steady_state(diesel).converged)
