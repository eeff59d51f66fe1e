"""A calibration records how its recording's wheel was read; a log diagnosed with it is read
the same way, or refused naming what it reads otherwise."""

from __future__ import annotations

import json
from importlib import resources

import rotor
from rotor.logs.recording import ReadingRecord


def _preset() -> dict:
    return json.loads((resources.files("rotor.presets") / "tue-single.calibration.json").read_text())


def test_the_preset_calibration_records_its_reading():
    record = ReadingRecord.from_json_dict(_preset()["reading"])
    assert record.wheel == "60-2" and record.channel == "encoder_v" and record.edge == "rising"


def test_a_log_read_otherwise_than_the_calibrations_recording_is_refused_naming_it(tmp_path, capsys):
    from conftest import run_cli

    d = _preset()
    d["reading"]["channel"] = "encoder_d"  # a logic analyser's channel, where this log is sampled
    (tmp_path / "cal.json").write_text(json.dumps(d))
    log = rotor.simulated_recording(tmp_path / "sim.txt", "tue-single", cycles=4, seed=1)
    rc, _, err = run_cli(
        capsys, "diagnose", str(log), "--engine", "tue-single", "--calibration", str(tmp_path / "cal.json")
    )
    assert rc == 2
    assert "read otherwise than the calibration's recording (channel encoder_d there, encoder_v here)" in err


def test_a_log_of_the_installation_is_read_as_the_calibrations_recording_was(tmp_path):
    log = rotor.simulated_recording(tmp_path / "sim.txt", "tue-single", cycles=4, seed=2)
    d = rotor.diagnose(rotor.load_engine("tue-single"), log)  # the preset's calibration
    assert d.analysis.reading_record == ReadingRecord.from_json_dict(_preset()["reading"])
