"""Analog bench signals with the defects a real installation's sensor shows near the gap of a
missing-tooth wheel (``rotor.logs.synthetic.bench_capture``): the tooth after the gap swinging a
third of the others (in every revolution or some), the teeth next to the gap late by up to 0.3 of
a pitch, the tooth before the gap merging with the gap on one polarity, a level in the gap above
the one between the teeth, negated. Each reads as its wheel (the level that reads it found from
the signal, a tooth the signal never shows kept as a signature), named or found, never as
another wheel; files of one bench read alike, and as the first was read."""

from __future__ import annotations

import itertools

import pytest

from rotor.errors import LogError
from rotor.logs.recording import read_wheel, reading_record
from rotor.logs.synthetic import bench_capture

DEFECTS = list(
    itertools.product((1.0, 0.35), ((0.0, 0.0), (0.3, 0.1), (-0.3, 0.0)), (0.45, 1.5), (0.0, 0.1), (False, True))
)  # faint, late, wide, gap level, negated: 48 cells; the suite reads every third


def _read(log, wheel=None) -> str | None:
    try:
        return read_wheel(log, wheel).wheel.spec
    except LogError:
        return None


@pytest.mark.parametrize("i", range(0, len(DEFECTS), 3))
def test_a_bench_signal_with_the_gaps_defects_reads_as_its_wheel(i):
    faint, late, wide, gap, negated = DEFECTS[i]
    log = bench_capture(faint=faint, late_pitch=late, wide_pitch=wide, gap_level=gap, invert=negated, seed=i)
    assert _read(log) == "60-2"
    assert _read(log, "60-2") == "60-2"


@pytest.mark.parametrize("wheel", ["36-1", "36-2"])
def test_other_wheels_with_a_faint_late_tooth_after_the_gap_read_as_themselves(wheel):
    log = bench_capture(wheel, rpm=2000, faint=0.35, late_pitch=(0.3, 0.1), wide_pitch=1.5, gap_level=0.1, seed=7)
    assert _read(log) == wheel


def test_the_level_that_reads_the_wheel_is_found_and_said():
    r = read_wheel(bench_capture(faint=0.35, late_pitch=(0.2, 0.1), wide_pitch=1.5, seed=3), "60-2")
    assert r.wheel.spec == "60-2" and not r.track.repairs
    assert any("of the swing: at the default level (32 %)" in n for n in r.notes)
    assert reading_record(r).level == pytest.approx(0.14)


def test_a_tooth_the_signal_never_shows_next_to_the_gap_is_a_signature_not_a_repair():
    r = read_wheel(bench_capture(faint=0.0, seed=2), "60-2")
    assert r.wheel.spec == "60-2" and r.fit.inferred == 0 and len(r.fit.signature) == 1
    assert any(n.startswith("signature: tooth") for n in r.notes)
    # found from the signal: the standard wheel with a signature, not a 60-3
    assert read_wheel(bench_capture(faint=0.0, seed=2), None).wheel.spec == "60-2"


def test_a_wheel_with_fewer_gaps_is_never_taken_for_one_with_a_signature():
    # 60-1 with its second tooth after the gap lacking is a 60-2: found from a clean 60-2, it is 60-2
    assert read_wheel(bench_capture(seed=4), None).wheel.spec == "60-2"


def test_five_files_of_one_bench_read_as_one_wheel_and_as_the_first_was():
    files = [
        bench_capture(rpm=rpm, noise_v=noise, faint=0.35, late_pitch=(0.2, 0.1), wide_pitch=1.5, gap_level=0.05, seed=k)
        for k, (rpm, noise) in enumerate([(3000, 0.01), (2400, 0.03), (3300, 0.02), (1800, 0.01), (2800, 0.05)])
    ]
    records = [reading_record(read_wheel(log, None)) for log in files]
    assert len({(r.wheel, r.edge, r.channel) for r in records}) == 1 and records[0].wheel == "60-2"
    for log in files[1:]:
        assert reading_record(read_wheel(log, None, as_read=records[0])) == records[0]


def test_a_wheel_found_from_the_signal_never_misfits_its_gaps_beyond_the_bound():
    from rotor.logs.catalogue import find_pattern
    from rotor.logs.identify import MAX_GAP_MISFIT
    from rotor.logs.synthetic import pattern_capture
    from rotor.logs.track import WheelReading

    logs = [
        bench_capture(faint=faint, late_pitch=late, wide_pitch=wide, gap_level=gap, invert=neg, seed=i)
        for i, (faint, late, wide, gap, neg) in enumerate(DEFECTS[1::6])
    ]
    logs += [
        pattern_capture(find_pattern(name), jitter_deg=0.5, displace=0.3, invert=inv, seed=k)
        for k, (name, inv) in enumerate(
            itertools.product(("60-2", "36-1", "36-2-1", "36-2-2-2", "24-1"), (False, True))
        )
    ]
    misfits = []
    for log in logs:
        try:
            r = read_wheel(log, None)
        except LogError:
            continue
        if isinstance(r, WheelReading):
            misfits.append(r.fit.gap_misfit)
    assert len(misfits) >= 8  # the bench signals, and the captures read through the tracker
    assert max(misfits) <= MAX_GAP_MISFIT
