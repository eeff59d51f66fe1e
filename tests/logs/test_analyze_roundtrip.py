"""Simulated round trip: a 4-cylinder engine (rotor.simulate) turned into the tooth
timestamps of a 60-2 wheel with known tooth-spacing errors (±0.2°) and timer jitter;
the analysis must give back δ and the first orders of each cycle within 1 % and the
tooth errors within 0.02°.

The wheel's errors are estimated on a calibration run (a coast-down 3000 → 500 rpm of
the bare wheel with a gas-torque fluctuation that scales as 1/ω², like a motored
compression), saved as JSON, and applied to the engine's recording: the engine's own
fluctuation at integer orders (the reciprocating inertia of an inline four, order 2,
about 1 % of the speed) cannot be told from a wheel error within one steady recording
(see rotor/wheel.py), so a steady run alone cannot give the errors at the engine's orders.

Also: the errors estimated on the engine's own recording with ``cylinders=4`` (right at
the orders not left to the engine; δ then carries the wheel's errors at orders 2, 4, …,
and the note says by about how much); 200 ns of timer jitter; unequal cylinders (half
orders); the firing revolution from the speed alone (flagged as uncertain).
"""

import sys

import numpy as np
import pytest
from conftest import ROOT
from scipy.interpolate import CubicSpline

import rotor
from rotor.logs.wheel import TWO_PI
from rotor.units import RPM_PER_RAD_S

sys.path.insert(0, str(ROOT / "benchmarks"))
import synthetic_wheel  # noqa: E402
from synthetic_wheel import ERRORS, WHEEL  # noqa: E402

PITCH = WHEEL.pitch_rad
JITTER_S = 20e-9  # timer jitter (σ), a 50 MHz capture timer
GAP_DEG = -60.0  # crank angle of the first tooth edge after the gap: TDC is 60° after the gap


def tooth_times(t_of_theta, theta_lo, theta_hi, gap_rad, rng, jitter_s=JITTER_S):
    return synthetic_wheel.tooth_times(t_of_theta, theta_lo, theta_hi, gap_rad, rng, jitter_s)


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    """Tooth errors from a coast-down 3000 → 500 rpm of the bare wheel with a 1/ω² fluctuation."""
    edges = synthetic_wheel.coast_down_edges(JITTER_S)
    track = rotor.locate_teeth(edges, WHEEL)
    te = rotor.estimate_tooth_errors(track, engine_orders=())
    path = tmp_path_factory.mktemp("wheel") / "teeth.json"
    te.save(path)
    return te, path


def test_tooth_errors_from_a_coastdown_within_002_deg(calibration):
    te, path = calibration
    assert "coast-down" in te.method
    err = np.rad2deg(np.abs(te.errors_rad - ERRORS))
    assert err.max() < 0.02, err.max()
    back = rotor.ToothErrors.load(path)
    np.testing.assert_allclose(back.errors_rad, te.errors_rad, rtol=0, atol=1e-15)


@pytest.fixture(scope="module")
def engine_run():
    e = rotor.load_engine("4chn15")
    steady = rotor.steady_state(e)
    load = float(steady.load_torque_Nm)
    rpm0 = float(steady.omega[0]) * RPM_PER_RAD_S
    res = rotor.simulate(
        e,
        rpm=rpm0,
        cycles=8,
        load=rotor.ConstantLoad(load),
        method="grid",
        step_deg=0.25,
        steps_per_cycle=2880,
        progress=False,
    )
    return res


def _analyse(res, tooth_errors, jitter_s=JITTER_S, firing=None, **kw):
    theta, t = np.asarray(res.theta), np.asarray(res.t)
    edges = tooth_times(
        CubicSpline(theta, t), theta[0], theta[-1], np.deg2rad(GAP_DEG), np.random.default_rng(2), jitter_s
    )
    # the first reference edge: TDC lies 60° after every gap; the firing TDC (crank 360°) in revolution …
    first_ref = np.deg2rad(GAP_DEG) + TWO_PI * np.ceil((theta[0] - np.deg2rad(GAP_DEG)) / TWO_PI)
    parity = int(np.floor((TWO_PI - first_ref) / TWO_PI)) % 2
    return rotor.analyze_log(
        rotor.Log.from_arrays(tooth_time_s=edges),
        WHEEL,
        tdc_deg=-GAP_DEG,
        firing=parity if firing is None else firing,
        tooth_errors=tooth_errors,
        **kw,
    )


