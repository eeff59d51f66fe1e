"""A matrix of simulated trigger recordings with the defects real ones carry, each read with
nothing but its signal: every catalogue pattern's own signal (either polarity, inverted,
timing jitter, the edges next to its widest gap displaced by up to 0.3 of a pitch, a glitch,
a speed that swings and ramps) is read as that pattern or refused, never as another wheel;
named, it is read as itself."""

from __future__ import annotations

import itertools
import math
import re

import numpy as np
import pytest

import rotor
from rotor.errors import LogError
from rotor.logs.catalogue import CATALOGUE, find_pattern
from rotor.logs.recording import PatternReading, read_wheel


def digital_log(
    pattern, *, rpm=900.0, turns=14, swing=0.03, jitter_deg=0.0, displace=0.0, glitch=False, invert=False, seed=0
):
    """A logic-analyser export (time, 0/1 level at each transition) of ``pattern``'s edges."""
    rng = np.random.default_rng(seed)
    P = pattern.period_deg
    r = np.asarray(pattern.rising_deg)
    f = np.asarray(pattern.falling_deg)
    if f.size == 0:
        f = (r + min(np.diff(np.r_[r, r[0] + P]).min() * 0.3, 4.0)) % P
    if r.size == 0:
        r = (f - min(np.diff(np.r_[f, f[0] + P]).min() * 0.3, 4.0)) % P
    if displace and re.fullmatch(r"\d+(-\d+)+", pattern.name):
        # a toothed wheel's edges on either side of its gap moved into it by ``displace`` of a pitch
        a = pattern.angles_deg()
        gaps = np.diff(np.r_[a, a[0] + P])
        k = int(np.argmax(gaps))
        pitch = float(np.median(gaps))
        shift = {float(a[k]): displace * pitch, float(a[(k + 1) % a.size]): -displace * pitch}
        r = np.array([x + shift.get(float(x), 0.0) if pattern.read in ("rising", "both") else x for x in r]) % P
        f = np.array([x + shift.get(float(x), 0.0) if pattern.read in ("falling", "both") else x for x in f]) % P
    ang = np.concatenate(
        [(r[None, :] + P * np.arange(turns)[:, None]).ravel(), (f[None, :] + P * np.arange(turns)[:, None]).ravel()]
    )
    lev = np.concatenate([np.ones(r.size * turns), np.zeros(f.size * turns)])
    ang = ang + 3.0 + rng.normal(0.0, jitter_deg, ang.size)
    order = np.argsort(ang)
    ang, lev = ang[order], lev[order]
    w0 = rpm * 6.0
    t = np.linspace(0.0, 1.2 * ang.max() / w0, 400_000)
    theta = w0 * t * (1 + 0.1 * t / t[-1]) + swing * 360 / (4 * math.pi) * np.sin(4 * math.pi * w0 * t / 360)
    te = np.interp(ang, theta, t) + 1e-3
    if glitch:  # a pulse of a microsecond in the middle
        i = te.size // 2
        te = np.insert(te, i, [te[i - 1] + 0.4 * (te[i] - te[i - 1]), te[i - 1] + 0.4 * (te[i] - te[i - 1]) + 1e-6])
        lev = np.insert(lev, i, [1 - lev[i - 1], lev[i - 1]])
    if invert:
        lev = 1 - lev
    return rotor.Log.from_arrays(time=np.r_[0.0, te], encoder_d=np.r_[1 - lev[0], lev])


def _read_as(log, wheel=None) -> str | None:
    try:
        r = read_wheel(log, wheel)
    except LogError:
        return None
    return r.pattern.name if isinstance(r, PatternReading) else r.wheel.spec


DEFECTS = list(
    itertools.product((False, True), (0.0, 0.5), (0.0, 0.3), (False, True))
)  # invert, jitter, displace, glitch


@pytest.mark.parametrize("name", list(CATALOGUE))
def test_a_patterns_own_signal_reads_as_itself_or_is_refused(name):
    p = CATALOGUE[name]
    got = [
        _read_as(digital_log(p, invert=i, jitter_deg=j, displace=d, glitch=g, seed=k))
        for k, (i, j, d, g) in enumerate(DEFECTS)
    ]
    wrong = [(DEFECTS[k], g) for k, g in enumerate(got) if g is not None and g != name]
    assert not wrong, f"{name} read as another wheel: {wrong}"
    if not p.evenly_spaced:
        # clean and inverted, it is read (a pattern that timing alone cannot tell is refused, by design)
        assert got[0] == name and got[DEFECTS.index((True, 0.0, 0.0, False))] == name


def test_most_of_the_matrix_is_read():
    cells = [(p, d) for p in CATALOGUE.values() if not p.evenly_spaced for d in DEFECTS]
    read = sum(
        _read_as(digital_log(p, invert=i, jitter_deg=j, displace=dd, glitch=g)) == p.name for p, (i, j, dd, g) in cells
    )
    assert read / len(cells) >= 0.8, f"{read} of {len(cells)} read"


@pytest.mark.parametrize("name", list(CATALOGUE))
def test_a_named_pattern_reads_its_own_signal(name):
    p = CATALOGUE[name]
    assert _read_as(digital_log(p), name) == name


def test_a_wheel_of_two_equal_halves_is_never_read_as_its_half():
    """36-2-2 (two equal halves) and 18-2 give the same edges at speeds a factor 2 apart:
    read as the catalogue's 36-2-2, or refused naming both, never as 18-2."""
    p = find_pattern("36-2-2")
    for k, jitter in enumerate((0.0, 0.5, 0.8)):
        try:
            got = _read_as(digital_log(p, jitter_deg=jitter, seed=k), None)
        except LogError as e:
            assert "18-2" in str(e) and "36-2-2" in str(e)
            continue
        assert got in ("36-2-2", None)
