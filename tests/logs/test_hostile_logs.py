"""Hostile but realistic logs and calls: a time column in ms or µs,
a flat pressure channel, float32 time stamps, a log diagnosed as another engine, files
that are empty, binary, too large or not files at all, decimal commas, a byte-order mark,
an inverted wheel signal, size options, an order limit that keeps nothing, wrong Python
types. Each is refused with one line that names the file and the way out, or read right."""

import json

import numpy as np
import pytest
from conftest import run_cli

import rotor
from rotor import EngineError, LogError
from rotor.logs.analysis import NoCompressionPeak
from rotor.logs.reader import parse_columns

TWO_PI = 2 * np.pi


def tooth_times(rpm=3000.0, revs=12, teeth=60, missing=2, t0=0.0, fluct=0.02, start=0.37):
    """Edge times [s] of an N−M wheel at ``rpm`` with a half-order speed fluctuation ``fluct``."""
    w = TWO_PI * rpm / 60
    ang = start + TWO_PI * np.arange(revs)[:, None] + TWO_PI / teeth * np.arange(teeth - missing)[None, :]
    ang = ang.ravel()
    return t0 + ang / w + fluct * np.sin(ang / 2) / w


def wheel_samples(rpm=3000.0, seconds=0.3, fs=100e3, teeth=60, missing=2, narrow=None):
    """(t [s], a 0/1 pulse train of the wheel, crank angle [rad]); ``narrow`` = (duty, height)
    of the tooth after the gap (the real bench wheel's is narrow and low)."""
    t = np.arange(0.0, seconds, 1 / fs)
    phi = TWO_PI * rpm / 60 * t - 0.3
    pitch = TWO_PI / teeth
    pos = phi / pitch
    j = np.mod(np.floor(pos), teeth).astype(int)
    frac = pos - np.floor(pos)
    duty = np.full(t.size, 0.45)
    height = np.ones(t.size)
    if narrow is not None:
        duty[j == 0], height[j == 0] = narrow
    rf = np.deg2rad(0.5) / pitch
    v = height * np.minimum(np.clip(frac / rf, 0, 1), np.clip((duty - frac) / rf, 0, 1)) * (j < teeth - missing)
    return t, v, phi


def one_line_error(capsys, *argv):
    rc, out, err = run_cli(capsys, *argv)
    assert rc == 2, (rc, out, err)
    assert err.count("\n") == 1 and err.startswith("rotor: error:"), err
    assert "Traceback" not in err
    return err


# ----------------------------------------------------------------------------- 1. time base
@pytest.mark.parametrize("unit,factor,rpm_shown", [("milliseconds", 1e3, "3 rpm"), ("microseconds", 1e6, "0.003 rpm")])
def test_time_column_in_ms_or_us_is_questioned(tmp_path, capsys, unit, factor, rpm_shown):
    p = tmp_path / "teeth.csv"
    np.savetxt(p, tooth_times() * factor, fmt="%.12g")
    with pytest.raises(LogError, match=f"teeth.csv: the tooth-time column implies {rpm_shown}.*is it in {unit}"):
        rotor.analyze_log(p, "60-2")
    err = one_line_error(capsys, "analyze", p, "--wheel", "60-2")
    assert unit in err and "give seconds" in err


def test_unit_in_the_column_name_is_the_way_out(tmp_path):
    p = tmp_path / "teeth.csv"
    np.savetxt(p, tooth_times() * 1e3, fmt="%.12g")
    a = rotor.analyze_log(p, "60-2", columns="tooth_time_ms")
    assert np.mean(a.mean_rpm) == pytest.approx(3000.0, rel=1e-3)
    assert any("tooth_time_ms" in n for n in a.notes)
    log = rotor.Log.from_arrays(time_us=np.arange(5.0) * 10.0, rpm=np.full(5, 100.0))
    np.testing.assert_allclose(log["time"], np.arange(5.0) * 1e-5)
    with pytest.raises(LogError, match="'time_ms' names the 'time' column a second time"):
        parse_columns("time,time_ms")


def test_sampled_and_speed_logs_in_ms(capsys, tmp_path):
    t, v, _ = wheel_samples(seconds=0.1)
    with pytest.raises(LogError, match=r"the time column implies 3 rpm.*milliseconds.*'time_ms'"):
        rotor.analyze_log(rotor.Log.from_arrays(time=t * 1e3, encoder_v=v), "60-2")
    ts = np.arange(0.0, 0.5, 1e-3)
    with pytest.raises(LogError, match="revolutions apart.*'time_ms'"):
        rotor.analyze_log(rotor.Log.from_arrays(time=ts * 1e3, rpm=np.full(ts.size, 3000.0)))