def _match(res, an):
    """Simulator cycle index of each analysed cycle (by start time)."""
    P = res.points_per_cycle
    t_sim = np.asarray(res.t)[: res.uniform_cycles * P : P]
    k = np.array([int(np.argmin(np.abs(t_sim - t0))) for t0 in an.t_start_s])
    assert np.max(np.abs(t_sim[k] - an.t_start_s)) < 2e-5  # uncorrected: tooth 0 is the angle origin
    return k


def test_round_trip_delta_and_orders_within_1_percent(engine_run, calibration):
    res = engine_run
    te, path = calibration
    an = _analyse(res, path)  # the saved calibration, reused
    k = _match(res, an)
    assert an.cycles >= 5
    sim_delta = np.asarray(res.delta_per_cycle)[k]
    np.testing.assert_allclose(an.delta, sim_delta, rtol=0.01)
    np.testing.assert_allclose(an.mean_omega, np.asarray(res.cycle_mean_omega)[k], rtol=1e-5)
    for i, kk in enumerate(k):
        o = res.orders(cycle=int(kk) + 1, max_order=6)  # row kk is cycle kk + 1
        amp = np.asarray(o.speed_amplitude_rad_s)
        for order in (2.0, 4.0):  # the inline four's main orders
            j = int(np.flatnonzero(np.isclose(o.order, order))[0])
            assert an.amplitude_of(order)[i] == pytest.approx(amp[j], rel=0.01)
            jj = int(np.flatnonzero(np.isclose(an.order, order))[0])
            assert abs(np.angle(np.exp(1j * (an.phase_rad[i, jj] - np.asarray(o.speed_phase_rad)[j])))) < 0.01


def test_without_correction_the_tooth_errors_spoil_delta(engine_run):
    """The same recording without correction: δ is far off (the test above can fail)."""
    res = engine_run
    an = _analyse(res, None)
    k = _match(res, an)
    off = np.abs(an.delta / np.asarray(res.delta_per_cycle)[k] - 1)
    print("delta off without correction", off)
    assert np.min(off) > 0.05


def _sim_orders(res, k, orders):
    """(amplitude, phase) of the simulator's speed at ``orders``, cycles k."""
    out = np.zeros((len(k), len(orders), 2))
    for i, kk in enumerate(k):
        o = res.orders(cycle=int(kk) + 1, max_order=6)  # row kk is cycle kk + 1
        for j, q in enumerate(orders):
            m = int(np.flatnonzero(np.isclose(o.order, q))[0])
            out[i, j] = np.asarray(o.speed_amplitude_rad_s)[m], np.asarray(o.speed_phase_rad)[m]
    return out


def test_estimate_on_the_firing_run_with_cylinders(engine_run):
    """No calibration: the errors from the 4-cylinder recording itself. With cylinders=4
    the orders 2, 4, … 28 are left to the engine; the wheel's errors at the other orders
    come back within 0.02°. Its errors at orders 2, 4, … stay in the speed: for this wheel
    (±0.2°, 0.03° per order) and this engine (δ = 0.0067, an inline four with a heavy
    flywheel) δ comes out at 0.029, 4.4× the simulator's — no data from a firing run can do
    better; the note says so and gives the size (±0.026), which covers the error."""
    from rotor.logs.wheel import order_fit_matrix

    res = engine_run
    an = _analyse(res, "estimate", cylinders=4)
    te = an.tooth_errors
    assert te.engine_orders == tuple(range(2, 29, 2))
    X = order_fit_matrix(PITCH * np.arange(WHEEL.edges_per_rev), te.engine_orders)
    beta, *_ = np.linalg.lstsq(X, ERRORS, rcond=None)
    assert np.rad2deg(np.max(np.abs(te.errors_rad - (ERRORS - X @ beta)))) < 0.02
    k = _match(res, an)
    sim = np.asarray(res.delta_per_cycle)[k]
    note = [n for n in an.notes if "firing run" in n]
    assert len(note) == 1 and "orders 2, 4, … 28 were left to the engine" in note[0] and "coast-down" in note[0]
    u = float(note[0].split("change δ by about ±")[1].split(";")[0])
    print("δ", an.delta.mean(), "sim", sim.mean(), "stated ±", u)
    assert np.all(np.abs(an.delta - sim) < u)
    assert an.to_json_dict()["notes"] == list(an.notes)
    # without cylinders the orders 2 and 4 are taken for the wheel's (δ ≈ 0): the note warns
    one = _analyse(res, "estimate")
    assert one.tooth_errors.engine_orders == ()
    assert np.all(one.delta < 0.2 * sim)
    assert any("cylinders=N" in n for n in one.notes)
    assert "cylinders=N" in one.summary()


