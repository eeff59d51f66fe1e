"""Measurement files (rotor.logs.formats): a recording written as MDF 3 and 4, TDMS, MATLAB
v5 and v7.3, Parquet and Arrow by their own libraries reads to the same per-cycle speed and
δ as its text file, with its channels recognised by content or named by role; units from
the file's metadata (a time in ms, a speed in rad/s) are converted and said; a channel name
that is not in the file lists those that are; a missing library names its extra; the sample
files that npTDMS, pyarrow and SciPy ship read as what they hold."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import rotor
from rotor.errors import LogError
from rotor.logs.formats import FORMATS, detect_format
from rotor.logs.reader import channel_map, read_log
from rotor.logs.synthetic import pattern_capture, speed_profile, wheel_signal, write_log

asammdf = pytest.importorskip("asammdf")
nptdms = pytest.importorskip("nptdms")
h5py = pytest.importorskip("h5py")
pa = pytest.importorskip("pyarrow")
import pyarrow.feather as feather  # noqa: E402
import pyarrow.parquet as pq  # noqa: E402
import scipy.io as sio  # noqa: E402

WHEEL = "60-2"


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """A VR wheel signal (1500 rpm, δ 0.05 at order 2) as a text log, the columns it reads
    back as, and the analysis of the text file."""
    folder = tmp_path_factory.mktemp("formats")
    prof = speed_profile("steady", rpm=1500.0, revolutions=12, ripple=0.05, order=2.0)
    text = folder / "run.tsv"
    write_log(text, wheel_signal(prof, WHEEL, sensor="vr", sample_rate_hz=50e3))
    log = read_log(text)
    return folder, log["time"], log["encoder_v"], rotor.analyze_log(text, wheel=WHEEL)


def write_mdf(path: Path, t, v, version="4.10", unit="V"):
    m = asammdf.MDF(version=version)
    m.append([asammdf.Signal(v, t, name="CRANK", unit=unit)], comment="crank")
    m.append([asammdf.Signal(np.arange(5.0), np.arange(5.0), name="coolant", unit="degC")], comment="slow")
    m.save(path, overwrite=True)
    m.close()


def write_tdms(path: Path, t, v):
    with nptdms.TdmsWriter(str(path)) as w:
        props = {"wf_increment": float(np.median(np.diff(t))), "wf_start_offset": float(t[0]), "unit_string": "V"}
        w.write_segment([nptdms.ChannelObject("bench", "CRANK", v, properties=props)])


def arrow_table(t, v):
    schema = pa.schema(
        [
            pa.field("t_ms", pa.float64(), metadata={"unit": "ms"}),
            pa.field("CRANK", pa.float64(), metadata={"unit": "V"}),
        ]
    )
    return pa.table({"t_ms": t * 1e3, "CRANK": v}, schema=schema)


def write_mat73(path: Path, t, v):
    with h5py.File(path, "w", userblock_size=512) as f:  # MATLAB's layout: a text header, then HDF5
        f["t"] = t[None, :]  # MATLAB stores a column vector transposed
        f["CRANK"] = v[None, :]
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64".ljust(116))


WRITERS = {
    "run.mf4": lambda p, t, v: write_mdf(p, t, v),
    "run.mdf": lambda p, t, v: write_mdf(p, t, v, version="3.30"),
    "run.tdms": write_tdms,
    "run.mat": lambda p, t, v: sio.savemat(p, {"t": t[:, None], "CRANK": v[:, None]}),
    "run73.mat": write_mat73,
    "run.parquet": lambda p, t, v: pq.write_table(arrow_table(t, v), p),
    "run.arrow": lambda p, t, v: feather.write_feather(arrow_table(t, v), p),
}
KEYS = {"run.mf4": "mdf", "run.mdf": "mdf", "run.tdms": "tdms", "run.mat": "mat", "run73.mat": "mat73"}


@pytest.mark.parametrize("name", list(WRITERS))
@pytest.mark.parametrize("named", [False, True], ids=["by-content", "by-name"])
def test_a_recording_reads_to_the_same_speed_and_delta_as_its_text_file(recording, name, named):
    folder, t, v, ref = recording
    path = folder / name
    WRITERS[name](path, t, v)
    assert detect_format(str(path)) == KEYS.get(name, path.suffix[1:])
    columns = "crank=CRANK" if named else None
    res = rotor.analyze_log(path, wheel=WHEEL, columns=columns)
    assert res.cycles == ref.cycles >= 4
    np.testing.assert_allclose(res.mean_rpm, ref.mean_rpm, rtol=1e-9)
    np.testing.assert_allclose(res.delta, ref.delta, rtol=1e-7)
    assert res.delta.mean() == pytest.approx(0.05, rel=0.03)


def test_the_time_unit_of_the_metadata_is_converted_and_said(recording):
    folder, t, v, _ = recording
    pq.write_table(arrow_table(t, v), folder / "ms.parquet")
    log = read_log(folder / "ms.parquet", "time=t_ms,encoder_v=CRANK")
    np.testing.assert_allclose(log["time"], t, rtol=1e-15)
    assert any("'t_ms' [ms] → time, × 0.001 to s" in n for n in log.notes)


def test_a_speed_in_rad_per_s_is_read_in_rpm(tmp_path):
    t = np.linspace(0.0, 2.0, 400)
    omega = 150.0 + 3.0 * np.sin(2 * np.pi * 5 * t)  # rad/s
    m = asammdf.MDF(version="4.10")
    m.append([asammdf.Signal(omega, t, name="nEng", unit="rad/s")])
    m.save(tmp_path / "speed.mf4", overwrite=True)
    log = read_log(tmp_path / "speed.mf4", "speed=nEng")
    assert log.kind == "speed"
    np.testing.assert_allclose(log["rpm"], omega * 30 / math.pi, rtol=1e-14)
    assert any("× 9.5493 to rpm" in n for n in log.notes)


def test_a_time_channel_in_a_unit_that_is_no_time_is_refused(tmp_path):
    t = np.linspace(0.0, 1.0, 100)
    pq.write_table(
        pa.table(
            {"t": t, "v": np.sin(80 * t)},
            schema=pa.schema([pa.field("t", pa.float64(), metadata={"unit": "V"}), pa.field("v", pa.float64())]),
        ),
        tmp_path / "x.parquet",
    )
    with pytest.raises(LogError, match=r"channel 't' is in 'V', not a time unit"):
        read_log(tmp_path / "x.parquet", "time=t,encoder_v=v")


def test_a_digital_channel_in_mdf_reads_as_the_text_export_of_it(tmp_path):
    from rotor.logs.catalogue import find_pattern

    cap = pattern_capture(find_pattern("36-1"), rpm=1200.0, turns=10)
    m = asammdf.MDF(version="4.10")
    m.append([asammdf.Signal(cap["encoder_d"].astype(np.uint8), cap["time"], name="CRANK_DI", unit="")])
    m.save(tmp_path / "di.mf4", overwrite=True)
    for columns in (None, "crank=CRANK_DI", "encoder_d=CRANK_DI"):
        log = read_log(tmp_path / "di.mf4", columns)
        assert log.kind == "digital"
        np.testing.assert_array_equal(log["encoder_d"], cap["encoder_d"])
        np.testing.assert_array_equal(log["time"], cap["time"])


def test_a_channel_name_not_in_the_file_lists_the_names_that_are(recording):
    folder, t, v, _ = recording
    write_mdf(folder / "names.mf4", t, v)
    with pytest.raises(
        LogError,
        match=r"no channel 'crank_x' \(named for encoder_d\); the file's channels: "
        r"group 1 \(crank\): 'CRANK'; group 2 \(slow\): 'coolant'",
    ):
        read_log(folder / "names.mf4", "encoder_d=crank_x")


def test_channels_of_two_time_bases_are_refused_naming_both(recording):
    folder, t, v, _ = recording
    write_mdf(folder / "two.mf4", t, v)
    with pytest.raises(LogError, match=r"different time bases \('CRANK' in group 1.*'coolant' in group 2"):
        read_log(folder / "two.mf4", "encoder_v=CRANK,pressure_v=coolant")


def test_a_name_matches_in_another_case_and_the_group_time_base_is_the_time(recording):
    folder, t, v, _ = recording
    write_tdms(folder / "case.tdms", t, v)
    log = read_log(folder / "case.tdms", "encoder_v=crank")
    np.testing.assert_allclose(log["time"], t, rtol=0, atol=1e-12)


def test_an_order_spec_is_refused_for_a_measurement_file(recording):
    folder, t, v, _ = recording
    write_tdms(folder / "order.tdms", t, v)
    with pytest.raises(LogError, match=r"named by role and channel name"):
        read_log(folder / "order.tdms", "time,encoder_v")


@pytest.mark.parametrize(
    "spec, message",
    [
        ("time=t,encoder_v", r"'encoder_v' has no '='"),
        ("crank_wheel=CRANK", r"'crank_wheel' is no role; roles: time, encoder_v"),
        ("crank=A,encoder_d=B", r"'encoder_d' names the channel of 'crank' a second time"),
        ("time=t,time_ms=u", r"'time_ms' names the channel of 'time' a second time"),
        ("encoder_v=", r"encoder_v= names no channel"),
    ],
)
def test_a_bad_spec_of_channel_names_is_refused_by_name(spec, message):
    with pytest.raises(LogError, match=message):
        channel_map(spec)


def test_channel_map_takes_a_dict_and_leaves_an_order_spec_alone():
    assert channel_map({"time": "t", "encoder_d": "CRANK"}) == {"time": "t", "encoder_d": "CRANK"}
    assert channel_map("time,encoder_v") is None and channel_map(None) is None


def test_a_text_file_takes_the_same_spec_by_its_header_or_its_column_numbers(tmp_path, recording):
    _, t, v, ref = recording
    head = tmp_path / "head.csv"
    np.savetxt(head, np.column_stack([v, t, v * 0]), delimiter=",", header="CRANK,t,other", comments="", fmt="%.9f")
    log = read_log(head, "time=t,crank=CRANK")
    np.testing.assert_allclose(log["encoder_v"], v, atol=1e-9)
    assert log.lines is not None and int(log.lines[0]) == 2  # line numbers kept for messages
    bare = tmp_path / "bare.csv"
    np.savetxt(bare, np.column_stack([v, t]), delimiter=",", fmt="%.9f")
    np.testing.assert_allclose(read_log(bare, "time=2,encoder_v=1")["time"], t, atol=1e-9)
    with pytest.raises(LogError, match=r"no channel 'CRANK'.*the file's channels: '1', '2'"):
        read_log(bare, "encoder_v=CRANK")


@pytest.mark.parametrize(
    "module, extra", [("asammdf", "mdf"), ("nptdms", "tdms"), ("h5py", "mat"), ("pyarrow.parquet", "parquet")]
)
def test_a_missing_library_names_its_extra_and_the_install_command(recording, monkeypatch, module, extra):
    folder, t, v, _ = recording
    name = {"mdf": "run.mf4", "tdms": "run.tdms", "mat": "run73.mat", "parquet": "run.parquet"}[extra]
    WRITERS[name](folder / f"missing-{name}", t, v)
    monkeypatch.setitem(sys.modules, module, None)  # an import of it raises ImportError
    with pytest.raises(LogError) as err:
        read_log(folder / f"missing-{name}")
    text = str(err.value)
    assert "\n" not in text
    assert f"install rotor's {extra!r} extra (pip install '.[{extra}]' in rotor's folder" in text


def test_a_file_named_as_a_format_it_is_not_is_refused(tmp_path):
    (tmp_path / "fake.mf4").write_text("time,encoder_v\n0,1\n")
    with pytest.raises(LogError, match=r"named as a MDF \(ASAM MDF 3/4\) file but its first bytes"):
        read_log(tmp_path / "fake.mf4")
    (tmp_path / "log.dat").write_text("time,rpm\n0,1000\n0.1,1001\n0.2,1002\n")
    assert read_log(tmp_path / "log.dat").kind == "speed"  # a text .dat is a text log


def test_every_format_names_an_extra_of_the_project():
    import tomllib

    extras = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    for fmt in FORMATS.values():
        assert fmt.extra in extras, fmt
    assert set(extras["formats"]) == set(extras["mdf"] + extras["tdms"] + extras["mat"] + extras["parquet"])


# ---------------------------------------------------------------- the libraries' own sample files
def test_nptdms_digital_input_sample_reads_as_a_digital_channel_on_its_waveform_timing():
    path = Path(nptdms.__file__).parent / "test" / "data" / "Digital_Input.tdms"
    if not path.is_file():
        pytest.skip("npTDMS ships no sample files here")
    log = read_log(path)
    assert log.kind == "digital" and log.rows == 20000  # the full-rate group, not the decimated ones
    np.testing.assert_allclose(np.diff(log["time"]), 0.0005, rtol=1e-9)  # wf_increment
    assert any("All Data" in n for n in log.notes)


def test_nptdms_raw_sample_reads_a_named_channel_in_volts():
    path = Path(nptdms.__file__).parent / "test" / "data" / "raw1.tdms"
    if not path.is_file():
        pytest.skip("npTDMS ships no sample files here")
    log = read_log(path, {"encoder_v": "First  Channel"})
    assert log.rows == 2000
    np.testing.assert_allclose(np.diff(log["time"]), 2e-5, rtol=1e-9)
    assert any("'First  Channel' [Volts] → encoder_v" in n for n in log.notes)


def test_pyarrow_parquet_sample_lists_its_columns_for_a_name_it_lacks():
    path = Path(pa.__file__).parent / "tests" / "data" / "parquet" / "v0.7.1.parquet"
    if not path.is_file():
        pytest.skip("pyarrow ships no sample files here")
    with pytest.raises(LogError, match=r"no channel 'CRANK'.*'carat', 'depth', 'table', 'price'"):
        read_log(path, "encoder_v=CRANK")


def test_scipy_v73_sample_reads_its_vector_through_h5py():
    from rotor.logs.formats import read_channels

    path = Path(sio.__file__).parent / "matlab" / "tests" / "data" / "testhdf5_7.4_GLNX86.mat"
    if not path.is_file():
        pytest.skip("SciPy ships no sample files here")
    assert detect_format(str(path)) == "mat73"
    (group,) = read_channels(str(path), "mat73")
    assert [c.name for c in group.channels] == ["testdouble"] and group.rows == 9


# ---------------------------------------------------------------- the command line
def test_rotor_analyze_reads_an_mf4_file_by_channel_name(recording, capsys):
    import json

    from conftest import run_cli

    folder, t, v, ref = recording
    write_mdf(folder / "cli.mf4", t, v)
    args = ("analyze", folder / "cli.mf4", "--wheel", WHEEL, "--json")
    rc, out, err = run_cli(capsys, *args, "--columns", "time=time,crank=CRANK")
    assert rc == 0, err
    cycles = json.loads(out)["cycles"]
    np.testing.assert_allclose([c["delta"] for c in cycles], ref.delta, rtol=1e-9)
    rc, out, err = run_cli(capsys, *args, "--columns", "crank=CRANK2")
    assert rc == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "no channel 'CRANK2'" in lines[0] and "'CRANK'" in lines[0], err


# ---------------------------------------------------------------- damaged and odd files
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")  # asammdf's half-made reader, freed
def test_a_damaged_mdf_file_is_refused_in_one_line(recording):
    folder, t, v, _ = recording
    write_mdf(folder / "whole.mf4", t, v)
    data = (folder / "whole.mf4").read_bytes()
    (folder / "cut.mf4").write_bytes(data[:200])
    with pytest.raises(LogError, match=r"cut.mf4: not a readable MDF file") as e:
        read_log(folder / "cut.mf4")
    assert "\n" not in str(e.value)


def test_an_empty_table_and_a_table_of_text_have_no_channel(tmp_path):
    pq.write_table(pa.table({"t": pa.array([], pa.float64())}), tmp_path / "empty.parquet")
    with pytest.raises(LogError, match=r"empty.parquet: a Parquet file without a channel of numbers"):
        read_log(tmp_path / "empty.parquet")
    pq.write_table(pa.table({"label": ["a", "b", "c"]}), tmp_path / "words.parquet")
    with pytest.raises(LogError, match=r"without a channel of numbers"):
        read_log(tmp_path / "words.parquet")


def test_a_missing_value_is_refused_naming_its_row(recording):
    folder, t, v, _ = recording
    crank = pa.array(v.tolist()[:500] + [None] + v.tolist()[501:], pa.float64())
    pq.write_table(pa.table({"t": t, "CRANK": crank}), folder / "gap.parquet")
    with pytest.raises(LogError, match=r"row 500, column 'encoder_v': nan is not a finite number"):
        read_log(folder / "gap.parquet", "time=t,encoder_v=CRANK")


def test_a_file_over_the_memory_budget_is_refused_before_reading(recording, monkeypatch):
    folder, t, v, _ = recording
    write_tdms(folder / "big.tdms", t, v)
    monkeypatch.setenv("ROTOR_MEMORY_LIMIT_GB", "1e-6")
    with pytest.raises(LogError, match=r"big.tdms: reading the channels of this .* MB TDMS \(NI LabVIEW\) file needs"):
        read_log(folder / "big.tdms")


def test_a_mat_struct_and_matrix_name_their_fields_and_columns(recording):
    folder, t, v, ref = recording
    sio.savemat(folder / "struct.mat", {"bench": {"t": t, "crank": v}, "data": np.column_stack([t, v]), "n": 3.0})
    log = read_log(folder / "struct.mat", "time=bench.t,encoder_v=bench.crank")
    np.testing.assert_array_equal(log["encoder_v"], v)
    log = read_log(folder / "struct.mat", "time=data[1],encoder_v=data[2]")
    np.testing.assert_array_equal(log["time"], t)
    with pytest.raises(LogError, match=r"no channel 'data\[3\]'.*'bench.t', 'bench.crank', 'data\[1\]', 'data\[2\]'"):
        read_log(folder / "struct.mat", "time=data[1],encoder_v=data[3]")
    np.testing.assert_array_equal(read_log(folder / "struct.mat", "encoder_v=data[2]")["time"], t)  # bench.t
    sio.savemat(folder / "two.mat", {"a": t, "b": t + 1.0, "crank": v})
    with pytest.raises(LogError, match=r"'a', 'b' could each be it; name it \(time=…\)"):
        read_log(folder / "two.mat", "encoder_v=crank")


def test_a_binary_file_of_no_known_format_names_the_formats_read(tmp_path):
    (tmp_path / "blob.bin").write_bytes(b"\x00\x01\x02" * 100)
    with pytest.raises(
        LogError, match=r"NUL bytes .* or a measurement file \(MDF, TDMS, MATLAB .mat, Parquet, Arrow\)"
    ):
        read_log(tmp_path / "blob.bin")


def test_a_spec_reads_only_the_channels_it_names_and_lists_the_others(recording):
    from rotor.logs.formats import read_channels

    folder, t, v, _ = recording
    write_mdf(folder / "some.mf4", t, v)
    groups = read_channels(str(folder / "some.mf4"), "mdf", ["crank"])
    assert [c.name for g in groups for c in g.channels] == ["CRANK"]
    assert [n for g in groups for n in g.others] == ["coolant"]
    pq.write_table(arrow_table(t, v), folder / "some.parquet")
    (table,) = read_channels(str(folder / "some.parquet"), "parquet", ["CRANK"])
    assert [c.name for c in table.channels] == ["CRANK"] and table.others == ("t_ms",)
