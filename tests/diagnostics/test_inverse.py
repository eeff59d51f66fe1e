"""Inverse dynamics: the indicated torque from ω(θ), regularised, and the harmonic method.

The reference is a 6-cycle 4chn15 run-up (1187.5 → ~1225 rpm against a propeller load,
method "closed", saved every 1°): its ``SpeedResult.torque`` is the engine's gas torque
(at the "variable" fidelity there is no explicit inertia torque) and ``load_torque`` the
friction plus load, so M_gas = d(½Iω²)/dθ + load_torque holds exactly on its samples.
"""

import numpy as np
import pytest
from conftest import two_mass_engine

import rotor
from rotor.diagnostics import inverse

LOAD = rotor.PropellerLoad(1132.0, 1250.0)


@pytest.fixture(scope="module")
def run(diesel):
    r = rotor.simulate(diesel, rpm=1187.5, cycles=6, load=LOAD)
    C, P = r.uniform_cycles, r.points_per_cycle
    truth = np.asarray(r.torque)[: C * P].reshape(C, P)
    omega = np.asarray(r.omega)[: C * P].reshape(C, P)
    return r, truth, omega


def rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


def test_round_trip_recovers_the_engine_torque(diesel, run):
    r, truth, omega = run
    res = inverse.indicated_torque(diesel, r, load=LOAD)
    assert res.torque.shape == truth.shape == (6, 720)
    err = np.abs(res.torque - truth)
    # measured 0.278 N·m (6e-5 of the 4733 N·m peak), the same in every cycle: the spectral
    # derivative's error at 1° (0.075 N·m at 0.5°); the record's end jumps cost nothing more
    assert np.abs(truth).max() == pytest.approx(4733, rel=1e-3)
    assert err.max() < 0.85, err.max()  # ~3× the measured error
    assert err[0].max() < 0.85 and err[-1].max() < 0.85
    # the loss terms are the simulator's own
    np.testing.assert_allclose(
        res.friction_torque + res.load_torque, np.asarray(r.load_torque)[: 6 * 720].reshape(6, 720), rtol=1e-9
    )
    # steady combustion: every cycle's mean gas torque is the same 1131.95 N·m
    np.testing.assert_allclose(res.mean_torque_Nm, np.mean(truth, axis=1), atol=0.05)
    # the bare array (no end sample) is as good
    arr = inverse.indicated_torque(diesel, omega, load=LOAD)
    assert np.abs(arr.torque - truth).max() < 0.85
    # treating the run-up as one period puts the end-to-start jump into the derivative:
    # errors of ~2e5 N·m in the first and last cycles (the end-jump removal is what fixes it)
    naive = inverse.indicated_torque(diesel, omega, load=LOAD, periodic=True)
    assert np.abs(naive.torque - truth)[[0, -1]].max() > 1e4


def test_unknown_load_leaves_the_fluctuation(diesel, run):
    """load=None gives M_gas − M_load: off by exactly the load, whose fluctuation within a
    cycle is what the speed-dependent load adds (here up to 13 N·m: the propeller torque
    follows ω's fluctuation and, in the run-up, its rise across the cycle)."""
    r, truth, _ = run
    known = inverse.indicated_torque(diesel, r, load=LOAD)
    res = inverse.indicated_torque(diesel, r)
    assert np.all(res.load_torque == 0)
    np.testing.assert_allclose(res.torque, known.torque - known.load_torque, rtol=0, atol=1e-9)
    load = known.load_torque - known.load_torque.mean(axis=1, keepdims=True)
    fluct = (res.torque - res.torque.mean(axis=1, keepdims=True)) - (truth - truth.mean(axis=1, keepdims=True))
    assert 10 < np.abs(load).max() < 16
    np.testing.assert_allclose(fluct, -load, rtol=0, atol=0.85)  # the round trip's tolerance
    # the mean is the acceleration torque's (+ friction, none here): the mean gas torque,
    # 1132 N·m, is not in the speed
    np.testing.assert_allclose(res.mean_torque_Nm, np.mean(truth - known.load_torque, axis=1), atol=0.05)
    assert np.all(np.abs(res.mean_torque_Nm) < 130)


