"""Invariants checked at the end of every run: time increases, θ does not
go back, every number finite, ω positive in the angle domain, min ≤ mean ≤ max, a steady
state's period and balance finite. A violation is a one-line SolverError that says what to
tighten, never a printed number. And the case that was silently wrong: a starter torque of
10¹² N·m, whose time quadrature stepped backwards (mean_rpm −5194.5)."""

import dataclasses
import functools
import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import rotor
from rotor import cli
from rotor.dynamics import equation
from rotor.dynamics.invariants import check_speed_result, steady_invariants_hold

STARTER = rotor.ConstantLoad(-1e12)  # a starter torque of 10¹² N·m driving the crankshaft


@pytest.fixture(scope="module")
def run(diesel):
    return rotor.simulate(diesel, cycles=2, load=rotor.ConstantLoad(1131.95), progress=False)


@pytest.fixture(scope="module")
def steady(diesel):
    return rotor.steady_state(diesel)


def _set(x, i, value):
    return jnp.asarray(x).at[i].set(value)


def _one_line_error(result, *words):
    with pytest.raises(rotor.SolverError) as info:
        check_speed_result(result)
    msg = str(info.value)
    assert "\n" not in msg and "cannot be trusted" in msg
    assert any(k in msg for k in ("grid_deg", "steps_per_cycle", "rtol", "method='time'")), msg
    for w in words:
        assert w in msg, msg
    return msg


BROKEN = {
    "time steps back": (lambda r: {"t": _set(r.t, 5, r.t[3])}, "time does not increase"),
    "θ goes back": (lambda r: {"theta": _set(r.theta, 6, r.theta[2])}, "crank angle decreases"),
    "ω NaN": (lambda r: {"omega": _set(r.omega, 7, jnp.nan)}, "speed is not finite"),
    "engine torque ∞": (lambda r: {"torque": _set(r.torque, 8, jnp.inf)}, "engine torque is not finite"),
    "load torque NaN": (lambda r: {"load_torque": _set(r.load_torque, 9, jnp.nan)}, "load torque is not finite"),
    "dω/dt NaN": (lambda r: {"accel": _set(r.accel, 10, jnp.nan)}, "acceleration is not finite"),
    "kinetic energy ∞": (lambda r: {"omega": _set(r.omega, 11, 1e200)}, "kinetic energy overflows"),
    "ω negative": (lambda r: {"omega": _set(r.omega, 12, -1.0)}, "speed is not positive"),
    "ω zero, not stalled": (lambda r: {"omega": _set(r.omega, 13, 0.0)}, "speed is not positive"),
    "mean above max": (lambda r: {"t": r.t * 0.5}, "time-mean speed"),
    "mean below min": (lambda r: {"t": r.t * 2.0}, "time-mean speed"),
    "t NaN": (lambda r: {"t": _set(r.t, 4, jnp.nan)}, "time is not finite"),
}


@pytest.mark.parametrize("case", list(BROKEN))
def test_each_broken_invariant_is_a_one_line_solver_error(run, case):
    change, words = BROKEN[case]
    check_speed_result(run)  # the real run keeps them all
    msg = _one_line_error(dataclasses.replace(run, **change(run)), words, "method 'closed'", "grid_deg")
    assert "cycle 1 at crank angle" in msg or "mean" in msg or "kinetic" in msg


def test_finite_values_whose_sum_overflows_keep_the_invariants(run):
    """Every value finite, though their sum is not: nothing is refused (the one-pass check
    of the values hands over to the checks one by one, which pass); one infinity among
    them is still named."""
    huge = jnp.full_like(run.torque, 1e308)
    check_speed_result(dataclasses.replace(run, torque=huge, load_torque=huge))
    _one_line_error(
        dataclasses.replace(run, torque=huge, load_torque=_set(huge, 9, jnp.inf)), "load torque is not finite"
    )


def test_a_stalled_run_may_end_at_zero_speed(run):
    check_speed_result(dataclasses.replace(run, omega=_set(run.omega, 13, 0.0), stalled=True))
    _one_line_error(dataclasses.replace(run, omega=_set(run.omega, 13, -1.0), stalled=True), "speed is negative")


def test_the_remedy_follows_the_method(run):
    bad = {"t": _set(run.t, 5, run.t[3])}
    for method, remedy in (("grid", "steps_per_cycle"), ("angle", "rtol"), ("time", "rtol"), ("closed+time", "rtol")):
        _one_line_error(dataclasses.replace(run, method=method, **bad), remedy, f"method {method!r}")


STEADY_BROKEN = {
    "period negative": ({"period_s": -0.1}, "period of the cycle"),
    "period NaN": ({"period_s": float("nan")}, "period of the cycle"),
    "load NaN": ({"load_torque_Nm": float("nan")}, "balancing load torque"),
    "fuel ∞": ({"load_torque_Nm": None, "fuel_scale": float("inf")}, "fuel scale"),
    "textbook δ NaN": ({"textbook_delta": float("nan")}, "textbook δ"),
}


