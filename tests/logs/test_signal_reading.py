"""Reading a wheel signal without guessing: the edge, the wheel and the repair budget chosen from
the signal and recorded with their evidence; a file read and its edges placed once per command."""

import numpy as np
import pytest
from conftest import SHARED_DATA

import rotor
import rotor.diagnostics.diagnosis
import rotor.logs.analysis
import rotor.logs.reader
import rotor.logs.recording
from rotor.cli import main
from rotor.errors import LogError
from rotor.logs.identify import FitStatus, find_wheel, fit_wheel
from rotor.logs.track import ChoiceSource, read_track

TUE = SHARED_DATA / "tue-4gb10"
ECU = SHARED_DATA / "ecu-triggers"
needs_tue = pytest.mark.skipif(not TUE.is_dir(), reason=f"shared data not found at {TUE}")
needs_ecu = pytest.mark.skipif(not ECU.is_dir(), reason=f"shared data not found at {ECU}")
TUE_COLUMNS = "time,pressure_v,encoder_v"
ECU_COLUMNS = "time,encoder_d,cam_d"


def _count(monkeypatch, module, name):
    """Wrap ``module.name`` so that its calls are counted; returns the list of calls."""
    calls = []
    original = getattr(module, name)

    def counted(*a, **k):
        calls.append(a[:1])
        return original(*a, **k)

    monkeypatch.setattr(module, name, counted)
    return calls


def test_diagnose_reads_and_places_the_file_once(tmp_path, monkeypatch):
    """diagnose with TDC from the speed reads the log at several TDCs: the file's text is read once and its
    edges found and placed on the wheel once."""
    log = rotor.simulated_recording(tmp_path / "sim.txt", cycles=4, seed=2)
    texts = _count(monkeypatch, rotor.logs.reader, "_read_text")
    placed = _count(monkeypatch, rotor.diagnostics.diagnosis, "read_wheel")
    tracks = _count(monkeypatch, rotor.logs.recording, "read_track")
    again = _count(monkeypatch, rotor.logs.analysis, "read_wheel")
    d = rotor.diagnose(rotor.load_engine("tue-single"), log, None, wheel="60-2", columns=TUE_COLUMNS, tdc_deg="speed")
    assert d.analysis is not None and d.analysis.cycles >= 3
    assert len(texts) == 1 and len(placed) == 1 and len(tracks) == 1 and len(again) == 0


def test_choices_recorded_with_evidence_and_pins(tmp_path):
    log = rotor.simulated_recording(tmp_path / "sim.txt", cycles=3, seed=1)
    a = rotor.analyze_log(log, "auto", columns=TUE_COLUMNS)
    r = a.reading
    assert r.wheel.spec == "60-2" and r.edge == "rising"
    assert r.choice("wheel").source is ChoiceSource.FOUND and "60-2" in r.choice("wheel").evidence
    assert r.choice("edge").source is ChoiceSource.FOUND
    assert r.pins() == "wheel='60-2', edge='rising'" and "read as wheel='60-2', edge='rising'" in a.summary()
    d = a.to_json_dict()["wheel"]["reading"]
    assert d["choices"]["wheel"]["source"] == "found" and d["pins"] == r.pins()
    assert all(f["status"] in ("fits", "repaired", "over_budget", "no_fit", "no_edges") for f in d["tried"])
    # the same signal negated (its two edges equally clean here: either may be taken, and says why), the same speed
    log2 = rotor.read_log(log, TUE_COLUMNS)
    neg = rotor.Log.from_arrays(time=log2["time"], encoder_v=-log2["encoder_v"])
    b = rotor.analyze_log(neg, "auto")
    assert b.reading.wheel.spec == "60-2" and b.reading.choice("edge").evidence
    assert np.mean(b.delta) == pytest.approx(np.mean(a.delta), rel=0.02)  # the other edge, as the bench files


