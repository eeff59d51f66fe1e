"""``rotor calibrate``: its own command over rotor.calibrate: a simulated
bench recording with pressure, with and without the sensor's gain (from a motored stretch);
JSON, the file it writes (which ``rotor diagnose --calibration`` reads) and one-line errors."""

from __future__ import annotations

import json

import matplotlib.pyplot as plt
import pytest
from conftest import run_cli

import rotor
from rotor.diagnostics.pegging import motored_cycles, pressure_gain_from_motored
from rotor.diagnostics.synthetic import BENCH_GAIN_PA_PER_V, BENCH_OFFSET_V, DEFAULT_GAP_DEG, simulated_recording

ENGINE = rotor.load_engine("tue-single")
ROD_RATIO = float(ENGINE.geometry.stroke_m) / 2 / float(ENGINE.geometry.rod_length_m)


@pytest.fixture(scope="module", autouse=True)
def _compilation_cache():
    """The test session's own persistent compilation cache (conftest.py sets its folder; the
    CLI switches it on anyway): this module and tests/diagnostics/test_tdc_from_speed.py /
    tests/diagnostics/test_calibrate_cli.py compile the same steady state and identification, and the
    second reuses the first's code after conftest drops the compiled executables."""
    rotor.enable_compilation_cache()


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    folder = tmp_path_factory.mktemp("calibrate")
    return simulated_recording(folder / "sim.txt", cycles=4, seed=3), folder


def test_calibrate_writes_what_diagnose_reads(recording, capsys):
    """With the sensor's gain (the no-gain default is rotor.calibrate's, tests/diagnostics/test_calibration.py):
    that gain back, TDC from the pressure within 0.5° of the simulated 29.4°, the file written
    and read back; the text names TDC and the file."""
    path, folder = recording
    out_file = folder / "cal.json"
    rc, out, err = run_cli(
        capsys,
        "calibrate",
        str(path),
        "--engine",
        "tue-single",
        "--wheel",
        "60-2",
        "--columns",
        "time,pressure_v,encoder_v",
        "--pressure-gain",
        str(BENCH_GAIN_PA_PER_V),
        "--output",
        str(out_file),
    )
    assert rc == 0, err
    assert "calibration of" in out and "after the gap" in out and str(out_file) in out
    cal = rotor.Calibration.load(out_file)
    assert cal.pressure_gain_pa == pytest.approx(BENCH_GAIN_PA_PER_V)
    assert cal.tdc_after_gap_deg == pytest.approx(-DEFAULT_GAP_DEG, abs=0.5)
    assert json.loads(json.dumps(cal.to_json_dict()))["format"] == "rotor-calibration"


def test_calibrate_errors_are_one_line(recording, tmp_path, capsys):
    path, _ = recording
    cases = [
        (["calibrate", str(path)], "--engine"),
        (
            ["calibrate", str(path), "--engine", "tue-single", "--wheel", "60-2", "--columns", "time,-,encoder_v"],
            "pressure",
        ),
        (
            [
                "calibrate",
                str(path),
                "--engine",
                "tue-single",
                "--wheel",
                "60-2",
                "--output",
                str(tmp_path / "x" / "c.json"),
            ],
            "no folder",
        ),
        (["calibrate", str(path), "--engine", "mwm6", "--wheel", "60-2"], "cylinders"),
    ]
    for argv, needle in cases:
        rc, out, err = run_cli(capsys, *argv)
        assert rc == 2, (argv, err)
        assert err.count("\n") == 1 and needle in err, (argv, err)


@pytest.fixture(scope="module")
def motored(tmp_path_factory):
    """A simulated recording whose cycles 1 and 2 do not fire (an ignition cut): the pressure
    channel's gain is found from them."""
    folder = tmp_path_factory.mktemp("motored")
    return simulated_recording(folder / "cut.txt", cycles=4, seed=5, motored_cycles=(1, 2))