@pytest.mark.parametrize("case", list(STEADY_BROKEN))
def test_a_steady_state_with_a_bad_period_or_balance_is_refused(steady, case):
    change, words = STEADY_BROKEN[case]
    check_speed_result(steady)
    _one_line_error(dataclasses.replace(steady, **change), words, "steady state", "grid_deg")


@functools.partial(jax.jit, static_argnums=8)
def _screen(t, theta, omega, accel, torque, load, period, numbers, cycle_rad):
    """The screen as it finds the speed's range itself, and as the program calls it with the
    lowest and highest samples it has found (both must agree)."""
    arrays = (t, theta, omega, accel, torque, load)
    own = steady_invariants_hold(*arrays, period, numbers, cycle_rad)
    given = steady_invariants_hold(*arrays, period, numbers, cycle_rad, omega_range=(jnp.min(omega), jnp.max(omega)))
    return own, given


def _screened(r):
    """Whether the compiled screen of a steady state's invariants lets ``r`` through."""
    numbers = [0.0 if v is None else v for v in (r.load_torque_Nm, r.fuel_scale, r.excess_work_J, r.textbook_delta)]
    arrays = (r.t, r.theta, r.omega, r.accel, r.torque, r.load_torque)
    own, given = _screen(*(jnp.asarray(a) for a in arrays), r.period_s, numbers, r.cycle_rad)
    assert bool(own) == bool(given)
    return bool(own)


def _refused(r):
    try:
        check_speed_result(r)
    except rotor.SolverError:
        return True
    return False


def test_the_steady_states_compiled_screen_is_never_looser_than_the_checks(steady):
    """The closed form's program screens its own arrays and the host checks them only where
    the screen fails: every broken steady state the checks refuse, the screen stops too,
    and a sound one passes it."""
    assert _screened(steady) and not _refused(steady)
    cases = [change(steady) for change, _ in BROKEN.values()] + [change for change, _ in STEADY_BROKEN.values()]
    refused = 0
    for change in cases:
        broken = dataclasses.replace(steady, **change)
        if _refused(broken):
            refused += 1
            assert not _screened(broken), change
    assert refused >= len(cases) - 2  # a steady state's mean speed is its period's: scaling t breaks nothing


@settings(max_examples=40, deadline=None)
@given(
    field=st.sampled_from(["t", "theta", "omega", "accel", "torque", "load_torque"]),
    at=st.integers(0, 2879),
    value=st.sampled_from([np.nan, np.inf, -np.inf, 0.0, -1.0, 1e200, -1e-300]),
)
def test_the_screen_stops_every_broken_sample_the_checks_refuse(steady, field, at, value):
    broken = dataclasses.replace(steady, **{field: _set(getattr(steady, field), at, value)})
    assert not (_refused(broken) and _screened(broken))


@settings(max_examples=30, deadline=None)
@given(margin=st.floats(-3e-6, 3e-6))
def test_the_screens_mean_speed_slack_is_within_the_checks(steady, margin):
    """A period that puts the mean speed just outside the highest or lowest speed, around
    the checks' slack: the screen never lets through what the checks refuse."""
    for edge in (np.max(np.asarray(steady.omega)), np.min(np.asarray(steady.omega))):
        broken = dataclasses.replace(steady, period_s=steady.cycle_rad / (edge * (1.0 + margin)))
        assert not (_refused(broken) and _screened(broken))


def test_the_host_checks_a_steady_state_where_the_screen_stops_it(diesel, monkeypatch):
    """A steady state whose program's screen passes is not checked again on the host; one
    whose screen fails is (traced again without kept programs: the screen is in the program)."""
    from rotor.dynamics import steady as steady_module

    checked = []
    monkeypatch.setattr(steady_module, "check_speed_result", checked.append)
    rotor.steady_state(diesel, rpm=1100.0)
    assert not checked
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")
    jax.clear_caches()
    monkeypatch.setattr(steady_module, "steady_invariants_hold", lambda *args, **kwargs: jnp.asarray(False))
    result = rotor.steady_state(diesel, rpm=1100.0)
    assert checked == [result]
    monkeypatch.undo()
    jax.clear_caches()


def test_nothing_is_checked_on_tracers(run):
    bad_t = _set(run.t, 5, run.t[3])

    @jax.jit
    def f(t):
        check_speed_result(dataclasses.replace(run, t=t))
        return jnp.sum(t)

    assert np.isfinite(float(f(bad_t)))


@pytest.mark.parametrize("method", ["closed", "grid", "angle", "time"])
def test_normal_runs_of_every_method_pass(diesel, method):
    res = rotor.simulate(diesel, cycles=2, load=rotor.ConstantLoad(1131.95), method=method, progress=False)
    check_speed_result(res)
    assert float(res.min_rpm) <= float(res.mean_rpm) <= float(res.max_rpm)


@pytest.mark.parametrize("method", ["closed", "shooting"])
def test_normal_steady_states_pass(diesel, method):
    check_speed_result(rotor.steady_state(diesel, method=method))  # steady_state checks it too


