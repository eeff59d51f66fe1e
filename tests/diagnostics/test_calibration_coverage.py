"""The calibration format's version 2 (the wheel reading, the speed TDC's bias, the recordings
and the loads and speeds they cover), a calibration from several recordings, the TDC check
less the bias its load gives, and a diagnosis outside the calibration's coverage."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import SHARED_DATA

import rotor
from rotor.diagnostics.calibration_record import CALIBRATION_VERSION, COVERAGE_IMEP_MARGIN
from rotor.diagnostics.phase import KAPPA_REL, TdcBias, TdcVerdict, check_tdc, tdc_bias_of, tdc_from_speed

TUE = SHARED_DATA / "tue-4gb10"
GAIN = 1e5 / (5 * 0.00385)  # the data README's sensor gain [Pa/V]
needs_data = pytest.mark.skipif(not TUE.is_dir(), reason=f"shared data not found at {TUE}")
ENGINE = rotor.load_engine("tue-single")


def _record(**kw):
    cal = rotor.Calibration(
        engine=ENGINE.name,
        inertia_kgm2=0.016,
        tdc_after_gap_deg=29.4,
        pressure_gain_pa=5.2e6,
        pressure_offset_pa=-3e6,
        loss_torque_Nm=8.0,
        **kw,
    )
    return cal


def test_version_2_round_trip_and_version_1_still_read(tmp_path):
    recs = (
        {"source": "a.txt", "mean_rpm": 2990.0, "imep_measured_pa": 5.0e5},
        {"source": "b.txt", "mean_rpm": 3100.0, "imep_measured_pa": 2.9e5},
    )
    cal = _record(reading={"edge": "rising"}, tdc_bias=TdcBias(2.4, 0.36, 2), recordings=recs)
    p = tmp_path / "cal.json"
    cal.save(p)
    d = json.loads(p.read_text())
    assert d["version"] == CALIBRATION_VERSION == 2
    assert d["coverage"] == {"rpm": [2990.0, 3100.0], "imep_pa": [2.9e5, 5.0e5], "recordings": 2}
    back = rotor.Calibration.load(p)
    assert back.reading == {"edge": "rising"} and back.tdc_bias == TdcBias(2.4, 0.36, 2)
    assert back.recordings == recs and back.coverage() == cal.coverage()
    for key in ("reading", "tdc_bias", "recordings", "coverage"):
        d.pop(key)
    d["version"] = 1
    p.write_text(json.dumps(d))
    old = rotor.Calibration.load(p)
    assert old.reading is None and old.tdc_bias is None and old.recordings == () and old.coverage() is None
    assert old.outside(9000.0, 1e7) == ""  # a version-1 file states no coverage: nothing said outside it
    d["version"] = 3
    p.write_text(json.dumps(d))
    with pytest.raises(rotor.EngineError, match="key 'version' = 3: this rotor reads versions 1, 2"):
        rotor.Calibration.load(p)


@pytest.mark.parametrize(
    "key, value, message",
    [
        ("reading", 3, "key 'reading'"),
        ("tdc_bias", {"kappa": "x"}, "key 'tdc_bias'"),
        ("recordings", [1], "recordings"),
    ],
)
def test_malformed_version_2_keys_are_named(tmp_path, key, value, message):
    d = _record().to_json_dict()
    d[key] = value
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(d))
    with pytest.raises(rotor.EngineError, match=message):
        rotor.Calibration.load(p)


def test_outside_names_the_speed_and_the_load():
    cal = _record(recordings=({"mean_rpm": 3000.0, "imep_measured_pa": 5.0e5},))
    assert cal.outside(3100.0, 4.5e5) == ""
    assert "1500 rpm" in cal.outside(1500.0, 5.0e5)
    low = 5.0e5 * (1 - COVERAGE_IMEP_MARGIN) * 0.99
    assert "IMEP" in cal.outside(3000.0, low) and "calibrate on a recording" in cal.outside(3000.0, low)


def test_the_bias_factor_from_the_recordings():
    one = tdc_bias_of([(6.8, 2.8)])
    assert one.kappa == pytest.approx(6.8 / 2.8) and one.kappa_std == pytest.approx(KAPPA_REL * one.kappa)
    three = tdc_bias_of([(6.8, 2.8), (11.3, 4.3), (18.0, 7.6)])
    ks = [6.8 / 2.8, 11.3 / 4.3, 18.0 / 7.6]
    assert three.kappa == pytest.approx(np.mean(ks)) and three.recordings == 3
    assert three.kappa_std == pytest.approx(max(np.std(ks, ddof=1), KAPPA_REL * np.mean(ks)))
    assert tdc_bias_of([(3.0, 0.0)]) is None


@pytest.fixture(scope="module")
def full_load_calibration():
    if not TUE.is_dir():
        pytest.skip(f"shared data not found at {TUE}")
    return rotor.calibrate(
        ENGINE, TUE / "full_load.txt", wheel="60-2", columns="time,pressure_v,encoder_v", pressure_gain=GAIN
    )


def _pressure_tdc(name):
    a = rotor.analyze_log(
        TUE / f"{name}.txt", "60-2", columns="time,pressure_v,encoder_v", compression_ratio=8.5, rod_ratio=27.5 / 84.2
    )
    return float(np.rad2deg(a.tdc_rad))


@needs_data
def test_a_calibration_states_its_recording_and_bias(full_load_calibration):
    cal = full_load_calibration
    (rec,) = cal.recordings
    assert rec["imep_measured_pa"] == pytest.approx(cal.fit["imep_measured_pa"])
    assert 2900 < rec["mean_rpm"] < 3100 and rec["pumping_mep_pa"] < 0  # the gas exchange takes work
    assert 5.0 < rec["speed_tdc_bias_deg"] < 9.0  # the speed puts TDC late at full load (module doc of phase)
    assert cal.tdc_bias is not None and cal.tdc_bias.kappa > 0
    assert cal.reading is not None  # how the wheel was read, stored


@needs_data
@pytest.mark.parametrize("name", ["full_load", "half_load", "No_load"])
def test_the_tdc_check_is_honest_at_every_load(full_load_calibration, name):
    """Calibrated at full load, each recording's speed: the speed's TDC less the bias its load
    gives lies within 2.5° of that recording's pressure TDC (it lay 7–19° away without the bias),
    within the check's 3σ, and the calibration's TDC agrees at a distance of at most 3°: never
    "agrees" 17° apart, never corrected to the speed's."""
    cal = full_load_calibration
    truth = _pressure_tdc(name)
    a = rotor.analyze_log(TUE / f"{name}.txt", "60-2", columns="time,-,encoder_v", tdc_deg=cal.tdc_after_gap_deg)
    chk = check_tdc(tdc_from_speed(cal.apply(ENGINE), a), cal.tdc_after_gap_deg, bias=cal.tdc_bias)
    less_bias = chk.fit.tdc_after_gap_deg - chk.bias_deg
    err = (less_bias - truth + 180.0) % 360.0 - 180.0
    assert abs(err) < 2.5 and abs(err) <= 3.0 * chk.std_deg, (err, chk.std_deg)
    assert chk.verdict is TdcVerdict.AGREES and chk.used_deg == cal.tdc_after_gap_deg
    dist = abs((less_bias - cal.tdc_after_gap_deg + 180.0) % 360.0 - 180.0)
    assert dist < 3.0 and chk.distance_sigma == pytest.approx(dist / chk.std_deg, rel=1e-6)
    assert f"{dist:.1f}° apart" in chk.message
    assert chk.std_deg < 3.5  # the bias modelled, what is left of the model's error is small
    j = chk.to_json_dict()
    assert j["bias_deg"] == pytest.approx(chk.bias_deg) and j["compared_std_deg"] == pytest.approx(chk.std_deg)