def test_round_trip_with_200_ns_jitter(engine_run, calibration):
    """200 ns timer jitter (a 5 MHz timer): with the signal-to-noise weighting δ is within
    4 % (it was within 10 % unweighted, which this checks can fail), orders 2 and 4 within
    1 % and 3 %."""
    res = engine_run
    _, path = calibration
    an = _analyse(res, path, jitter_s=200e-9)
    k = _match(res, an)
    sim = np.asarray(res.delta_per_cycle)[k]
    off = an.delta / sim - 1
    print("δ off at 200 ns", off)
    assert np.all(np.abs(off) < 0.04)
    raw = _analyse(res, path, jitter_s=200e-9, denoise=False)
    assert np.max(np.abs(raw.delta / sim - 1)) > 0.06
    ref = _sim_orders(res, k, (2.0, 4.0))
    np.testing.assert_allclose(an.amplitude_of(2.0), ref[:, 0, 0], rtol=0.01)
    np.testing.assert_allclose(an.amplitude_of(4.0), ref[:, 1, 0], rtol=0.03)


@pytest.fixture(scope="module")
def unequal_run():
    e = rotor.load_engine("4chn15")
    steady = rotor.steady_state(e)
    load = float(steady.load_torque_Nm)
    rpm0 = float(steady.omega[0]) * RPM_PER_RAD_S
    comb = rotor.combustion_pattern(8, 4, imep_scale=[1, 1.1, 0.9, 1])
    return rotor.simulate(
        e,
        rpm=rpm0,
        cycles=8,
        load=rotor.ConstantLoad(load),
        method="grid",
        step_deg=0.25,
        steps_per_cycle=2880,
        progress=False,
        combustion=comb,
    )


def test_unequal_cylinders_half_orders(unequal_run, calibration):
    """Cylinders at 1, 1.1, 0.9, 1 × the IMEP: orders 0.5 and 1.5 appear; every order of
    0.5, 1, 1.5, 2 above 1 % of order 2 is within 1 % in amplitude and 0.01 rad in phase,
    δ within 1 %."""
    res = unequal_run
    _, path = calibration
    an = _analyse(res, path)
    k = _match(res, an)
    np.testing.assert_allclose(an.delta, np.asarray(res.delta_per_cycle)[k], rtol=0.01)
    orders = (0.5, 1.0, 1.5, 2.0)
    ref = _sim_orders(res, k, orders)
    significant = [q for j, q in enumerate(orders) if ref[:, j, 0].min() > 0.01 * ref[:, 3, 0].max()]
    assert {0.5, 1.5, 2.0} <= set(significant)  # order 1 cancels in this pattern
    for j, q in enumerate(orders):
        if q in significant:
            np.testing.assert_allclose(an.amplitude_of(q), ref[:, j, 0], rtol=0.01)
            jj = int(np.flatnonzero(np.isclose(an.order, q))[0])
            assert np.all(np.abs(np.angle(np.exp(1j * (an.phase_rad[:, jj] - ref[:, j, 1])))) < 0.01)


def test_firing_revolution_from_the_speed_is_flagged(unequal_run, calibration):
    """TDC cannot be inferred from tooth times alone (no pressure or cam channel: the
    speed of an evenly firing four has no feature that marks cylinder 1), so the round
    trips give tdc_deg. The firing revolution can be asked of the speed: for a four with
    ±10 % unequal cylinders the signature is weak, and the result says it is uncertain."""
    _, path = calibration
    an = _analyse(unequal_run, path, firing="auto")
    assert an.firing_method.startswith("speed")
    assert any("uncertain" in n for n in an.notes)
