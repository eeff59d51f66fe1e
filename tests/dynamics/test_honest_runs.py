"""Numbers a user can trust: per-cycle δ and orders of a transient with its trend
removed, loads that are carried and never replaced, a runaway that says so, a progress bar
that compiles nothing more, and a stall reported within its cycle."""

import json
import warnings

import numpy as np
import pytest
from kernel_traces import kernel_traces

import rotor
from rotor import cli


@pytest.fixture(scope="module")
def propeller_run(diesel):
    return rotor.simulate(diesel, rpm=1200.0, cycles=20, load=rotor.PropellerLoad(1100.0, 1250.0), progress=False)


# ----------------------------------------------------------------------------- 1. per-cycle truth
def test_steady_delta_is_unchanged_and_equals_its_cycle(diesel):
    ss = rotor.steady_state(diesel)
    assert float(ss.delta) == pytest.approx(0.006665, rel=1e-3)  # the README's figure
    assert float(ss.delta) == float(ss.delta_per_cycle[0])
    assert float(ss.speed_range_ratio) == pytest.approx(float(ss.delta), rel=1e-12)


def test_transient_delta_is_the_last_cycles_and_the_range_is_named_apart(propeller_run):
    run = propeller_run
    assert float(run.delta) == float(run.delta_per_cycle[-1])
    # the run-up from 1200 rpm is in the range over the run, not in δ
    assert float(run.speed_range_ratio) > 5 * float(run.delta)
    assert float(run.delta) == pytest.approx(0.0069, abs=3e-4)
    s = run.to_json_dict()
    assert s["delta"] == pytest.approx(float(run.delta)) and "last complete cycle" in s["delta_of"]
    assert s["speed_range_ratio"] == pytest.approx(float(run.speed_range_ratio))
    text = run.summary()
    assert "last complete cycle, its linear trend removed" in text and "drift included" in text


def test_a_settled_run_has_the_steady_states_delta(diesel):
    """Per-cycle δ of a run that has settled is the steady state's δ, cycle by cycle."""
    ss = rotor.steady_state(diesel)
    load = rotor.ConstantLoad(float(ss.load_torque_Nm))
    run = rotor.simulate(diesel, rpm=float(ss.omega[0]) * 30 / np.pi, cycles=4, load=load, progress=False)
    np.testing.assert_allclose(np.asarray(run.delta_per_cycle), float(ss.delta), rtol=1e-5)


def _half_order_share(run, cycle=-1):
    o = run.orders(cycle=cycle)
    amp = dict(zip(np.round(o.order, 2), np.asarray(o.speed_amplitude_rad_s)))
    return amp[0.5] / amp[2.0]


def test_accelerating_balanced_four_shows_no_half_order_leakage(diesel):
    """A balanced inline four has no half orders; running up from 1200 rpm must not invent
    one (order 0.5 was 17 % of the firing order 2 before the trend was removed)."""
    run = rotor.simulate(diesel, rpm=1200.0, cycles=10, load=rotor.PropellerLoad(1100.0, 1250.0), progress=False)
    assert float(run.cycle_mean_omega[-1] - run.cycle_mean_omega[0]) * 30 / np.pi > 40  # it does run up
    assert _half_order_share(run) < 0.01
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no load: it runs away, 1250 → 1680 rpm in six cycles
        away = rotor.simulate(diesel, cycles=6, load=None, progress=False)
    assert _half_order_share(away) < 0.03 and _half_order_share(away, cycle=4) < 0.03


def test_logged_and_simulated_speed_share_one_detrending():
    """rotor.cycles removes an exact linear ramp entirely from the spectrum and δ."""
    from rotor.cycles import cycle_slopes, cycle_spectrum

    P, cycle = 720, 4 * np.pi
    psi = np.arange(P) * cycle / P
    means = 100.0 + 2.0 * np.arange(5)
    slope = 2.0 / cycle
    omega = means[:, None] + slope * (psi[None, :] - cycle / 2) + 0.5 * np.cos(2 * psi)[None, :]
    np.testing.assert_allclose(cycle_slopes(means, cycle), slope)
    X = cycle_spectrum(omega, means, cycle)
    np.testing.assert_allclose(np.abs(X[:, 1]), 0.0, atol=1e-12)  # order 0.5: nothing leaks
    np.testing.assert_allclose(np.abs(X[:, 4]), 0.5, rtol=1e-12)  # order 2


# ----------------------------------------------------------------------------- 2. loads mean what they say
def test_a_constant_load_is_carried_not_replaced(diesel):
    ss = rotor.steady_state(diesel, load=rotor.ConstantLoad(500.0))
    assert float(ss.load_torque_Nm) == pytest.approx(500.0) and 0 < float(ss.fuel_scale) < 1
    assert ss.solved_for == "fuel_scale"
    # the engine's mean torque meets the 500 N·m (no friction in this engine file)
    assert float(np.mean(np.asarray(ss.load_torque))) == pytest.approx(500.0, rel=1e-9)
    assert float(np.mean(np.asarray(ss.torque))) == pytest.approx(500.0, rel=1e-6)
    balanced = rotor.steady_state(diesel)
    assert float(balanced.load_torque_Nm) == pytest.approx(1131.95, abs=0.01)
    assert balanced.solved_for == "load" and float(balanced.fuel_scale) == 1.0
    assert "(solved: the load" in balanced.summary()
    assert "500.00 N·m (given)" in ss.summary() and "(solved: the fuelling that carries the load" in ss.summary()


