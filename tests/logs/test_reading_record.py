"""The reading record: how a recording's wheel was read, kept to read the other recordings of
the installation the same way, and to refuse one that reads otherwise, naming the difference."""

from __future__ import annotations

import pytest
from conftest import SHARED_DATA

import rotor
from rotor.errors import LogError
from rotor.logs.catalogue import find_pattern
from rotor.logs.recording import ReadingRecord, read_wheel, reading_record
from rotor.logs.synthetic import pattern_capture

TUE = SHARED_DATA / "tue-4gb10"


def test_a_record_says_how_the_wheel_was_read_and_survives_json():
    log = pattern_capture(find_pattern("36-2-1"), seed=1)
    r = reading_record(read_wheel(log, None))
    assert r.wheel == "36-2-1" and r.channel == "encoder_d" and r.edge in ("rising", "falling")
    assert ReadingRecord.from_json_dict(r.to_json_dict()) == r


def test_a_recording_of_the_same_wheel_reads_as_recorded():
    first = read_wheel(pattern_capture(find_pattern("36-2-1"), seed=1), None)
    second = read_wheel(
        pattern_capture(find_pattern("36-2-1"), seed=2, jitter_deg=0.3), None, as_read=reading_record(first)
    )
    assert reading_record(second) == reading_record(first)


def test_a_recording_of_another_wheel_is_refused_naming_the_calibrations_reading():
    record = reading_record(read_wheel(pattern_capture(find_pattern("60-2"), seed=1), None))
    with pytest.raises(LogError, match="not read as the calibration's recording was .60-2"):
        read_wheel(pattern_capture(find_pattern("36-2-1"), seed=2), None, as_read=record)


def test_a_recording_read_from_another_channel_is_refused_naming_it():
    log = pattern_capture(find_pattern("36-2-1"), seed=1)
    record = reading_record(read_wheel(log, None))
    other = ReadingRecord(record.wheel, record.edge, "cam_d")
    with pytest.raises(LogError, match="channel cam_d there, encoder_d here"):
        read_wheel(log, None, as_read=other)


@pytest.mark.parametrize("bad", [None, 3, {"wheel": "60-2"}, {"wheel": "60-2", "channel": "encoder_v", "edge": 1}])
def test_a_damaged_record_is_refused(bad):
    with pytest.raises(LogError, match="reading record"):
        ReadingRecord.from_json_dict(bad)


def test_analyze_log_takes_only_a_record():
    with pytest.raises(TypeError, match="ReadingRecord"):
        rotor.analyze_log(pattern_capture(find_pattern("60-2"), seed=1), as_read={"wheel": "60-2"})


@pytest.mark.skipif(not TUE.is_dir(), reason=f"shared data not found at {TUE}")
def test_the_files_of_one_bench_read_as_the_first_was():
    record = rotor.analyze_log(TUE / "full_load.txt").reading_record
    assert record is not None and record.wheel == "60-2"
    for name in ("half_load.txt", "No_load.txt"):
        assert rotor.analyze_log(TUE / name, as_read=record).reading_record == record
