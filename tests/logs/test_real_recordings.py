"""Every real recording of ../shared/data read as a user reads it, with nothing but the file
(skipped without the data): each capture as its documented pattern, at a speed within the
range its README gives (±2 %), the bench files at the speed of their pressure channel's
cycle period (±1 %); those that no catalogue pattern describes refused, never read as
another wheel."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SHARED_DATA

import rotor
from rotor.errors import LogError

TRIGGERS = SHARED_DATA / "ecu-triggers"
TUE = SHARED_DATA / "tue-4gb10"
needs_data = pytest.mark.skipif(not TRIGGERS.is_dir(), reason=f"shared data not found at {TRIGGERS}")

# file, the pattern its README documents (a catalogue name or an N-M wheel), the README's speed range [rpm]
CAPTURES = [
    ("3000gt.csv", "mitsubishi-6g72-cam", 164, 194),
    ("4b11-running.csv", "36-2-1", 1399, 1486),
    ("4b11-running-doubled-edge.csv", "36-2-1", 1399, 1486),
    ("4g63-cranking.csv", "mitsubishi-4g63-cam", 133, 218),
    ("6g75-withsparkplugs-cranking.csv", "36-2-1-1", 135, 167),
    ("6g75-without-spark-crank.csv", "36-2-1-1", 128, 165),
    ("arctic-cat.csv", "arctic-cat", 528, 2129),
    ("BQS-1.csv", "bosch-quick-start-cam", 235, 444),  # ≈0.51 s a cam revolution at first, ≈0.27 s in the middle
    ("chrysler-phaser.csv", "chrysler-phaser-cam", 787, 821),
    ("cas_nissan_24_plus_1.csv", "12-tooth", 806, 1063),
    ("cranking_na_3.csv", "mazda-na-cas-1", 225, 1100),
    ("hr12-vvt-in-16s.csv", "nissan-hr-cam-in", 196, 202),
    ("nb2_rev-d-1.csv", ("mazda-nb-crank", "mazda-nb-cam"), 240, 250),
    ("nb2_rev-d-2.csv", ("mazda-nb-crank", "mazda-nb-cam"), 235, 235),
    ("neonsrt4.csv", "36-2-2", 147, 225),
]
# its wheel signal: sparse irregular edges for a second, then every period jittering by a fifth,
# broken by a dropout: no stretch long enough for the catalogue's gates
REFUSED = ["noisy-trigger-2.csv"]


def _wheel(a) -> str:
    return a.pattern.pattern.name if a.pattern is not None else a.track.wheel.spec


@needs_data
@pytest.mark.parametrize("name,pattern,lo,hi", CAPTURES, ids=[c[0] for c in CAPTURES])
def test_a_capture_is_read_by_default_as_its_documented_pattern(name, pattern, lo, hi):
    a = rotor.analyze_log(TRIGGERS / name)
    assert _wheel(a) in ((pattern,) if isinstance(pattern, str) else pattern)
    # the speed of the cycles read: the median within the README's range, ±2 %
    assert 0.98 * lo <= float(np.median(a.mean_rpm)) <= 1.02 * hi
    assert any(n.startswith("columns recognised by their content") for n in a.notes)


@needs_data
@pytest.mark.parametrize("name", REFUSED)
def test_a_capture_no_pattern_describes_is_refused(name):
    with pytest.raises(LogError):
        rotor.analyze_log(TRIGGERS / name)


@needs_data
def test_the_phaser_cam_capture_ends_at_the_speed_rusefi_asserts():
    # rusEFI's test of this capture (realChryslerPhaser.phaser_cam_1) asserts a final 808.3 rpm
    a = rotor.analyze_log(TRIGGERS / "chrysler-phaser.csv")
    assert float(a.mean_rpm[-1]) == pytest.approx(808.3, rel=0.01)


@needs_data
def test_a_header_that_names_a_coil_output_crank_is_overridden_by_the_content():
    a = rotor.analyze_log(TRIGGERS / "nb2_rev-d-2.csv")
    said = " ".join(a.notes)
    assert "the header names 'crank' but its content reads as -" in said


@pytest.mark.skipif(not TUE.is_dir(), reason=f"shared data not found at {TUE}")
@pytest.mark.parametrize("name", ["No_load.txt", "half_load.txt", "full_load.txt"])
def test_a_bench_file_is_read_by_default_at_its_pressure_cycles_speed(name):
    from scipy.signal import find_peaks

    a = rotor.analyze_log(TUE / name)
    assert _wheel(a) == "60-2"
    log = rotor.read_log(TUE / name)
    t, p = log["time"], log["pressure_v"]
    fs = 1.0 / float(np.median(np.diff(t)))
    peaks, _ = find_peaks(p, distance=int(0.03 * fs), prominence=0.5 * float(np.ptp(p)))
    rpm_pressure = 120.0 / float(np.mean(np.diff(t[peaks])))  # a cycle (720°) from peak to peak
    assert float(np.mean(a.mean_rpm)) == pytest.approx(rpm_pressure, rel=0.01)


@needs_data
def test_files_of_one_bench_read_as_one_wheel():
    wheels = {_wheel(rotor.analyze_log(TUE / f)) for f in ("No_load.txt", "half_load.txt", "full_load.txt")}
    assert wheels == {"60-2"}
    assert {_wheel(rotor.analyze_log(TRIGGERS / f)) for f in ("4b11-running.csv", "4b11-running-doubled-edge.csv")} == {
        "36-2-1"
    }