def test_a_speed_column_that_is_not_a_speed_is_refused(tmp_path, capsys):
    """A pressure table (angle, normalised pressure) read as time,rpm: 'rpm' of a few units is refused."""
    p = tmp_path / "pressure.csv"
    ang = np.linspace(0, 720, 721)
    p.write_text("".join(f"{a:.1f};{1 + 14 * np.exp(-(((a - 368) / 20) ** 2)):.4f}\n" for a in ang))
    with pytest.raises(LogError, match="'rpm' column's median is .* rpm, outside 10"):
        rotor.analyze_log(p, columns="time,rpm")
    assert main(["analyze", str(p), "--columns", "time,rpm"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--columns" in err


def test_fit_budget_and_ranking_on_tooth_times():
    """A 60-2 wheel's edges with the edge after the gap 0.3 pitches late (a distorted neighbour): counted as
    60-2 (not 61-3), and a 36-1 or 60-1 wheel needs an edge inferred in every revolution: over budget."""
    pitch = 2 * np.pi / 60
    revs = 30
    ang = np.concatenate([r * 2 * np.pi + pitch * np.arange(58) for r in range(revs)])
    ang[::58] += 0.3 * pitch
    omega = 300.0 * (1 + 0.02 * np.sin(2 * ang))
    t = np.cumsum(np.concatenate([[0.0], np.diff(ang) / (0.5 * (omega[1:] + omega[:-1]))]))
    w, said = find_wheel(t)
    assert w.spec == "60-2" and "61-3" in said
    f = fit_wheel(t, "60-1")
    assert f.status in (FitStatus.OVER_BUDGET, FitStatus.NO_FIT) and not f.status.ok
    with pytest.raises(LogError, match="not this signal's wheel|does not fit|stop fitting"):
        read_track(rotor.Log.from_arrays(tooth_time_s=t), "60-1")


@needs_tue
@pytest.mark.parametrize("name", ["No_load.txt", "half_load.txt", "full_load.txt"])
def test_bench_files_read_as_60_2_by_auto(name):
    """--wheel auto names 60-2 on the bench files and gives the δ read with --wheel 60-2 within 1 %; the
    encoder negated reads, without an edge given, to the same δ within 2 %."""
    log = rotor.read_log(TUE / name, TUE_COLUMNS)
    auto = rotor.analyze_log(log, "auto")
    given = rotor.analyze_log(log, "60-2", edge="rising")
    assert auto.reading.wheel.spec == "60-2"
    assert np.mean(auto.delta) == pytest.approx(np.mean(given.delta), rel=0.01)
    neg = rotor.Log.from_arrays(time=log["time"], pressure_v=log["pressure_v"], encoder_v=-log["encoder_v"])
    b = rotor.analyze_log(neg, "auto")
    assert b.reading.wheel.spec == "60-2" and b.reading.edge == "falling"
    assert np.mean(b.delta) == pytest.approx(np.mean(given.delta), rel=0.02)


@needs_tue
def test_wrong_wheel_on_a_bench_file_exits_2(capsys):
    assert main(["analyze", str(TUE / "half_load.txt"), "--wheel", "36-1", "--columns", TUE_COLUMNS]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "36-1" in err


@needs_ecu
def test_captures_read_with_the_documented_wheels(capsys):
    a = rotor.analyze_log(ECU / "4b11-running.csv", "auto", columns=ECU_COLUMNS)
    assert a.reading.wheel.spec == "36-2-1" and a.reading.edge == "falling"  # the regular edges (its README)
    b = rotor.analyze_log(ECU / "6g75-withsparkplugs-cranking.csv", "auto", columns=ECU_COLUMNS)
    assert b.reading.wheel.spec == "36-2-1-1"
    c = rotor.analyze_log(ECU / "6g75-withsparkplugs-cranking.csv", "36-2-1-1", columns=ECU_COLUMNS)
    assert c.reading.edge == "falling" and c.reading.choice("edge").source is ChoiceSource.FOUND


@needs_ecu
@pytest.mark.parametrize("wheel", ["36-1", "36-2"])
@pytest.mark.parametrize("edge", [[], ["--edge", "falling"]])
def test_wrong_wheels_on_the_4b11_capture_exit_2(wheel, edge, capsys):
    argv = ["analyze", str(ECU / "4b11-running.csv"), "--wheel", wheel, "--columns", ECU_COLUMNS, *edge]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "36-2-1" in err  # names the wheel that fits


# ------------------------------------------------------------------ a simulated matrix of analog signals
PROFILES = {
    "steady": dict(rpm=2000.0, revolutions=14, ripple=0.04),
    "ignition_cut": dict(rpm=2000.0, revolutions=16, ripple=0.04),  # the speed drops 30 % in 3 revolutions
    "coast_down": dict(rpm=1500.0, revolutions=16, ripple=0.02),  # to a twentieth of its speed
}


def _matrix():
    """Every standard wheel with a covering rotation of sensor (VR: amplitude ∝ speed; Hall), the tooth after the
    gap (regular, weak, early, late) and the speed (steady, ignition cut, coast-down): 88 readings with the
    inverted ones."""
    from rotor.logs.identify import STANDARD_WHEELS

    combos = [
        (spec, sensor, gap, prof)
        for spec in STANDARD_WHEELS
        for sensor in ("vr", "hall")
        for gap in (None, "weak", "early", "late")
        for prof in PROFILES
    ]
    return combos[::5]


@pytest.mark.parametrize("spec,sensor,gap,profile", _matrix())
def test_simulated_signals_read_without_options(spec, sensor, gap, profile):
    """Each signal and its negation are read with wheel="auto" and no edge: the documented wheel, and within 1 %
    the δ read with that wheel and the documented edge given. The documented edge is the signal's own (a Hall
    tooth's leading edge, a variable-reluctance tooth's centre crossing), except where a Hall sensor's weak tooth
    is a narrow pulse, both of whose edges move (its leading edge late, its trailing edge early): there either
    edge is a documented reading, and the δ of the one rotor takes is compared."""
    from rotor.logs.synthetic import speed_profile, wheel_signal

    p = speed_profile(profile, **PROFILES[profile])
    deltas = []
    for inverted in (False, True):
        s = wheel_signal(p, spec, sensor=sensor, gap_tooth=gap, inverted=inverted, noise_v=0.02, tooth_error_deg=0.05)
        log = rotor.Log.from_arrays(time=s.t_s, encoder_v=s.v)
        a = rotor.analyze_log(log, "auto", firing=0, tdc_deg=0.0)
        assert a.reading.wheel.spec == spec
        documented = s.edge if not (sensor == "hall" and gap == "weak") else a.reading.edge
        given = rotor.analyze_log(log, spec, edge=documented, firing=0, tdc_deg=0.0)
        assert np.mean(a.delta) == pytest.approx(np.mean(given.delta), rel=0.01)
        deltas.append(np.mean(a.delta))
    assert deltas[1] == pytest.approx(deltas[0], rel=0.01)  # the same read inverted


def test_plot_of_the_reading(tmp_path, capsys):
    """--plot draws the signal as read beside the analysis: its levels, the edges taken and the repairs."""
    log = rotor.simulated_recording(tmp_path / "sim.txt", cycles=3, seed=4)
    assert main(["analyze", str(log), "--wheel", "auto", "--columns", TUE_COLUMNS, "--plot", str(tmp_path / "p")]) == 0
    out = capsys.readouterr().out
    assert (tmp_path / "p" / "sim_reading.png").stat().st_size > 10_000 and "sim_reading.png" in out
    a = rotor.analyze_log(log, "auto", columns=TUE_COLUMNS)
    ax = a.reading.plot()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(x.startswith("edges taken") for x in labels) and any(x.startswith("timed at") for x in labels)
    assert "wheel='60-2'" in ax.get_title()


def test_calibrate_reads_the_file_once(tmp_path, monkeypatch):
    log = rotor.simulated_recording(tmp_path / "sim.txt", cycles=3, seed=6)
    texts = _count(monkeypatch, rotor.logs.reader, "_read_text")
    cal = rotor.calibrate(rotor.load_engine("tue-single"), log, wheel="60-2", columns=TUE_COLUMNS)
    assert cal is not None and len(texts) == 1


@needs_ecu
def test_another_engine_on_a_capture_is_no_misfire_verdict(tmp_path):
    """The 4B11 capture (the first 25 cycles) diagnosed with the 4ChN15 diesel's file: the model does not fit it,
    and that is the verdict — not "the engine does not fire", not a list of misfires."""
    rows = (ECU / "4b11-running.csv").read_text().splitlines()
    part = tmp_path / "4b11-part.csv"
    part.write_text("\n".join(rows[:3500]) + "\n")
    d = rotor.diagnose(rotor.load_engine("4chn15"), part, None, wheel="36-2-1", columns=ECU_COLUMNS, tdc_deg=90.0)
    from rotor.diagnostics.diagnosis import DiagnosisVerdict

    assert d.verdict is DiagnosisVerdict.MODEL_DOES_NOT_FIT
    assert not d.no_firing and not d.misfire.any() and d.misfires() == []
    text = d.summary()
    assert "does not fit this recording" in text and "does not fire" not in text
    assert d.to_json_dict()["verdict"] == "model_does_not_fit"


def test_a_wheel_in_another_column_is_named(tmp_path, capsys):
    """The columns given in the wrong order: the refusal says which column reads as the wheel."""
    log = rotor.simulated_recording(tmp_path / "sim.txt", cycles=3, seed=7)
    for wheel in ("60-2", "auto"):
        assert main(["analyze", str(log), "--wheel", wheel, "--columns", "time,encoder_v,pressure_v"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "'pressure_v' reads as the 60-2 wheel" in err and "--columns" in err


def test_a_calibration_of_another_wheel_is_named_by_its_origin(tmp_path, capsys):
    """tue-single's preset calibration holds a 60-2 wheel's tooth errors: a 36-2-1 log diagnosed with it is refused
    in one line that says the errors are the preset's own calibration's, and how to go without it."""
    from rotor.logs.synthetic import speed_profile, wheel_signal, write_log

    s = wheel_signal(speed_profile("steady", rpm=3000.0, revolutions=30, ripple=0.05), "36-2-1", sensor="hall")
    write_log(tmp_path / "w.txt", s)
    assert main(["diagnose", str(tmp_path / "w.txt"), "--engine", "tue-single", "--wheel", "36-2-1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the preset's own calibration" in err and "60-2" in err
    assert "--no-calibration" in err


@needs_ecu
def test_a_capture_whose_channels_are_swapped_names_the_crank(capsys):
    argv = ["analyze", str(ECU / "4b11-running.csv"), "--wheel", "36-2-1", "--columns", "time,cam_d,encoder_d"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'cam_d' reads as the 36-2-1 wheel" in err and "--columns" in err
