"""Simulated analog trigger-wheel signals (rotor.logs.synthetic): the true edges are where
the signal says they are (the Hall output crosses its mid level there, the VR pulse its
zero), a VR pulse grows with the speed, a gap gives no pulse, the distorted tooth after
the gap is distorted as asked, inverted is the negation, a seed gives the same signal,
the speed profiles do what their names say, a written log reads back, and bad arguments
are refused naming the argument."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rotor
from rotor.errors import LogError
from rotor.logs.synthetic import (
    STANDARD_LAYOUTS,
    SpeedProfile,
    speed_profile,
    wheel_signal,
    write_log,
)

WHEELS = ("60-2", "36-1", "36-2-1", "36-2-1-1", "36-2-2-2", "24-1", "12-1", "60-1", "36-2")


@pytest.fixture(scope="module")
def steady():
    return speed_profile("steady", rpm=1500.0, revolutions=8, ripple=0.05, order=2.0)


def crossings(sig):
    """(index of the first sample at or after each true edge, the crossing time found by
    linear interpolation between that sample and the one before [s])."""
    i = np.searchsorted(sig.t_s, sig.edge_times_s)
    a, b = sig.v[i - 1] - sig.level_v, sig.v[i] - sig.level_v
    return i, sig.t_s[i - 1] + a / (a - b) / sig.sample_rate_hz


@pytest.mark.parametrize("gap_tooth", [None, "weak", "early", "late"])
@pytest.mark.parametrize("wheel", ["60-2", "36-2-1", "36-2-2-2"])
def test_hall_rising_edge_crosses_the_mid_level_at_the_true_time(steady, wheel, gap_tooth):
    sig = wheel_signal(steady, wheel, sensor="hall", noise_v=0.0, gap_tooth=gap_tooth, tooth_error_deg=0.05)
    assert sig.edge == "rising" and sig.level_v == pytest.approx(2.5)
    i, _ = crossings(sig)
    assert np.all(sig.v[i - 1] < sig.level_v) and np.all(sig.v[i] >= sig.level_v)  # within one sample
    # and nowhere else: one rising mid-level crossing per true edge
    up = np.flatnonzero((sig.v[:-1] < sig.level_v) & (sig.v[1:] >= sig.level_v)) + 1
    half = 0.5 * np.min(np.diff(sig.edge_times_s))
    inside = (sig.t_s[up] > sig.edge_times_s[0] - half) & (sig.t_s[up] < sig.edge_times_s[-1] + half)
    np.testing.assert_array_equal(up[inside], i)


@pytest.mark.parametrize("gap_tooth", [None, "weak", "early", "late"])
@pytest.mark.parametrize("wheel", ["60-2", "36-2-1-1", "12-1"])
def test_vr_falling_zero_crossing_at_the_true_time(steady, wheel, gap_tooth):
    sig = wheel_signal(steady, wheel, sensor="vr", noise_v=0.0, gap_tooth=gap_tooth, tooth_error_deg=0.05)
    assert sig.edge == "falling" and sig.level_v == 0.0
    i, tz = crossings(sig)
    assert np.all(sig.v[i - 1] > 0) and np.all(sig.v[i] <= 0)
    assert np.max(np.abs(tz - sig.edge_times_s)) * sig.sample_rate_hz < 0.05  # a twentieth of a sample


@pytest.mark.parametrize("wheel", WHEELS)
def test_true_edges_are_numbered_as_rotor_numbers_them(steady, wheel):
    sig = wheel_signal(steady, wheel, noise_v=0.0)
    w = sig.wheel
    assert w.spec == wheel and w.layout == STANDARD_LAYOUTS.get(wheel, (w.edges_per_rev,))
    E = w.edges_per_rev
    assert np.all(np.diff(sig.edge_times_s) > 0)
    assert np.all((np.diff(sig.tooth_index) % E) == 1)  # every tooth, in order
    assert np.array_equal(np.diff(sig.revolution) == 1, np.diff(sig.tooth_index) < 0)
    assert sig.revolution[sig.tooth_index == 0][0] == 0
    assert np.count_nonzero(sig.after_gap[sig.revolution == 0]) == len(w.gaps)
    assert sig.gap_edge_times_s.size == np.count_nonzero(sig.after_gap)
    # the angles: 2π·revolution + the tooth's angle
    np.testing.assert_allclose(
        sig.edge_angles_rad, 2 * np.pi * sig.revolution + w.tooth_angles_rad[sig.tooth_index], atol=1e-12
    )
    # the same numbering as rotor's own tooth location
    track = rotor.locate_teeth(sig.edge_times_s, wheel)
    assert track.wheel.layout == w.layout
    np.testing.assert_array_equal(track.tooth, sig.tooth_index)
    np.testing.assert_array_equal(track.rev, sig.revolution)


def test_vr_amplitude_grows_with_speed():
    p = speed_profile("coast_down", rpm=3000.0, revolutions=12, ripple=0.0, end_rpm=300.0)
    sig = wheel_signal(p, "60-2", sensor="vr", noise_v=0.0, sample_rate_hz=400e3)
    # each tooth's positive peak: the largest sample in the quarter pitch before its edge
    i = np.searchsorted(sig.t_s, sig.edge_times_s)
    period = np.gradient(sig.edge_times_s)
    win = np.maximum((0.3 * period * sig.sample_rate_hz).astype(int), 2)
    peaks = np.array([sig.v[a - k : a].max() for a, k in zip(i, win)])
    omega = sig.omega_at_edges_rad_s
    assert omega.max() > 5 * omega.min()
    ratio = peaks / omega
    assert ratio.max() / ratio.min() < 1.05  # the peak is ∝ the speed
    assert np.median(ratio) == pytest.approx(0.02, rel=0.05)  # the sensitivity [V/(rad/s)]
    slow = wheel_signal(speed_profile("steady", rpm=1000.0, revolutions=3, ripple=0.0), "60-2", noise_v=0.0)
    fast = wheel_signal(speed_profile("steady", rpm=3000.0, revolutions=3, ripple=0.0), "60-2", noise_v=0.0)
    assert np.ptp(fast.v) / np.ptp(slow.v) == pytest.approx(3.0, rel=0.02)
    assert slow.v.max() == pytest.approx(0.02 * 1000 * math.pi / 30, rel=0.02)


@pytest.mark.parametrize("sensor", ["vr", "hall"])
def test_the_gap_gives_no_pulse(steady, sensor):
    sig = wheel_signal(steady, "60-2", sensor=sensor, noise_v=0.0)
    t0 = sig.reference_times_s
    dt = np.diff(sig.edge_times_s)
    k = np.flatnonzero(sig.tooth_index == 0)[1:]
    assert np.allclose(dt[k - 1] / dt[k], 3.0, rtol=0.02)  # the gap: three pitches
    for a, b in zip(sig.edge_times_s[k - 1], t0[1:]):  # from the last tooth before the gap to tooth 0
        pitch_t = (b - a) / 3
        quiet = (sig.t_s > a + pitch_t) & (sig.t_s < b - pitch_t)  # the two missing teeth's places
        assert np.count_nonzero(quiet) > 10
        assert np.max(np.abs(sig.v[quiet])) < 1e-12  # VR: no pulse; Hall: low all through


def test_the_tooth_after_the_gap_weak_early_late(steady):
    base = wheel_signal(steady, "36-2-1", noise_v=0.0)
    weak = wheel_signal(steady, "36-2-1", noise_v=0.0, gap_tooth="weak", gap_tooth_amplitude=0.3)

    def peak(sig, j):
        e = sig.edge_times_s[j]
        near = np.abs(sig.t_s - e) < 0.4 * np.median(np.diff(sig.edge_times_s))
        return sig.v[near].max()

    for j in np.flatnonzero(base.after_gap)[:4]:
        assert peak(weak, j) / peak(base, j) == pytest.approx(0.3, rel=0.01)
        assert peak(weak, j + 1) / peak(base, j + 1) == pytest.approx(1.0, rel=1e-6)
    pitch = base.wheel.pitch_rad
    for kind, sign in (("early", -1), ("late", 1)):
        sig = wheel_signal(steady, "36-2-1", noise_v=0.0, gap_tooth=kind, gap_tooth_shift=0.2)
        shift = (sig.edge_angles_rad - base.edge_angles_rad) / pitch
        np.testing.assert_allclose(shift[sig.after_gap], sign * 0.2, atol=1e-12)
        np.testing.assert_allclose(shift[~sig.after_gap], 0.0, atol=1e-12)
    hall = wheel_signal(steady, "60-2", sensor="hall", noise_v=0.0, gap_tooth="weak", gap_tooth_amplitude=0.4)
    shift = (hall.edge_angles_rad - 2 * np.pi * hall.revolution) / hall.wheel.pitch_rad - hall.wheel.positions[
        hall.tooth_index
    ]
    np.testing.assert_allclose(shift[hall.after_gap], 0.5 * 0.6 * 0.5, atol=1e-12)  # narrower, so later


def test_tooth_errors_are_in_the_truth(steady):
    err = np.zeros(58)
    err[[3, 30]] = (0.1, -0.2)
    sig = wheel_signal(steady, "60-2", noise_v=0.0, tooth_error_deg=err)
    d = np.rad2deg(sig.edge_angles_rad - 2 * np.pi * sig.revolution - sig.wheel.tooth_angles_rad[sig.tooth_index])
    np.testing.assert_allclose(d, err[sig.tooth_index], atol=1e-9)
    _, tz = crossings(sig)
    assert np.max(np.abs(tz - sig.edge_times_s)) * sig.sample_rate_hz < 0.05
    drawn = wheel_signal(steady, "60-2", noise_v=0.0, tooth_error_deg=0.05, seed=3)
    again = wheel_signal(steady, "60-2", noise_v=0.2, tooth_error_deg=0.05, seed=3)
    np.testing.assert_array_equal(drawn.edge_times_s, again.edge_times_s)  # the teeth do not depend on the noise
    d = np.rad2deg(drawn.edge_angles_rad - 2 * np.pi * drawn.revolution) - np.rad2deg(
        drawn.wheel.tooth_angles_rad[drawn.tooth_index]
    )
    assert 0.02 < np.std(d[drawn.revolution == 0]) < 0.09


@pytest.mark.parametrize("sensor", ["vr", "hall"])
def test_inverted_is_the_negation(steady, sensor):
    a = wheel_signal(steady, "60-2", sensor=sensor, noise_v=0.05, seed=7)
    b = wheel_signal(steady, "60-2", sensor=sensor, noise_v=0.05, seed=7, inverted=True)
    np.testing.assert_array_equal(b.v, -a.v)
    np.testing.assert_array_equal(b.edge_times_s, a.edge_times_s)
    assert {a.edge, b.edge} == {"rising", "falling"} and b.level_v == -a.level_v
    assert a.edge == ("falling" if sensor == "vr" else "rising")


def test_a_seed_gives_the_same_signal(steady):
    a = wheel_signal(steady, "36-2-1", noise_v=0.02, tooth_error_deg=0.03, seed=11)
    b = wheel_signal(steady, "36-2-1", noise_v=0.02, tooth_error_deg=0.03, seed=11)
    c = wheel_signal(steady, "36-2-1", noise_v=0.02, tooth_error_deg=0.03, seed=12)
    np.testing.assert_array_equal(a.v, b.v)
    np.testing.assert_array_equal(a.edge_times_s, b.edge_times_s)
    assert not np.array_equal(a.v, c.v) and not np.array_equal(a.edge_times_s, c.edge_times_s)
    clean = wheel_signal(steady, "36-2-1", noise_v=0.0, tooth_error_deg=0.03, seed=11)
    assert np.std(a.v - clean.v) == pytest.approx(0.02, rel=0.05)  # white Gaussian noise of noise_v


def test_speed_profiles_do_what_they_say():
    st = speed_profile("steady", rpm=2000.0, duration_s=0.6, ripple=0.05, order=2.0)
    assert st.duration_s == pytest.approx(0.6, abs=1e-9) and st.phi_rad[0] == 0.0
    w = st.omega_rad_s
    assert (w.max() - w.min()) / w.mean() == pytest.approx(0.05, rel=0.02)
    assert w.mean() * 30 / math.pi == pytest.approx(2000.0, rel=0.01)
    # the ripple is locked to the crank: order 2 per revolution
    spec = np.abs(np.fft.rfft(np.interp(np.linspace(0, 2 * np.pi * 16, 4096, endpoint=False), st.phi_rad, w)))
    assert np.argmax(spec[1:]) + 1 == 32
    t = np.linspace(0.0, 0.6, 777)
    np.testing.assert_allclose(st.time_of(st.phi(t)), t, atol=1e-12)
    np.testing.assert_allclose(st.omega(t), np.gradient(st.phi(t), t, edge_order=2), rtol=2e-3)

    cut = speed_profile("ignition_cut", rpm=3000.0, revolutions=20, ripple=0.0, cut_revolution=8, drop_revolutions=3)
    rev = cut.phi_rad / (2 * np.pi)
    rpm = cut.omega_rad_s * 30 / math.pi
    assert np.allclose(rpm[rev < 8], 3000.0) and np.allclose(rpm[rev > 11], 2100.0)
    assert cut.revolutions == pytest.approx(20.0, abs=1e-6)

    cd = speed_profile("coast_down", rpm=3000.0, duration_s=2.0, end_rpm=100.0)
    rpm = cd.omega_rad_s * 30 / math.pi
    assert rpm[0] == pytest.approx(3000.0, rel=0.01)
    assert rpm[-20:].max() < 250.0 and cd.duration_s == pytest.approx(2.0, rel=0.02)
    trend = np.polyfit(cd.t_s, np.sqrt(cd.omega_rad_s.clip(0)), 1)[0]
    assert trend < 0  # decelerating all through

    cr = speed_profile("crank", rpm=200.0, revolutions=4)
    w = cr.omega_rad_s
    assert w.max() / w.min() > 2.0 and w.mean() * 30 / math.pi == pytest.approx(200.0, rel=0.1)


def test_profile_given_as_arrays_or_a_function():
    t = np.linspace(0.0, 0.3, 3001)
    phi = 2 * np.pi * 25 * t + 0.05 * np.sin(2 * np.pi * 50 * t)
    a = wheel_signal((t, phi), "36-1", noise_v=0.0)
    b = wheel_signal(
        lambda x: 2 * np.pi * 25 * x + 0.05 * np.sin(2 * np.pi * 50 * x), "36-1", noise_v=0.0, duration_s=0.3
    )
    assert a.edge_times_s.size == b.edge_times_s.size > 250
    np.testing.assert_allclose(a.edge_times_s, b.edge_times_s, atol=1e-9)
    assert isinstance(a.profile, SpeedProfile)


def test_written_log_reads_back(tmp_path, steady):
    sig = wheel_signal(steady, "60-2", sensor="vr", noise_v=0.01)
    path = tmp_path / "vr.tsv"
    write_log(path, sig)
    assert path.read_text().splitlines()[0] == "time\tencoder_v"
    for columns in (None, sig.columns):
        log = rotor.read_log(path, columns)
        np.testing.assert_allclose(log.columns["time"], sig.t_s, atol=1e-9)
        np.testing.assert_allclose(log.columns["encoder_v"], sig.v, atol=1e-6)


@pytest.mark.parametrize(
    "kwargs,name",
    [
        ({"wheel": "60-x"}, "wheel="),
        ({"wheel": "60"}, "wheel="),
        ({"wheel": "3-5"}, "wheel="),
        ({"sensor": "optical"}, "sensor="),
        ({"gap_tooth": "wobbly"}, "gap_tooth="),
        ({"gap_tooth": ("early", "late")}, "gap_tooth="),
        ({"sample_rate_hz": 0.0}, "sample_rate_hz="),
        ({"noise_v": -1.0}, "noise_v="),
        ({"seed": -1}, "seed="),
        ({"tooth_error_deg": 5.0}, "tooth_error_deg="),
        ({"tooth_error_deg": [0.1, 0.2]}, "tooth_error_deg"),
        ({"layout": (10, 10)}, "layout="),
        ({"pulse_width": 0.8}, "pulse_width="),
        ({"sensor": "hall", "duty": 1.2}, "duty="),
        ({"sensor": "hall", "high_v": -1.0}, "high_v="),
        ({"gap_tooth_shift": 0.6}, "gap_tooth_shift="),
    ],
)
def test_bad_signal_arguments_are_named(steady, kwargs, name):
    kw = dict(kwargs)
    wheel = kw.pop("wheel", "36-2-1")
    with pytest.raises(LogError, match=name) as e:
        wheel_signal(steady, wheel, **kw)
    assert isinstance(e.value, ValueError) and "\n" not in str(e.value)


@pytest.mark.parametrize(
    "kwargs,name",
    [
        ({"kind": "idle"}, "kind="),
        ({"rpm": -100.0}, "rpm="),
        ({"rpm": float("nan")}, "rpm="),
        ({"revolutions": None}, "duration_s="),
        ({"duration_s": 1.0}, "revolutions="),
        ({"ripple": 2.5}, "ripple="),
        ({"order": 0.0}, "order="),
        ({"kind": "ignition_cut", "drop": 1.5}, "drop="),
        ({"kind": "coast_down", "end_rpm": 5000.0}, "end_rpm="),
    ],
)
def test_bad_profile_arguments_are_named(kwargs, name):
    kw = {"kind": "steady", "rpm": 1000.0, "revolutions": 4} | kwargs
    with pytest.raises(LogError, match=name):
        speed_profile(kw.pop("kind"), **kw)
    with pytest.raises(LogError, match="duration_s="):
        wheel_signal(lambda t: t, "60-2")