@needs_data
def test_a_wrong_tdc_is_still_corrected(full_load_calibration):
    """The bias does not hide a gross error: a calibration's TDC 30° off disagrees and is
    replaced by the speed's less the bias, within 2.5° of the pressure's."""
    import dataclasses

    cal = dataclasses.replace(full_load_calibration, tdc_after_gap_deg=full_load_calibration.tdc_after_gap_deg + 30.0)
    d = rotor.diagnose(ENGINE, TUE / "half_load.txt", cal, columns="time,-,encoder_v")
    assert d.tdc_check.verdict is TdcVerdict.DISAGREES
    used = float(np.rad2deg(d.analysis.tdc_rad))
    assert abs((used - _pressure_tdc("half_load") + 180.0) % 360.0 - 180.0) < 2.5


@needs_data
def test_outside_the_calibration_says_so_in_the_json(full_load_calibration):
    """No load read with a full-load calibration lies outside the loads it covers: the text, the
    warnings and the JSON say so (``supported: false`` with the reason), every cycle flagged; the
    JSON's per-cylinder IMEP is the table's, and its mean speed the time mean."""
    d = rotor.diagnose(ENGINE, TUE / "No_load.txt", full_load_calibration, columns="time,-,encoder_v")
    assert d.coverage and "outside what the calibration covers" in d.coverage
    j = d.to_json_dict()
    assert j["supported"] is False and j["unsupported_reason"] == d.coverage
    assert all(not c["supported"] for c in j["cycles"])
    assert d.coverage in d.warnings and "not supported" in d.summary()
    ok = d.identification.identified[:, 0] & ~d.misfire[:, 0]
    assert j["cylinder_imep_pa"][0] == pytest.approx(float(np.mean(d.imep_pa[ok, 0])))
    assert f"{j['cylinder_imep_pa'][0] / 1e5:15.3f}" in d.summary()
    periods = np.diff(d.t_start_s)
    time_mean = 720.0 / 360.0 * 60.0 / periods  # rpm over each whole cycle but the last
    np.testing.assert_allclose([c["mean_rpm"] for c in j["cycles"]][:-1], time_mean, rtol=2e-3)
    inside = rotor.diagnose(ENGINE, TUE / "full_load.txt", full_load_calibration, columns="time,-,encoder_v")
    assert inside.coverage == "" and inside.to_json_dict()["supported"] is True