def test_regularisation_with_noise(diesel, run):
    _, truth, omega = run
    rng = np.random.default_rng(0)
    noisy = omega * (1 + 1e-4 * rng.standard_normal(omega.shape))
    K = 12
    none = inverse.indicated_torque(diesel, noisy, load=LOAD)
    cut = inverse.indicated_torque(diesel, noisy, load=LOAD, regularisation="orders", max_order=K)
    tik = inverse.indicated_torque(diesel, noisy, load=LOAD, regularisation="tikhonov", max_order=K)
    e_none, e_cut, e_tik = rms(none.torque - truth), rms(cut.torque - truth), rms(tik.torque - truth)
    # measured rms errors 1790, 51, 63 N·m: the derivative multiplies the noise at order ν by ν
    assert e_none > 1000
    assert e_cut < 155 and e_tik < 190  # ~3× the measured
    assert e_cut < e_none / 10 and e_tik < e_none / 10
    assert cut.regularisation == "orders" and tik.tikhonov_weight == pytest.approx(K**-4)
    # the kept orders against the truth's same orders: the noise floor of one cycle's
    # order-ν torque is Ī·ω̄·ν·σ_X, σ_X = 2σ_ω/√P ≈ 9.6e-4 rad/s, ≈ 15 N·m at ν = 12;
    # measured max over 6 cycles and orders ≤ 12: 29 N·m, orders ≤ 4: 7.2 N·m, mean 1.0 N·m
    got, want = cut.orders(K), inverse.cycle_orders(truth, 4, K)
    d = np.abs(got.complex_Nm - want.complex_Nm)
    assert d.max() < 90 and d[:, :8].max() < 22, (d.max(), d[:, :8].max())
    assert np.abs(got.mean_Nm - want.mean_Nm).max() < 3.0
    # without noise the cut costs little below the cut-off (0.5 N·m on orders ≤ 10 measured;
    # 2.2 at order 12, where the products with I(θ)'s orders miss the cut orders' share)
    clean = inverse.indicated_torque(diesel, omega, load=LOAD, regularisation="orders", max_order=K)
    d = np.abs(clean.orders(K).complex_Nm - want.complex_Nm)
    assert d[:, :20].max() < 1.5 and d.max() < 7.0


def test_harmonic_method_against_the_exact_inverse(diesel, run):
    r, _, _ = run
    exact = inverse.indicated_torque(diesel, r, load=LOAD).orders(6.0)
    h = inverse.harmonic_torque(diesel, r, load=LOAD, max_order=6.0)
    assert np.allclose(h.torque.order, exact.order)
    d = np.abs(h.torque.complex_Nm - exact.complex_Nm)
    # the linearisation drops ½·I·w²: |w|/(2ω̄) ≈ 0.0017 of the dynamic torque per order
    # (max|w|/ω̄ = 0.0034 here), ≈ 4.4 N·m on order 2's 2595 N·m; the run-up's curvature of
    # the mean speed within a cycle leaks into all orders (largest in the first cycle).
    # Measured: max 9.2 N·m over all orders ≤ 6 and cycles; orders 2, 4, 6: 3.8, 1.3, 1.6 N·m
    assert np.all(h.relative_speed_amplitude < 0.0036) and np.all(h.relative_speed_amplitude > 0.003)
    assert d.max() < 28, d.max()
    firing = [np.flatnonzero(np.isclose(h.torque.order, o))[0] for o in (2.0, 4.0, 6.0)]
    assert np.all(d[:, firing].max(axis=0) < [12.0, 4.0, 5.0]), d[:, firing].max(axis=0)
    # without I(θ)'s orders coupling the speed orders, orders 4 and 6 were 11 and 17 N·m off:
    # the coupling is what the tolerances above test
    np.testing.assert_allclose(h.torque.mean_Nm, exact.mean_Nm, atol=6.0)  # measured ≤ 2.1


