"""Trigger patterns as edge lists: edges simulated from every catalogue pattern read back
as that pattern (each edge's place, the speed), defects absorbed or refused, and the real
logic-analyser captures read as their documented patterns (skipped without ../shared/data)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import SHARED_DATA

from rotor.errors import LogError
from rotor.logs.catalogue import CATALOGUE, find_pattern
from rotor.logs.patterns import TriggerPattern, channel_edges, decode_edges, pattern_from_wheel
from rotor.logs.reader import read_log

TRIGGERS = SHARED_DATA / "ecu-triggers"
OFFSET_DEG = 5.0  # the simulated edges' angles from the pattern's angle 0 of their first turn


def simulated_edges(pattern: TriggerPattern, polarity: str, *, rpm=600.0, turns=12, swing=0.03, jitter_deg=0.0, seed=0):
    """Edge times [s] of ``pattern`` turning at ``rpm`` with a speed that swings by ``swing``
    twice a revolution (a four-cylinder's compressions) and a slow ramp, each edge's angle
    off by a normal error of ``jitter_deg``; the true angles [deg]."""
    rng = np.random.default_rng(seed)
    a = pattern.angles_deg(polarity)
    P = pattern.period_deg
    ang = (a[None, :] + P * np.arange(turns)[:, None]).ravel() + OFFSET_DEG
    ang_true = ang + rng.normal(0.0, jitter_deg, ang.size) if jitter_deg else ang
    w0 = rpm * 6.0  # deg/s
    t = np.linspace(0.0, 1.3 * ang.max() / w0, 400_000)
    theta = w0 * t * (1 + 0.1 * t / t[-1]) + swing * w0 / (4 * math.pi * w0 / 360) * np.sin(4 * math.pi * w0 * t / 360)
    assert np.all(np.diff(theta) > 0)
    return np.interp(ang_true, theta, t), ang


@pytest.mark.parametrize("name", list(CATALOGUE))
def test_every_catalogue_pattern_reads_its_own_simulated_edges(name):
    p = CATALOGUE[name]
    t, ang = simulated_edges(p, p.read)
    fit = decode_edges(t, p)
    assert fit.kept > 0.9
    # the angles between kept edges are the pattern's (modulo its repetition at the start)
    k = np.searchsorted(t, fit.t)
    d_true = np.diff(ang[k])
    np.testing.assert_allclose(np.diff(np.rad2deg(fit.angle_rad)), d_true, atol=1e-6)
    unit = p.period_deg / fit.repeats
    off = (np.rad2deg(fit.angle_rad) - (ang[k] - OFFSET_DEG) + 0.5 * unit) % unit - 0.5 * unit
    np.testing.assert_allclose(off, 0.0, atol=1e-6)  # each edge's place in the pattern
    _, rpm = fit.rpm_per_turn()
    assert rpm.size > 0 and np.all((rpm > 500) & (rpm < 800))


@pytest.mark.parametrize("name", [n for n, p in CATALOGUE.items() if p.repeats() < p.edges_per_turn])
def test_a_missed_edge_is_bridged_and_a_stop_dropped(name):
    p = CATALOGUE[name]
    t, ang = simulated_edges(p, p.read, turns=16)
    K = p.edges_per_turn
    t2 = np.delete(t, 6 * K + 1)  # one edge missed in the middle
    fit = decode_edges(t2, p)
    k = np.searchsorted(t, fit.t)
    np.testing.assert_allclose(np.diff(np.rad2deg(fit.angle_rad)), np.diff(ang[k]), atol=1e-6)
    assert fit.turns > 8


def test_wrong_pattern_explains_less_than_the_right_one():
    right = CATALOGUE["mazda-nb-crank"]
    t, _ = simulated_edges(right, "rising")
    good = decode_edges(t, right)
    for other in ("nissan-hr-cam-in", "mitsubishi-4g63-cam", "36-2-1"):
        try:
            bad = decode_edges(t, CATALOGUE[other], CATALOGUE[other].read)
        except LogError:
            continue
        assert bad.evidence * bad.kept < good.evidence * good.kept


def test_evenly_spaced_edges_carry_no_evidence_of_a_pattern():
    p = CATALOGUE["12-tooth"]
    t, _ = simulated_edges(p, "rising")
    assert abs(decode_edges(t, p).evidence) < 1e-3
    assert decode_edges(t, p).repeats == 12


def test_too_few_edges_and_edges_out_of_order_are_refused():
    p = CATALOGUE["mazda-nb-crank"]
    with pytest.raises(LogError, match="edges; the mazda-nb-crank pattern"):
        decode_edges([0.0, 0.1, 0.2], p)
    with pytest.raises(LogError, match="not increasing"):
        decode_edges(np.r_[np.arange(10.0), 5.0], p)


def test_shorthand_wheels_and_catalogue_names():
    assert find_pattern("36-2-1").name == "36-2-1"  # the catalogue's, with its layout
    assert find_pattern("TT_MIATA_VVT").name == "mazda-nb-crank"
    w = find_pattern("60-2")
    assert w.edges_per_turn == 58 and w.period_deg == 360
    assert pattern_from_wheel(36, (2, 1), (17, 16)).edges_per_turn == 33
    with pytest.raises(LogError, match="closest: mazda-nb-crank"):
        find_pattern("mazda-nb-crnk")


def test_a_wheel_with_two_equal_halves_is_read_modulo_its_half():
    p = CATALOGUE["36-2-2"]
    assert p.repeats() == 2
    t, ang = simulated_edges(p, "rising")
    fit = decode_edges(t, p)
    assert fit.repeats == 2
    _, rpm = fit.rpm_per_turn()
    assert np.all((rpm > 500) & (rpm < 800))


# the real captures: the channel, the documented pattern, and the speed range the data's README gives
CAPTURES = [
    ("arctic-cat.csv", "time,encoder_d", "arctic-cat", "falling", 528, 2165),
    ("hr12-vvt-in-16s.csv", "time,encoder_d", "nissan-hr-cam-in", "falling", 196, 202),
    ("cranking_na_3.csv", "time,-,encoder_d,-,-", "mazda-na-cas-1", "both", 225, 1100),
    ("nb2_rev-d-1.csv", "time,-,encoder_d,-,-", "mazda-nb-cam", "rising", 240, 250),
    ("4g63-cranking.csv", "time,-,encoder_d", "mitsubishi-4g63-cam", "both", 133, 218),
    ("neonsrt4.csv", "time,-,encoder_d", "36-2-2", "falling", 147, 225),
]


@pytest.mark.skipif(not TRIGGERS.is_dir(), reason=f"shared data not found at {TRIGGERS}")
@pytest.mark.parametrize("name,columns,pattern,polarity,lo,hi", CAPTURES, ids=[c[0] for c in CAPTURES])
def test_real_captures_read_as_their_documented_pattern(name, columns, pattern, polarity, lo, hi):
    log = read_log(TRIGGERS / name, columns)
    p = find_pattern(pattern)
    edges, kinds = channel_edges(log["time"], log["encoder_d"], polarity)
    fit = decode_edges(edges, p, p.read if polarity != "both" else "both", kinds=kinds if polarity == "both" else None)
    _, rpm = fit.rpm_per_turn()
    assert fit.turns >= 3
    # the median speed of the turns inside the documented range, ±2 %; no turn far outside it
    assert 0.98 * lo <= np.median(rpm) <= 1.02 * hi
    assert np.all((rpm > 0.5 * lo) & (rpm < 1.5 * hi))


def test_a_header_of_a_time_name_and_channel_numbers_is_a_header(tmp_path):
    f = tmp_path / "capture.csv"
    f.write_text("Time[s], 0, 1\n0.0, 1, 0\n0.001, 0, 0\n0.002, 1, 1\n")
    log = read_log(f, "time,encoder_d,cam_d")
    np.testing.assert_array_equal(log["encoder_d"], [1.0, 0.0, 1.0])
    bad = tmp_path / "mixed.csv"
    bad.write_text("0,001;x\n1;2\n")
    with pytest.raises(LogError, match="mixes numbers and text"):
        read_log(bad, "time,encoder_v")