@needs_data
def test_a_calibration_from_several_recordings_covers_their_loads():
    cal = rotor.calibrate(
        ENGINE,
        [TUE / "full_load.txt", TUE / "No_load.txt"],
        wheel="60-2",
        columns="time,pressure_v,encoder_v",
        pressure_gain=GAIN,
    )
    cov = cal.coverage()
    assert cov["recordings"] == 2 and cov["imep_pa"][0] < 1.3e5 < 4.5e5 < cov["imep_pa"][1]
    assert cal.tdc_bias.recordings == 2
    truths = [_pressure_tdc("full_load"), _pressure_tdc("No_load")]
    assert min(truths) - 0.1 <= cal.tdc_after_gap_deg <= max(truths) + 0.1
    d = rotor.diagnose(ENGINE, TUE / "half_load.txt", cal, columns="time,-,encoder_v")
    assert d.coverage == "" and d.tdc_check.verdict is TdcVerdict.AGREES
    assert abs(float(np.rad2deg(d.analysis.tdc_rad)) - _pressure_tdc("half_load")) < 2.0


def test_a_transient_without_a_steady_state_keeps_the_calibration_tdc(tmp_path, monkeypatch):
    """Where the engine has no steady state at the record's mean speed (a cranking, a coast-down
    to a stop: the kinetic energy would reach zero in the compression), the speed has no
    signature to check TDC with: the calibration's is kept, unchecked, a note says why, and the
    record is diagnosed (it was an error); TDC from the speed alone is refused by name."""
    import rotor.diagnostics.phase as phase
    from rotor.diagnostics.synthetic import simulated_recording

    path = simulated_recording(tmp_path / "sim.txt", cycles=4)

    def stalls(*a, **k):
        raise rotor.errors.NoSteadyStateError("no steady state at 400 rpm: the kinetic energy would reach zero")

    monkeypatch.setattr(phase, "_charge_fit", stalls)
    d = rotor.diagnose(ENGINE, path, "preset", columns="time,-,encoder_v")
    assert d.tdc_check is None and float(np.rad2deg(d.analysis.tdc_rad)) == pytest.approx(29.4, abs=0.01)
    assert any("kept unchecked: the engine has no steady state" in n for n in d.notes)
    with pytest.raises(phase.NoSignature, match="no steady state at the record's mean speed"):
        rotor.diagnose(ENGINE, path, "preset", columns="time,-,encoder_v", tdc_deg="speed")


def test_rotor_calibrate_takes_several_logs(tmp_path, capsys):
    """``rotor calibrate A B``: one calibration of both recordings (full and about half load),
    stating each and the IMEPs they cover; diagnosed in between, supported."""
    from rotor.cli import main
    from rotor.diagnostics.synthetic import BENCH_GAIN_PA_PER_V, simulated_recording

    logs = [str(simulated_recording(tmp_path / f"{s}.txt", imep_scale=s, cycles=6)) for s in (1.0, 0.6)]
    out = tmp_path / "cal.json"
    argv = ["calibrate", *logs, "--engine", "tue-single", "--wheel", "60-2", "--columns", "time,pressure_v,encoder_v"]
    assert main([*argv, "--pressure-gain", str(BENCH_GAIN_PA_PER_V), "--output", str(out), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["coverage"]["recordings"] == 2 and len(d["recordings"]) == 2
    lo, hi = d["coverage"]["imep_pa"]
    assert hi > 1.5 * lo
    cal = rotor.Calibration.load(out)
    mid = simulated_recording(tmp_path / "mid.txt", imep_scale=0.8, cycles=6)
    diag = rotor.diagnose(ENGINE, mid, cal, columns="time,-,encoder_v")
    assert diag.coverage == "" and diag.to_json_dict()["supported"] is True
