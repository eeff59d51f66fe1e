"""rotor analyze on the real tue-4gb10 recordings (skipped without ../shared/data), the
log reader's errors, and the command line."""

import json

import numpy as np
import pytest

import rotor
from rotor import LogError
from rotor.cli import main
from conftest import SHARED_DATA

TUE = SHARED_DATA / "tue-4gb10"
needs_data = pytest.mark.skipif(not TUE.is_dir(), reason=f"shared data not found at {TUE}")
COLS = "time,pressure_v,encoder_v"
GEOM = dict(compression_ratio=8.5, rod_ratio=27.5 / 84.2)  # data README: stroke 55 mm, rod 84.2 mm
NAMES = ("No_load", "half_load", "full_load")


@pytest.fixture(scope="module")
def tue():
    out = {}
    for n in NAMES:
        out[n] = (rotor.analyze_log(TUE / f"{n}.txt", "60-2", columns=COLS, **GEOM),
                  rotor.analyze_log(TUE / f"{n}.txt", "60-2", columns=COLS, tooth_errors=None, **GEOM))
    return out


@needs_data
def test_real_every_revolution_found_and_speed(tue):
    for n, (a, _) in tue.items():
        w = a.track
        assert np.all(np.bincount(w.rev[w.rev >= 0])[:-1] == 58)  # every complete revolution: 58 edges
        assert a.cycles >= 11
        assert np.all(np.abs(a.mean_rpm - 3000) < 250)
        assert np.std(a.mean_rpm) / np.mean(a.mean_rpm) < 0.01


@needs_data
def test_real_half_order_ranks_with_load(tue):
    half = [tue[n][0].amplitude_of(0.5).mean() for n in NAMES]
    assert half[0] < half[1] < half[2]
    deltas = [tue[n][0].delta.mean() for n in NAMES]
    assert deltas[0] < deltas[1] < deltas[2]


@needs_data
def test_real_tooth_correction_matters_and_agrees_across_recordings(tue):
    errs = []
    for n, (a, raw) in tue.items():
        assert raw.delta.mean() > 2 * a.delta.mean()  # the gap's distorted edges dominate uncorrected δ
        errs.append(a.tooth_errors.errors_deg)
    errs = np.array(errs)
    # one wheel, three recordings: the estimates agree (the two edges at the gap are ~+0.9° and −0.55°)
    assert np.max(np.abs(errs - errs.mean(axis=0))) < 0.05
    assert errs[:, 0].mean() > 0.7 and errs[:, -1].mean() < -0.4


@needs_data
def test_real_tdc_from_pressure_consistent(tue):
    tdc = np.array([np.rad2deg(tue[n][0].tdc_rad) for n in NAMES])
    # benchmarks/calibrate_presets.py found 28.9° on full load by the same kind of fit
    assert np.all(np.abs(tdc - 29.0) < 2.5), tdc
    # the firing TDC is where the pressure peaks: cycle angle 360° + a few degrees
    for n in NAMES:
        ph, p, _ = tue[n][0].pressure
        assert 360 < np.rad2deg(ph[np.argmax(p)]) < 400


@needs_data
def test_real_other_column_order_gain_and_offset(tmp_path):
    raw = np.loadtxt(TUE / "half_load.txt")
    path = tmp_path / "other.csv"
    with open(path, "w") as f:
        f.write("encoder,x,time,pressure\n")
        for t, p, e in raw:
            f.write(f"{-3.3 * e + 7.0:.6f},0,{t:.6e},{0.2 * p - 1:.6f}\n")
    a = rotor.analyze_log(path, "60-2", columns="encoder_v,-,time,pressure_v", edge="falling", **GEOM)
    b = rotor.analyze_log(TUE / "half_load.txt", "60-2", columns=COLS, **GEOM)
    assert a.cycles == b.cycles
    np.testing.assert_allclose(a.mean_rpm, b.mean_rpm, rtol=1e-4)
    np.testing.assert_allclose(a.amplitude_of(0.5), b.amplitude_of(0.5), rtol=0.02)
    assert abs(a.tdc_rad - b.tdc_rad) < np.deg2rad(0.5)