def test_the_pressure_gain_from_a_motored_stretch(motored, recording, capsys):
    """No gain given, cycles without combustion in the log: the sensor's gain from their
    polytropic compression pegged at the intake pressure, within 1 % of the simulated
    sensor's (51.95 bar/V), its zero (the output at 0 Pa) within 2 mV; the motored cycles are exactly those
    simulated. ``--pressure-gain motored`` on a log that fires throughout: refused, one line."""
    a = rotor.analyze_log(
        motored,
        "60-2",
        columns="time,pressure_v,encoder_v",
        compression_ratio=float(ENGINE.pressure.compression_ratio),
        rod_ratio=ROD_RATIO,
    )
    assert list(motored_cycles(a)) == [False, True, True, False]
    gain = pressure_gain_from_motored(ENGINE, a)
    assert gain.cycles == (1, 2) and gain.gain_pa == pytest.approx(BENCH_GAIN_PA_PER_V, rel=0.01)
    ax = gain.plot()
    assert len(ax.lines) == 2 and "motored" in ax.get_title()
    plt.close(ax.figure)
    rc, out, err = run_cli(
        capsys,
        "calibrate",
        str(motored),
        "--engine",
        "tue-single",
        "--wheel",
        "60-2",
        "--columns",
        "time,pressure_v,encoder_v",
        "--json",
    )
    assert rc == 0, err
    d = json.loads(out)
    assert d["fit"]["pressure_gain_from"] == "motored cycles 1, 2"
    assert d["pressure_gain_pa"] == pytest.approx(BENCH_GAIN_PA_PER_V, rel=0.01)
    # the sensor's zero (its output at 0 Pa, 0.575 V) within 2 mV (0.1 bar)
    assert -d["pressure_offset_pa"] / d["pressure_gain_pa"] == pytest.approx(BENCH_OFFSET_V, abs=0.002)
    assert d["fit"]["motored"]["r2"] > 0.999
    path, _ = recording
    rc, out, err = run_cli(
        capsys,
        "calibrate",
        str(path),
        "--engine",
        "tue-single",
        "--wheel",
        "60-2",
        "--columns",
        "time,pressure_v,encoder_v",
        "--pressure-gain",
        "motored",
    )
    assert rc == 2 and out == "" and err.count("\n") == 1 and "no motored cycle" in err, err


def test_files_of_one_simulated_bench_read_as_one_wheel_and_one_calibration_reads_them_all(tmp_path, capsys):
    """Five files of one bench (one wheel with its tooth errors, its noise, speed and load
    differing from file to file), read with nothing but the file: every one as the same
    wheel; a calibration made on one (with its pressure) reads the other four."""
    files = [
        simulated_recording(tmp_path / f"bench{k}.txt", rpm=rpm, cycles=4, seed=k, noise_v=noise, imep_scale=scale)
        for k, (rpm, noise, scale) in enumerate(
            [(3000, 0.01, 1.0), (2600, 0.02, 0.6), (3300, 0.005, 1.0), (2900, 0.03, 0.8), (3100, 0.015, 0.9)]
        )
    ]
    wheels = set()
    for f in files:
        rc, out, err = run_cli(capsys, "analyze", str(f), "--json")
        assert rc == 0, err
        wheels.add(json.loads(out)["wheel"]["spec"])
    assert wheels == {"60-2"}
    cal = tmp_path / "cal.json"
    rc, _, err = run_cli(
        capsys,
        "calibrate",
        str(files[0]),
        "--engine",
        "tue-single",
        "--pressure-gain",
        str(BENCH_GAIN_PA_PER_V),
        "--output",
        str(cal),
    )
    assert rc == 0, err
    for f in files[1:]:
        rc, out, err = run_cli(
            capsys, "diagnose", str(f), "--engine", "tue-single", "--calibration", str(cal), "--json"
        )
        assert rc == 0, err
        assert json.loads(out)["cycles"]