def test_plausible_speeds_still_pass():
    # a start at 20 rpm and a fast engine at 20,000 rpm are engines, not wrong units
    for rpm in (20.0, 20_000.0):
        a = rotor.analyze_log(rotor.Log.from_arrays(tooth_time_s=tooth_times(rpm=rpm)), "60-2")
        assert np.mean(a.mean_rpm) == pytest.approx(rpm, rel=1e-3)


# ----------------------------------------------------------------------------- 2. pressure without a peak
def _encoder_with_pressure(pressure):
    t, v, _ = wheel_samples(seconds=0.25)
    return rotor.Log.from_arrays(time=t, encoder_v=-0.7 + 4.7 * v, pressure_v=pressure(t))


def test_flat_pressure_channel_gives_no_tdc():
    rng = np.random.default_rng(1)
    log = _encoder_with_pressure(lambda t: 0.59 + 0.0005 * rng.standard_normal(t.size))
    a = rotor.analyze_log(log, "60-2")
    assert a.tdc_method.startswith("unknown") and "no clear compression peak" in a.tdc_method
    assert "pressure peak" not in a.summary() and "no clear compression peak" in a.summary()
    assert a.to_json_dict()["tdc_method"].startswith("unknown")
    with pytest.raises(LogError, match="no clear compression peak"):
        rotor.analyze_log(log, "60-2", firing="pressure")
    b = rotor.analyze_log(log, "60-2", tdc_deg=10.0)  # TDC given: the firing revolution from the speed instead
    assert b.tdc_method == "given" and b.firing_method.startswith("speed")
    assert any("no clear compression peak" in n for n in b.notes)
    ph = np.linspace(0, 6 * TWO_PI, 20000)
    for p in (np.zeros(ph.size), np.full(ph.size, 0.59) + 1e-4 * rng.standard_normal(ph.size)):
        with pytest.raises(NoCompressionPeak, match="no clear compression peak"):
            rotor.tdc_from_pressure(ph, p)


def test_periodic_signal_that_is_no_pressure_gives_no_tdc():
    ph = np.linspace(0, 6 * TWO_PI, 20000)
    with pytest.raises(NoCompressionPeak, match="above half its peak's height"):
        rotor.tdc_from_pressure(ph, 1.0 + np.cos(ph / 2) + 0.001 * np.cos(ph * 7))


def test_a_compression_peak_is_still_found():
    ph = np.linspace(0, 6 * TWO_PI, 40000)
    x = np.mod(ph - 1.0 + TWO_PI, 2 * TWO_PI) - TWO_PI  # TDC at 1 rad of every second revolution
    p = 0.6 + 0.5 * np.exp(-((x / 0.4) ** 2)) + 1e-4 * np.random.default_rng(2).standard_normal(ph.size)
    tdc, _, method = rotor.tdc_from_pressure(ph, p)
    assert tdc == pytest.approx(1.0, abs=0.01) and method.startswith("pressure")


def test_calibration_refuses_a_flat_pressure_channel(tmp_path):
    rng = np.random.default_rng(3)
    t, v, _ = wheel_samples(seconds=0.25)
    p = tmp_path / "flat.tsv"
    np.savetxt(p, np.c_[t, 0.59 + 0.0005 * rng.standard_normal(t.size), v], delimiter="\t", fmt="%.8g")
    with pytest.raises(EngineError, match="TDC is not known.*no clear compression peak"):
        rotor.calibrate(rotor.load_engine("tue-single"), p, wheel="60-2", columns="time,pressure_v,encoder_v")


# ----------------------------------------------------------------------------- 3. float32 stamps
def test_float32_time_stamps_are_refused():
    t32 = (1000.0 + tooth_times()).astype(np.float32)
    with pytest.raises(LogError, match=r"resolve 6.1e-05 s \(float32 near 1000 s.*float64.*offsets from the start"):
        rotor.analyze_log(rotor.Log.from_arrays(tooth_time_s=t32), "60-2")
    # the way out: offsets from the start (or float64) give δ of the speed, not of the rounding
    a = rotor.analyze_log(rotor.Log.from_arrays(tooth_time_s=tooth_times()), "60-2")
    b = rotor.analyze_log(rotor.Log.from_arrays(tooth_time_s=1000.0 + tooth_times()), "60-2")
    assert np.mean(b.delta) == pytest.approx(np.mean(a.delta), rel=1e-3)


