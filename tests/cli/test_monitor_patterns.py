"""The monitor reads a capture whose wheel is a catalogue pattern (a cam wheel, uneven teeth) as
`rotor analyze` does, and follows its edges as a missing-tooth wheel's (skipped without the
shared data)."""

from __future__ import annotations

import json

import pytest
from conftest import SHARED_DATA, run_cli

TRIGGERS = SHARED_DATA / "ecu-triggers"

# the 3000GT's 6G72: a 3.0 l V6, four-stroke (the capture's README); 91.1 x 76 mm, the rod, the
# masses and the inertia estimates of an engine of that size
ENGINE = """
name = "6G72"
strokes = 4
cylinders = 6

[geometry]
bore_m = 0.0911
stroke_m = 0.076
rod_length_m = 0.137

[masses]
reciprocating_kg = 0.6
rotating_kg = 0.4

[crankshaft]
inertia_kgm2 = 0.2

[layout]
throw_angles_deg = [0, 0, 120, 120, 240, 240]
bank_angles_deg = [0, 60, 0, 60, 0, 60]
firing_order = [1, 2, 3, 4, 5, 6]

[operating]
rpm = 200
"""

CYCLE = """
[pressure]
kind = "wiebe"
compression_ratio = 10.0
intake_pa = 90000
exhaust_pa = 105000
imep_pa = 3.0e5
start_deg = 350.0
duration_deg = 60.0
form_factor = 2.0
compression_exponent = 1.33
expansion_exponent = 1.28
exhaust_open_deg = 500.0
blowdown_deg = 60.0
overlap_deg = 30.0
crankcase_pa = 101325
"""


@pytest.mark.skipif(not TRIGGERS.is_dir(), reason=f"shared data not found at {TRIGGERS}")
def test_a_cam_pattern_capture_is_monitored(tmp_path, capsys):
    (tmp_path / "6g72.toml").write_text(ENGINE + CYCLE)
    rc, out, err = run_cli(
        capsys,
        "monitor",
        str(TRIGGERS / "3000gt.csv"),
        "--engine",
        str(tmp_path / "6g72.toml"),
        "--tdc-deg",
        "0",
        "--json",
    )
    assert rc == 0, err
    assert "wheel mitsubishi-6g72-cam" in err and "followed as a 60-2 wheel" in err
    summary = json.loads(out.strip().splitlines()[-1])["summary"]
    assert summary["firings_judged"] >= 60


def test_a_patterns_edges_as_tooth_times_keep_its_speed():
    import numpy as np

    from rotor.logs.catalogue import find_pattern
    from rotor.logs.patterns import channel_edges, decode_edges
    from rotor.logs.synthetic import pattern_capture

    log = pattern_capture(find_pattern("mazda-nb-crank"), rpm=900.0, swing=0.0, turns=10)
    times, _ = channel_edges(log["time"], log["encoder_d"], "rising")
    fit = decode_edges(times, find_pattern("mazda-nb-crank"))
    teeth = fit.tooth_times(60, 2)
    assert teeth.size >= 58 * 8
    # 58 of 60 teeth a revolution between the kept edges, each revolution as long as the pattern's
    rev = np.diff(teeth[::58])
    _, rpm = fit.rpm_per_turn()
    assert 60.0 / float(np.median(rev)) == pytest.approx(float(np.median(rpm)), rel=0.02)


@pytest.mark.skipif(not TRIGGERS.is_dir(), reason=f"shared data not found at {TRIGGERS}")
def test_an_engine_without_combustion_is_refused_by_the_monitor_in_one_line(tmp_path, capsys):
    (tmp_path / "6g72.toml").write_text(ENGINE)  # no [pressure]: the model has no firing torque
    rc, _, err = run_cli(
        capsys, "monitor", str(TRIGGERS / "3000gt.csv"), "--engine", str(tmp_path / "6g72.toml"), "--tdc-deg", "0"
    )
    assert rc == 2 and "does no combustion work in the model" in err and "internal error" not in err


def test_a_measurement_file_is_monitored_as_analyze_reads_it(tmp_path, capsys):
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    from rotor.logs.synthetic import bench_capture

    log = bench_capture(rpm=1500, revolutions=30)
    path = tmp_path / "run.parquet"
    pq.write_table(pa.table({"time": log["time"], "crank": log["encoder_v"]}), path)
    rc, out, err = run_cli(capsys, "monitor", str(path), "--cylinders", "1", "--tdc-deg", "0", "--json")
    assert rc == 0, err
    assert "wheel 60-2, rising edges, as `rotor analyze` reads the file" in err
    assert json.loads(out.strip().splitlines()[-1])["summary"]["firings_judged"] >= 10