@needs_data
def test_cli_analyze_json_and_plot(tmp_path, capsys):
    rc = main(["analyze", str(TUE / "full_load.txt"), "--wheel", "60-2", "--columns", COLS, "--json",
               "--compression-ratio", "8.5", "--rod-ratio", "0.3266", "--plot", str(tmp_path),
               "--save-tooth-errors", str(tmp_path / "teeth.json")])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    assert d["wheel"]["teeth_per_rev"] == 60 and d["wheel"]["edges_per_rev"] == 58
    c = d["cycles"][0]
    assert set(c) == {"t_start_s", "mean_rpm", "delta", "orders"}
    assert set(c["orders"][0]) == {"order", "amplitude_rad_s", "phase_rad"} and c["orders"][0]["order"] == 0.5
    assert len(d["tooth_error_correction"]["errors_rad"]) == 58
    assert (tmp_path / "full_load_analysis.png").stat().st_size > 10000
    # reuse the saved correction on another recording
    rc = main(["analyze", str(TUE / "No_load.txt"), "--wheel", "60-2", "--columns", COLS,
               "--tooth-errors", str(tmp_path / "teeth.json"), "--tdc-deg", "29"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "TDC 29.00° after the gap (given)" in out


# ------------------------------------------------------------------ reader and errors
def write(tmp_path, text, name="log.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_reader_delimiters_header_and_skip(tmp_path):
    for sep in (",", "\t", ";", "  "):
        p = write(tmp_path, f"# a comment\ntime{sep}x{sep}rpm\n0{sep}9{sep}1000\n0.1{sep}9{sep}1001\n"
                            f"\n0.2{sep}9{sep}1002\n".replace("time", "t0" if sep == "  " else "time"))
        log = rotor.read_log(p, "time,-,rpm")
        np.testing.assert_array_equal(log["rpm"], [1000, 1001, 1002])
        np.testing.assert_array_equal(log.lines, [3, 4, 6])
    p = write(tmp_path, "time,rpm\n0,1000\n0.1,1000\n0.2,1000\n")
    assert rotor.read_log(p).kind == "speed"  # the header's names are the spec
    p = write(tmp_path, "0.001\n0.002\n0.003\n")
    assert rotor.read_log(p).kind == "teeth"


@pytest.mark.parametrize("text,spec,match", [
    ("0,1\n0.1,2\n0.1,3\n0.3,4\n", "time,rpm", r"line 3, column 'time': 0.1 s is not after"),
    ("0,1\n0.1,nan\n0.2,3\n", "time,rpm", r"line 2, column 'rpm': nan is not a finite number"),
    ("0,1\n0.1,abc\n0.2,3\n", "time,rpm", r"line 2, column 2: 'abc' is not a number"),
    ("0,1\n0.1,2\n0.2,3\n", "time,rpm,encoder_v", r"line 1 has 2 columns.*no column for 'encoder_v'"),
    ("0,1\n0.1,2\n0.2,3\n", "time,speed", r"column 2 is named 'speed'"),
    ("0,1\n0.1,2\n0.2,3\n", "time,pressure_v", r"name a 'tooth_time_s', 'encoder_v'"),
    ("0,1,2\n0.1,2\n0.2,3,4\n", "time,-,rpm", r"line 2: 2 columns where the first line has 3"),
])
def test_reader_errors_name_row_and_column(tmp_path, text, spec, match):
    p = write(tmp_path, text)
    with pytest.raises(LogError, match=match):
        rotor.read_log(p, spec)


def test_cli_errors_one_line_exit_2(tmp_path, capsys):
    p = write(tmp_path, "0.001\n0.002\n0.003\n0.004\n")
    assert main(["analyze", str(p), "--wheel", "60-2"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "4 tooth edges" in err and "more than one revolution" in err
    assert main(["analyze", str(tmp_path / "none.csv"), "--wheel", "60-2"]) == 2
    assert "No such file" in capsys.readouterr().err
    p = write(tmp_path, "0,1,2\n", "one.csv")
    assert main(["analyze", str(p), "--wheel", "60-2", "--columns", "time,encoder_v,bogus"]) == 2
    assert "bogus" in capsys.readouterr().err


def test_speed_log_analysis():
    """A speed series (time, rpm) with a known half order: the analysis gives it back."""
    w0 = 2000 / 30 * np.pi
    t = np.linspace(0, 1.0, 20001)
    # ω(θ) = w0 (1 + 0.02 cos(θ/2 + 0.3)): integrate θ(t) finely
    th = np.zeros_like(t)
    for i in range(1, t.size):
        w = w0 * (1 + 0.02 * np.cos(th[i - 1] / 2 + 0.3))
        th[i] = th[i - 1] + w * (t[i] - t[i - 1])
    omega = w0 * (1 + 0.02 * np.cos(th / 2 + 0.3))
    a = rotor.analyze_log(rotor.Log.from_arrays(time=t, rpm=omega * 30 / np.pi), tdc_deg=0, firing=0)
    assert a.amplitude_of(0.5) == pytest.approx(np.full(a.cycles, 0.02 * w0), rel=2e-3)
    ph = a.phase_rad[:, 0]
    # cycles start at θ = 4πk (tdc 0, parity 0 → start one revolution before rev 0's TDC: θ = −2π + 4πk … )
    assert np.allclose(np.cos(ph), np.cos(ph[0]), atol=1e-3)