def test_float32_stamps_in_a_file_and_a_coarse_timer(tmp_path):
    p = tmp_path / "f32.csv"
    np.savetxt(p, (1000.0 + tooth_times()).astype(np.float32))  # float32 printed in full, read as float64
    with pytest.raises(LogError, match="f32.csv: the 'tooth_time_s' stamps resolve"):
        rotor.analyze_log(p, "60-2")
    period = 60 / 3000 / 60
    q = 0.005 * period  # a timer tick of half a per cent of the tooth period: read, with a note
    a = rotor.analyze_log(rotor.Log.from_arrays(tooth_time_s=np.round(tooth_times() / q) * q), "60-2")
    assert any("stamps resolve" in n for n in a.notes)
    # full-precision stamps, and an exactly constant speed (one tooth period, one gap period), are no rounding
    resolution = rotor.logs.plausibility.time_resolution_s
    assert resolution(tooth_times()) == 0.0
    assert resolution(tooth_times(fluct=0.0, teeth=36, missing=1)) == 0.0
    assert resolution(np.arange(2000) * 1e-5, evenly_spaced=True) == 0.0
    sampled = (100.0 + np.arange(2000) * 1e-5).astype(np.float32)  # float32 sample times near 100 s
    assert resolution(sampled, evenly_spaced=True) == pytest.approx(7.63e-6, rel=1e-3)


def test_equal_float32_sample_times_say_why():
    t = (1000.0 + np.arange(2000) * 1e-5).astype(np.float32)
    with pytest.raises(LogError, match="equal stamps.*float32.*float64"):
        rotor.Log.from_arrays(time=t, encoder_v=np.zeros(t.size))


# ----------------------------------------------------------------------------- 4. engine and log do not match
@pytest.fixture(scope="module")
def single_cylinder_log(tmp_path_factory):
    from rotor.diagnostics.synthetic import simulated_recording

    return simulated_recording(tmp_path_factory.mktemp("single") / "single.tsv", "tue-single", cycles=6)


def test_single_cylinder_log_diagnosed_as_four_cylinders_says_so(single_cylinder_log, capsys):
    rc, out, err = run_cli(
        capsys,
        "diagnose",
        single_cylinder_log,
        "--engine",
        "4chn15",
        "--wheel",
        "60-2",
        "--columns",
        "time,pressure_v,encoder_v",
        "--tdc-deg",
        "29.4",
        "--no-calibration",
        "--json",
    )
    assert rc == 0, err
    d = json.loads(out)
    assert any("implausible IMEP" in m for m in d["mismatch"])
    assert any("firing pattern of 4 cylinders is not seen" in m for m in d["mismatch"])
    assert any("operating speed" in m for m in d["mismatch"])
    assert set(d["mismatch"]) <= set(d["warnings"])
    assert "implausible IMEP" in err  # on stderr too


def test_matching_engine_has_no_mismatch(single_cylinder_log):
    d = rotor.diagnose(
        rotor.load_engine("tue-single"),
        single_cylinder_log,
        None,
        wheel="60-2",
        columns="time,pressure_v,encoder_v",
        tdc_deg=29.4,
    )
    assert d.mismatch == () and "mismatch" in d.to_json_dict() and "implausible" not in d.summary()


# ----------------------------------------------------------------------------- 5. messages
@pytest.mark.parametrize(
    "text,match",
    [
        ("", "empty.csv: no data"),
        ("0.1\n", "empty.csv: 1 row"),
        ("time,encoder_v\n", "empty.csv: no data rows"),
        ("time,encoder_v\n0,nan\n1,nan\n2,nan\n", "empty.csv: line 2, column 'encoder_v': nan"),
        (
            "time,encoder_v\n" + "".join(f"{i * 1e-5},1.0\n" for i in range(200)),
            "empty.csv: column 'encoder_v': no pulses",
        ),
        ("time,encoder_v\n" + "".join(f"{i * 1e-5},{float(i > 100)}\n" for i in range(200)), "empty.csv: 1 tooth edge"),
    ],
)
def test_degenerate_logs_one_line_naming_the_file(tmp_path, capsys, text, match):
    p = tmp_path / "empty.csv"
    p.write_text(text)
    with pytest.raises(LogError, match=match):
        rotor.analyze_log(p, "60-2")
    err = one_line_error(capsys, "analyze", p, "--wheel", "60-2")
    assert "empty.csv" in err and "zero-size" not in err