def test_closed_forms_constant_inertia(diesel):
    """Constant inertia J: the exact inverse of a pure sinusoidal energy is the sinusoidal
    torque; the harmonic response M_ν = iν·J·ω̄·W_ν is exact at the speed's own order and
    misses ½·ν·J·W² at order 2ν."""
    P, nu, J = 720, 2.0, float(rotor.crank_train(diesel, "constant").mean_inertia)
    theta = np.arange(P) * (4 * np.pi / P)
    A, wbar = 900.0, 130.0
    E = 0.5 * J * wbar**2 + A / nu * np.sin(nu * theta)
    res = inverse.indicated_torque(diesel, np.sqrt(2 * E / J), fidelity="constant", periodic=True, friction=False)
    assert res.net_torque.shape == (1, P)  # one cycle in, one row out
    np.testing.assert_allclose(res.net_torque[0], A * np.cos(nu * theta), rtol=0, atol=1e-9 * A)

    W = 0.8
    omega = wbar + W * np.cos(nu * theta)
    net = inverse.indicated_torque(diesel, omega, fidelity="constant", periodic=True, friction=False).net_torque[0]
    X = np.fft.rfft(net) * 2 / P  # bins n = ν·revs
    N = 16
    ci = np.zeros(2 * N + 1, complex)
    ci[N] = J
    offset, matrix = inverse.harmonic_response(ci, wbar, 2.0, 8)
    w = np.zeros(2 * N + 1, complex)
    w[N + 4], w[N - 4] = W / 2, W / 2  # order 2 = bin 4
    m = 2 * (offset + matrix @ w)
    assert m[3] == pytest.approx(1j * nu * J * wbar * W, rel=1e-12)
    assert X[4] == pytest.approx(m[3], rel=1e-10)
    assert abs(m[7]) == 0.0  # the linear map has nothing at 2ν ...
    assert abs(X[8]) == pytest.approx(0.5 * nu * J * W**2, rel=1e-9)  # ... the exact torque has ½·ν·J·W² there


def test_clear_errors(diesel, run):
    r, _, omega = run
    E = rotor.EngineError
    with pytest.raises(E, match="shape"):
        inverse.indicated_torque(diesel, omega[None])
    with pytest.raises(E, match="points per cycle"):
        inverse.indicated_torque(diesel, omega[:, :8])
    bad = omega.copy()
    bad[2, 10] = np.nan
    with pytest.raises(E, match="not finite.*cycle 2, point 10"):
        inverse.indicated_torque(diesel, bad)
    with pytest.raises(E, match="positive"):
        inverse.indicated_torque(diesel, -omega)
    with pytest.raises(E, match="360° does not fit the 4-stroke engine"):
        inverse.indicated_torque(diesel, omega, cycle_rad=2 * np.pi)
    with pytest.raises(E, match="a cycle of 720° does not fit the 2-stroke engine"):
        inverse.indicated_torque(two_mass_engine(strokes=2), r)
    with pytest.raises(E, match="regularisation"):
        inverse.indicated_torque(diesel, omega, regularisation="wiener")
    with pytest.raises(E, match="needs max_order"):
        inverse.indicated_torque(diesel, omega, regularisation="orders")
    with pytest.raises(E, match="Nyquist"):
        inverse.indicated_torque(diesel, omega, regularisation="orders", max_order=500)
    with pytest.raises(E, match="load"):
        inverse.indicated_torque(diesel, omega, load="heavy")
    with pytest.raises(E, match="max_order"):
        inverse.harmonic_torque(diesel, omega, max_order=0.1)
    with pytest.raises(E) as info:
        inverse.indicated_torque(diesel, bad)
    assert "\n" not in str(info.value)