def test_a_load_on_a_motored_engine_is_refused(diesel):
    motored = diesel.replace(pressure=rotor.NoPressure())
    with pytest.raises(rotor.EngineError, match="firing engine"):
        rotor.steady_state(motored, load=rotor.ConstantLoad(100.0))


def test_simulate_without_load_warns_that_it_accelerates(diesel):
    with pytest.warns(UserWarning, match="will accelerate"):
        rotor.simulate(diesel, cycles=2, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rotor.simulate(diesel, cycles=2, load=rotor.ConstantLoad(1131.95), progress=False)


def test_cli_steady_carries_the_load(capsys):
    cli.main(["steady", "4chn15", "--load", "500", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert out["load_torque_Nm"] == pytest.approx(500.0) and 0 < out["fuel_scale"] < 1


def test_cli_simulate_without_load_balances_at_the_start_speed(capsys):
    cli.main(["simulate", "4chn15", "--cycles", "3"])
    out = capsys.readouterr().out
    assert "balancing" in out and "1131.95" in out
    assert float(out.split("mean speed")[1].split("rpm")[0]) == pytest.approx(1250.0, abs=2.0)
    cli.main(["simulate", "4chn15", "--cycles", "3", "--json"])
    s = json.loads(capsys.readouterr().out)
    assert s["load_torque_Nm"] == pytest.approx(1131.95, abs=0.01) and s["solved_for"] == "load"


# ----------------------------------------------------------------------------- 3. progress costs nothing
@pytest.mark.parametrize("method", ["closed", "grid", "angle"])
def test_progress_bar_compiles_nothing_more(diesel, method, monkeypatch):
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")  # traced as jit traces: a kept program would trace nothing
    load = rotor.PropellerLoad(1100.0, 1250.0)
    counts = {}
    for progress, cycles in ((False, 41), (True, 50)):  # new padded sizes (48, 64): each compiles afresh
        before = kernel_traces()
        rotor.simulate(diesel, rpm=1200.0, cycles=cycles, load=load, method=method, progress=progress)
        counts[progress] = kernel_traces() - before
    assert counts[True] == counts[False] > 0


def test_progress_bar_hears_from_inside_the_run(diesel, capsys, monkeypatch):
    from rotor.progress import Progress

    monkeypatch.setattr(Progress, "update", _record_update)
    _SEEN.clear()
    rotor.simulate(diesel, rpm=1200.0, cycles=200, load=rotor.PropellerLoad(1100.0, 1250.0), progress=True)
    assert len(_SEEN) >= 10 and _SEEN[-1] == 200 and _SEEN == sorted(_SEEN)


_SEEN: list[int] = []


def _record_update(self, done):
    _SEEN.append(done)


# ----------------------------------------------------------------------------- 4. small items
def test_stall_is_reported_within_its_cycle(diesel, capsys):
    cli.main(["simulate", "4chn15", "--rpm", "300", "--cycles", "6", "--load", "3000", "--json"])
    s = json.loads(capsys.readouterr().out)
    assert s["stalled"]
    cycle_deg = 720.0
    assert 0 <= s["stall_angle_deg"] < cycle_deg
    assert s["stall_angle_total_deg"] == pytest.approx((s["stall_cycle"] - 1) * cycle_deg + s["stall_angle_deg"])


def test_misfire_counts_cycles_and_cylinders_from_one(diesel, capsys):
    from rotor.cli.run import parse_misfires

    assert parse_misfires("1:1,3:4", cycles=3, cylinders=4) == [(1, 1), (3, 4)]  # as combustion_pattern takes them
    for bad, what in (("0:1", "cycle 0"), ("4:1", "cycle 4"), ("2:5", "cylinder 5"), ("2:0", "cylinder 0")):
        with pytest.raises(rotor.EngineError, match=what):
            parse_misfires(bad, cycles=3, cylinders=4)


def test_orders_plot_is_in_rad_per_s(propeller_run):
    ax = propeller_run.plot(kind="orders")
    assert "rad/s" in ax.get_ylabel()
    assert "last cycle" in ax.get_title()
    heights = [p.get_height() for p in ax.patches]
    np.testing.assert_allclose(heights, np.asarray(propeller_run.orders().speed_amplitude_rad_s))


def test_plurals():
    from rotor.dynamics.result import SpeedResult

    assert "1 complete cycle\n" in rotor.steady_state(rotor.load_engine("tue-single"), grid_deg=1.0).summary()
    assert SpeedResult  # the type the summaries come from