def test_inverted_wheel_signal_suggests_the_falling_edge(tmp_path, capsys):
    t, v, _ = wheel_samples(narrow=(0.25, 0.5))  # a narrow, low tooth after the gap, as on the bench
    p = tmp_path / "inverted.csv"
    np.savetxt(p, np.c_[t, 2.0 - 3.0 * v], delimiter=",", header="time,encoder_v", comments="", fmt="%.8g")
    with pytest.raises(LogError, match=r"inverted.csv: the 60-2 wheel does not fit .* rising edges.*edge='falling'"):
        rotor.analyze_log(p, "60-2", edge="rising")
    err = one_line_error(capsys, "analyze", p, "--wheel", "60-2", "--edge", "rising")
    assert "--edge falling" in err and "is the wheel right" not in err
    for edge in ("falling", "auto"):  # given, or found: both edges are read and the falling ones fit
        a = rotor.analyze_log(p, "60-2", edge=edge)
        assert a.edges.inverted and np.mean(a.mean_rpm) == pytest.approx(3000.0, rel=1e-3)


def test_decimal_commas_are_read(tmp_path):
    t = tooth_times()
    p = tmp_path / "comma.csv"
    p.write_text("tooth_time_s;-\n" + "".join(f"{x:.9f};1.5\n".replace(".", ",") for x in t))
    a = rotor.analyze_log(p, "60-2")
    assert np.mean(a.mean_rpm) == pytest.approx(3000.0, rel=1e-4)
    assert any("decimal commas" in n for n in a.notes)
    q = tmp_path / "nohead.csv"
    q.write_text("0,001;1,23\n0,002;1,24\n0,003;1,25\n")
    log = rotor.read_log(q, "time,rpm")
    np.testing.assert_allclose(log["time"], [0.001, 0.002, 0.003])
    m = tmp_path / "mixed.csv"
    m.write_text("0,001;1.23\n")
    with pytest.raises(LogError, match="mixed.csv: line 1 writes '0,001' with a decimal comma"):
        rotor.read_log(m, "time,rpm")


def test_byte_order_mark_does_not_break_the_header(tmp_path):
    p = tmp_path / "bom.csv"
    p.write_text("tooth_time_s\n" + "".join(f"{x:.9f}\n" for x in tooth_times()), encoding="utf-8-sig")
    assert p.read_bytes().startswith(b"\xef\xbb\xbf")
    log = rotor.read_log(p)
    assert list(log.columns) == ["tooth_time_s"] and log.rows == tooth_times().size


# ----------------------------------------------------------------------------- 6. sizes
def test_an_engine_without_its_tdc_is_refused_in_each_callers_words(tmp_path, capsys):
    """The library names the argument, the command line the flag."""
    p = tmp_path / "teeth.csv"
    np.savetxt(p, tooth_times(), fmt="%.12g")
    err = one_line_error(capsys, "analyze", p, "--wheel", "60-2", "--engine", "4chn15")
    assert "give --tdc-deg … as well" in err and "tdc_deg" not in err
    with pytest.raises(LogError, match="give tdc_deg=… as well"):
        rotor.analyze_log(p, "60-2", engine=rotor.load_engine("4chn15"))


