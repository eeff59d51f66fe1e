"""The monitor reads a capture whose wheel is a catalogue pattern (a cam wheel, uneven teeth) as
`rotor analyze` does, and follows its edges as a missing-tooth wheel's (skipped without the
shared data)."""

from __future__ import annotations

import json

import pytest
from capture_engines import SIX, engine_toml
from conftest import SHARED_DATA, run_cli

TRIGGERS = SHARED_DATA / "ecu-triggers"

ENGINE = engine_toml("6G72 3.0 l V6", 0.0911, 0.076, SIX)  # the 3000GT's (its README)


@pytest.mark.skipif(not TRIGGERS.is_dir(), reason=f"shared data not found at {TRIGGERS}")
def test_a_cam_pattern_capture_is_monitored(tmp_path, capsys):
    (tmp_path / "6g72.toml").write_text(ENGINE)
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
    # no [pressure]: the model has no firing torque
    (tmp_path / "6g72.toml").write_text(engine_toml("6G72 3.0 l V6", 0.0911, 0.076, SIX, cycle=False))
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
