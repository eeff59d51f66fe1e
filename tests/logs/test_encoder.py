"""Edges of sampled wheel signals: noisy pulses, a narrow and low pulse next to the gap,
inverted, offset and other gains; the edges must be exactly the teeth, placed to a
fraction of a sample."""

import numpy as np
import pytest

import rotor
from rotor import LogError
from rotor.logs.wheel import TWO_PI

FS = 100e3  # samples per second


def wheel_signal(t, phi, teeth=60, missing=2, duty=0.5, ramp_deg=0.5, narrow=None):
    """Unit-height pulse train of a wheel at angles phi (rad; first edge after the gap at 0).

    ``narrow = (duty, height)`` of the tooth after the gap. **Returns:** (signal, rising
    edge angles of the 40 % crossings, per present tooth).
    """
    pitch = TWO_PI / teeth
    pos = phi / pitch
    j = np.mod(np.floor(pos), teeth).astype(int)
    frac = pos - np.floor(pos)
    rf = np.deg2rad(ramp_deg) / pitch
    d = np.full(phi.size, duty)
    h = np.ones(phi.size)
    if narrow is not None:
        d[j == 0], h[j == 0] = narrow
    level = h * np.minimum(np.clip(frac / rf, 0, 1), np.clip((d - frac) / rf, 0, 1)) * (j < teeth - missing)
    return level


def edges_true(t_of_phi, phi_end, teeth=60, missing=2, ramp_deg=0.5, narrow=None, phi_start=-0.3):
    pitch = TWO_PI / teeth
    rf = np.deg2rad(ramp_deg)
    k = np.arange(int(np.floor(phi_start / pitch)), int(phi_end / pitch) + 1)
    k = k[np.mod(k, teeth) < teeth - missing]
    h = np.where((np.mod(k, teeth) == 0) & (narrow is not None), narrow[1] if narrow else 1.0, 1.0)
    ang = k * pitch + rf * 0.32 / h
    return t_of_phi(ang[(ang > phi_start + 0.01) & (ang < phi_end - 0.01)])


def interior(x, t):
    return x[(x > t[0] + 1e-4) & (x < t[-1] - 1e-4)]


def run(rpm0=3000.0, rpm1=3000.0, seconds=0.2, **kw):
    t = np.arange(0, seconds, 1 / FS)
    w0, w1 = rpm0 / 30 * np.pi, rpm1 / 30 * np.pi
    a = (w1 - w0) / seconds
    phi = w0 * t + 0.5 * a * t**2 - 0.3
    t_of_phi = (lambda x: (x + 0.3) / w0) if a == 0 else (lambda x: (np.sqrt(w0**2 + 2 * a * (x + 0.3)) - w0) / a)
    return t, phi, t_of_phi


@pytest.mark.parametrize("gain,offset,sign", [(1.0, 0.0, 1), (4.6, -0.7, 1), (0.05, 2.5, 1), (3.0, 1.0, -1)])
def test_edges_exact_for_any_gain_offset_and_sign(gain, offset, sign):
    t, phi, t_of_phi = run()
    v = wheel_signal(t, phi)
    sig = offset + gain * sign * v
    e = rotor.find_edges(t, sig, edge="rising" if sign > 0 else "falling")
    truth, found = interior(edges_true(t_of_phi, phi[-1]), t), interior(e.times, t)
    assert found.size == truth.size
    assert np.max(np.abs(found - truth)) < 0.05 / FS  # a twentieth of a sample


def test_inverted_signal_rising_edges_still_count_every_tooth():
    t, phi, _ = run()
    v = -wheel_signal(t, phi)
    e = rotor.find_edges(t, v)  # rising edges of the inverted signal: the teeth's trailing edges
    track = rotor.locate_teeth(e.times, "60-2")
    assert e.times.size == track.t.size and track.revolutions >= 8


def test_noisy_pulses_no_double_or_missed_counts():
    rng = np.random.default_rng(0)
    t, phi, t_of_phi = run(3000, 2000)
    v = wheel_signal(t, phi) + rng.normal(0, 0.08, t.size)
    v[rng.integers(0, t.size, 200)] += rng.choice([-0.6, 0.6], 200)  # single-sample spikes
    e = rotor.find_edges(t, v)
    truth, found = interior(edges_true(t_of_phi, phi[-1]), t), interior(e.times, t)
    assert found.size == truth.size
    err = np.abs(found - truth)
    assert np.median(err) < 0.3 / FS  # noise σ = 8 % of the pulse on a 2.8-sample flank: σ_t ≈ 0.2 sample
    assert np.max(err) < 5 / FS  # a 60 % spike right on a flank moves that edge a few samples
    rotor.locate_teeth(e.times, "60-2")  # every revolution consistent


def test_narrow_low_pulse_next_to_the_gap():
    t, phi, t_of_phi = run()
    narrow = (0.25, 0.5)  # a quarter of the pitch wide and half as high
    v = wheel_signal(t, phi, narrow=narrow)
    e = rotor.find_edges(t, 0.2 + 5 * v)
    truth, found = interior(edges_true(t_of_phi, phi[-1], narrow=narrow), t), interior(e.times, t)
    assert found.size == truth.size
    assert np.max(np.abs(found - truth)) < 0.05 / FS
    track = rotor.locate_teeth(e.times, "60-2")
    assert track.revolutions >= 8


@pytest.mark.parametrize("teeth,missing", [(36, 1), (36, 2)])
def test_other_wheels_speed_changing_30_percent(teeth, missing):
    t, phi, t_of_phi = run(2000, 2600, seconds=0.3)
    v = wheel_signal(t, phi, teeth=teeth, missing=missing)
    e = rotor.find_edges(t, v)
    truth, found = interior(edges_true(t_of_phi, phi[-1], teeth=teeth, missing=missing), t), interior(e.times, t)
    assert found.size == truth.size
    assert np.max(np.abs(found - truth)) < 0.05 / FS
    track = rotor.locate_teeth(e.times, f"{teeth}-{missing}")
    assert track.t.size == e.times.size


def test_flat_signal_is_an_error():
    t = np.arange(1000) / FS
    with pytest.raises(LogError, match="encoder_v"):
        rotor.find_edges(t, np.full(t.size, 1.5) + 1e-4 * np.sin(t))


def test_real_recordings_edges(shared_data):
    for name, n in (("No_load", 1531), ("half_load", 1491), ("full_load", 1450)):
        log = rotor.read_log(shared_data / "tue-4gb10" / f"{name}.txt", "time,pressure_v,encoder_v")
        e = rotor.find_edges(log["time"], log["encoder_v"])
        assert e.times.size == n
        assert e.glitches == 0


@pytest.fixture(scope="module")
def shared_data():
    from conftest import SHARED_DATA

    if not (SHARED_DATA / "tue-4gb10").is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA}")
    return SHARED_DATA