def test_points_per_cycle_checked_before_allocating(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("ROTOR_MEMORY_LIMIT_GB", "1")
    p = tmp_path / "teeth.csv"
    np.savetxt(p, tooth_times(), fmt="%.12g")
    err = one_line_error(capsys, "analyze", p, "--wheel", "60-2", "--points-per-cycle", "100000000")
    assert "100000000 points per cycle" in err and "over the 1 GB" in err and "--points-per-cycle" in err
    with pytest.raises(LogError, match="needs .* GB of memory"):
        rotor.analyze_log(p, "60-2", points_per_cycle=10**9)


def test_zero_filled_and_too_large_files(tmp_path, capsys, monkeypatch):
    z = tmp_path / "zeros.csv"
    z.write_bytes(b"\0" * 200_000)
    with pytest.raises(LogError, match="zeros.csv: not a text log: it holds NUL bytes"):
        rotor.read_log(z)
    err = one_line_error(capsys, "analyze", z, "--wheel", "60-2")
    assert str(z) in err and len(err) < 300
    p = tmp_path / "teeth.csv"
    np.savetxt(p, tooth_times(), fmt="%.12g")
    monkeypatch.setenv("ROTOR_MEMORY_LIMIT_GB", "0.000001")
    with pytest.raises(LogError, match="teeth.csv: reading this .* MB log needs .* GB of memory.*split it"):
        rotor.read_log(p)


def test_simulated_recording_size_checked_before_allocating(tmp_path, monkeypatch):
    from rotor.diagnostics.synthetic import simulated_recording

    monkeypatch.setenv("ROTOR_MEMORY_LIMIT_GB", "0.5")
    with pytest.raises(EngineError, match="1000000 cycles .* needs .* GB of memory.*record fewer cycles"):
        simulated_recording(tmp_path / "huge.tsv", cycles=10**6)
    assert not (tmp_path / "huge.tsv").exists()


# ----------------------------------------------------------------------------- 7. an order limit that keeps none
def test_max_order_that_keeps_no_order_is_an_error(tmp_path, capsys):
    p = tmp_path / "teeth.csv"
    np.savetxt(p, tooth_times(), fmt="%.12g")
    err = one_line_error(capsys, "analyze", p, "--wheel", "60-2", "--max-order", "1e-9")
    assert "keeps no order" in err and "0.5" in err
    with pytest.raises(LogError, match="keeps no order.*2-stroke cycle is 1"):
        rotor.analyze_log(p, "60-2", strokes=2, max_order=0.5)
    a = rotor.analyze_log(p, "60-2", max_order=0.5)  # the lowest order alone is kept
    assert a.order.tolist() == [0.5] and np.all(np.isfinite(a.delta))


# ----------------------------------------------------------------------------- 8. wrong Python types
def test_wrong_types_name_the_argument(tmp_path):
    p = tmp_path / "teeth.csv"
    np.savetxt(p, tooth_times(), fmt="%.12g")
    log = rotor.Log.from_arrays(tooth_time_s=tooth_times())
    engine = rotor.load_engine("tue-single")
    cases = [
        (lambda: rotor.analyze_log(p, "60-2", engine="4chn15", tdc_deg=0.0), "engine = '4chn15': a rotor.Engine"),
        (lambda: rotor.analyze_log(5, "60-2"), "source = 5"),
        (lambda: rotor.analyze_log(log, 60.5), "wheel = 60.5"),
        (lambda: rotor.analyze_log(log, "60-2", tdc_deg="10"), "tdc_deg = '10'"),
        (lambda: rotor.analyze_log(log, "60-2", max_order="6"), "max_order = '6'"),
        (lambda: rotor.analyze_log(log, "60-2", points_per_cycle=720.5), "points_per_cycle = 720.5"),
        (lambda: rotor.analyze_log(log, "60-2", tooth_errors=3), "tooth_errors = 3"),
        (lambda: rotor.read_log(3), "path = 3"),
        (lambda: rotor.read_log(p, columns=5), "columns = 5"),
        (lambda: rotor.find_edges("a", "b"), r"find_edges\(t\)"),
        (lambda: rotor.diagnose("4chn15", p), r"diagnose\(engine\).*rotor.Engine"),
        (lambda: rotor.diagnose(engine, 5), r"diagnose\(log\)"),
        (lambda: rotor.diagnose(engine, p, 7), r"diagnose\(calibration\)"),
        (lambda: rotor.diagnose(engine, p, None, tdc_deg="x"), r"diagnose\(tdc_deg\)"),
        (lambda: rotor.calibrate("tue-single", p), r"calibrate\(engine\)"),
        (lambda: rotor.calibrate(engine, p, pressure_gain="5"), r"calibrate\(pressure_gain\)"),
        (lambda: rotor.identify("tue-single", np.ones((2, 720))), r"identify\(engine\)"),
    ]
    for call, match in cases:
        with pytest.raises(TypeError, match=match):
            call()


# ----------------------------------------------------------------------------- 9. file errors name the path
def test_file_errors_name_the_users_path(tmp_path, capsys):
    missing = tmp_path / "nowhere" / "log.csv"
    for path, match in ((missing, "No such file"), (tmp_path, "is a folder")):
        with pytest.raises(LogError, match=match) as e:
            rotor.read_log(path)
        assert str(path) in str(e.value)
        err = one_line_error(capsys, "analyze", path, "--wheel", "60-2")
        assert str(path) in err
    with pytest.raises(LogError, match=f"{tmp_path / 'te.json'}: No such file"):
        rotor.ToothErrors.load(tmp_path / "te.json")
    with pytest.raises(LogError, match="is a folder"):
        rotor.ToothErrors.load(tmp_path)
    with pytest.raises(EngineError, match=f"{tmp_path / 'cal.json'}: No such file"):
        rotor.Calibration.load(tmp_path / "cal.json")
    with pytest.raises(EngineError, match="is a folder"):
        rotor.Calibration.load(tmp_path)