def test_a_stall_and_a_start_from_rest_pass(diesel):
    stall = rotor.simulate(diesel, rpm=300.0, cycles=2, load=rotor.ConstantLoad(3000.0), progress=False)
    assert stall.stalled
    check_speed_result(stall)
    start = rotor.simulate(diesel, rpm=0.0, cycles=2, load=rotor.ConstantLoad(-3000.0), progress=False)
    assert float(start.omega[0]) == 0.0
    check_speed_result(start)


def test_starter_torque_of_1e12_is_handed_to_the_time_domain(diesel):
    """The angle domain's time quadrature stepped backwards where ω rose from 1250 rpm to
    10⁶ rpm within a step; the kernels now hand such a cycle to the time domain, and the
    answer is that of method='time' (the mean speed half the final one: E grows linearly in θ)."""
    ref = rotor.simulate(diesel, cycles=2, load=STARTER, method="time", progress=False)
    for method in ("closed", "grid"):
        res = rotor.simulate(diesel, cycles=2, load=STARTER, method=method, progress=False)
        check_speed_result(res)
        assert res.method == f"{method}+time"
        assert np.all(np.diff(np.asarray(res.t)) > 0)
        assert float(res.mean_rpm) == pytest.approx(float(ref.mean_rpm), rel=1e-6)
        assert float(res.mean_rpm) == pytest.approx(0.5 * float(res.max_rpm), rel=2e-2)
    angle = rotor.simulate(diesel, cycles=2, load=STARTER, method="angle", progress=False)
    check_speed_result(angle)
    assert float(angle.mean_rpm) == pytest.approx(float(ref.mean_rpm), rel=1e-6)


def test_cli_starter_torque_gives_the_time_domains_answer(capsys):
    code = cli.main(["simulate", "4chn15", "--load=-1e12", "--cycles", "2", "--json", "--quiet"])
    out = json.loads(capsys.readouterr().out)
    assert code in (0, None)
    assert out["method"] == "closed+time"
    assert 0 < out["min_rpm"] <= out["mean_rpm"] <= out["max_rpm"]
    assert out["mean_rpm"] == pytest.approx(0.5 * out["max_rpm"], rel=2e-2)


def test_a_crankshaft_of_1e_minus_9_kgm2_from_1e5_rpm(diesel):
    """An absurd but valid crankshaft: a finite, positive answer or an honest stall, the same
    as the time domain's, never a NaN or a negative speed in the JSON."""
    tiny = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, jnp.asarray(1e-9, dtype=jnp.float64))
    ss = rotor.steady_state(tiny)  # the crankshaft rattles (δ ≈ 2300) but the cycle is periodic
    s = ss.to_json_dict()
    assert 0 < s["min_rpm"] <= s["mean_rpm"] <= s["max_rpm"] and np.isfinite(s["delta"])
    load = rotor.ConstantLoad(1131.95)
    ref = rotor.simulate(tiny, rpm=1e5, cycles=2, load=load, method="time", progress=False)
    res = rotor.simulate(tiny, rpm=1e5, cycles=2, load=load, method="grid", progress=False)
    check_speed_result(res)
    assert res.method == "grid+time" and res.stalled == ref.stalled
    assert res.stall_time_s == pytest.approx(ref.stall_time_s, rel=1e-6)
    d = res.to_json_dict()
    assert all(np.isfinite(d[k]) for k in ("mean_rpm", "min_rpm", "max_rpm"))
    assert d["min_rpm"] > -1e-3 and d["min_rpm"] <= d["mean_rpm"] <= d["max_rpm"]


@pytest.fixture
def old_quadrature(monkeypatch):
    """The kernels as they were: no cycle handed over for an untrusted time quadrature
    (traced again: no kept program, which is found by rotor's source, not by a patch)."""
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")
    jax.clear_caches()
    monkeypatch.setattr(equation, "untrusted_steps", lambda E, t: jnp.asarray(False))
    yield
    monkeypatch.undo()
    jax.clear_caches()


def test_the_backwards_time_of_the_old_quadrature_is_caught(diesel, old_quadrature):
    """The old kernel printed mean_rpm < 0 as an answer; the end-of-run check refuses it."""
    with pytest.raises(rotor.SolverError) as e:
        rotor.simulate(diesel, cycles=2, load=STARTER, method="closed", progress=False)
    msg = str(e.value)
    assert "\n" not in msg
    for part in ("time does not increase", "cycle 1 at crank angle 0.0°", "grid_deg"):
        assert part in msg


def test_simulate_refuses_the_backwards_time(diesel, old_quadrature):
    with pytest.raises(rotor.SolverError, match="time does not increase"):
        rotor.simulate(diesel, cycles=2, load=STARTER, method="closed", progress=False)


def test_cli_refuses_the_backwards_time_in_one_line(capsys, old_quadrature):
    code = cli.main(["simulate", "4chn15", "--load=-1e12", "--cycles", "2", "--method", "closed", "--json"])
    out, err = capsys.readouterr()
    assert code == 1 and out == ""
    assert len(err.strip().splitlines()) == 1 and "time does not increase" in err and "grid_deg" in err
