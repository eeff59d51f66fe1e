"""Calibration from a recording with a pressure channel (rotor.calibrate), its JSON file,
and the real-data check: calibrate on one tue-4gb10 recording, identify the IMEP of the
other two from their crank speed alone, compare with the IMEP of their own pressure.

Tolerances (measured figures in brackets, `benchmarks/diagnose_real.py` for the real data):
- simulated round trip (tue-single at 3000 rpm, 8 cycles, exact speed, a pressure signal
  with gain 50 bar/unit and offset −29 bar): energy-balance inertia within 0.5 % (0.10 %),
  pressure offset within 2000 Pa (100 Pa), friction + load within 0.5 % (0.15 %), gain from
  the engine file's IMEP within 0.5 % (0.16 %), identification inertia within 0.5 %
  (0.12 %). The few 0.1 % are the 0.5° binning of the pressure signal (midpoint rule).
- real data, speed only: half load mean IMEP error within 0.10 bar (measured −0.058 bar,
  −1.9 %), rms over the cycles 0.12 bar (0.082); no load within 0.25 bar (−0.189 bar,
  −17 % of 1.11 bar: the engine file's full-load Wiebe shape is furthest from a throttled
  idle cycle), rms 0.25 bar (0.194).
"""

import json

import equinox as eqx
import numpy as np
import pytest
from conftest import SHARED_DATA

import rotor
from rotor.logs.analysis import LogAnalysis, PhaseSource
from rotor.units import RPM_PER_RAD_S

TUE = SHARED_DATA / "tue-4gb10"
needs_data = pytest.mark.skipif(not TUE.is_dir(), reason=f"shared data not found at {TUE}")
README_GAIN = 1e5 / (5 * 0.00385)  # Pa per volt: the bench's own scripts (data README)
J_TRUE = 0.0172
GAIN, OFFSET = 5.0e6, -29.0e5


def _engine(J=J_TRUE):
    return eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, rotor.load_engine("tue-single"), J)


@pytest.fixture(scope="module")
def simulated():
    """A simulated run of tue-single at its steady state with a constant load, and a
    pressure channel (gain GAIN, offset OFFSET) on a 0.2° grid, as a LogAnalysis."""
    eng = _engine()
    ss = rotor.steady_state(eng, rpm=3000)
    load = float(ss.load_torque_Nm)
    run = rotor.simulate(eng, rpm=float(ss.omega[0]) * RPM_PER_RAD_S, cycles=8, load=rotor.ConstantLoad(load))
    C, Pn = run.uniform_cycles, run.points_per_cycle
    omega = np.asarray(run.omega)[: C * Pn].reshape(C, Pn)[:, :: max(1, Pn // 240)]
    cyc = float(eng.cycle_rad)
    phi = np.arange(0, cyc, np.deg2rad(0.2))
    sig = (np.asarray(eng.pressure(phi, eng.geometry, 4)) - OFFSET) / GAIN
    z = np.zeros((C, 1))
    a = LogAnalysis(
        source="simulated",
        kind="teeth",
        strokes=4,
        cycle_rad=cyc,
        order=np.array([0.5]),
        t_start_s=np.asarray(run.t)[: C * Pn : Pn],
        mean_omega=omega.mean(1),
        delta=np.zeros(C),
        amplitude_rad_s=z,
        phase_rad=z,
        omega=omega,
        cycle_start_rad=np.arange(C) * cyc,
        tdc_rad=0.0,
        tdc_method="given",
        firing_parity=0,
        firing_method="given",
        tdc_source=PhaseSource.GIVEN,
        firing_source=PhaseSource.GIVEN,
        max_order=12.0,
        pressure=(np.tile(phi, C), np.tile(sig, C), np.repeat(np.arange(C), phi.size)),
    )
    return a, load


def test_simulated_round_trip(simulated):
    a, load = simulated
    cal = rotor.calibrate(_engine(0.01), a, pressure_gain=GAIN)  # the file's inertia is not used
    assert cal.fit["energy_balance_inertia_kgm2"] == pytest.approx(J_TRUE, rel=5e-3)
    assert cal.inertia_kgm2 == pytest.approx(J_TRUE, rel=5e-3)
    assert cal.pressure_offset_pa == pytest.approx(OFFSET, abs=2000)
    assert cal.loss_torque_Nm == pytest.approx(load, rel=5e-3)
    assert cal.fit["energy_balance_r2"] > 0.9999
    # the gain from the engine file's IMEP (the simulation's pressure is the file's)
    cal2 = rotor.calibrate(_engine(), a, refine=False)
    assert cal2.pressure_gain_pa == pytest.approx(GAIN, rel=5e-3)
    assert cal2.inertia_kgm2 == pytest.approx(J_TRUE, rel=5e-3)


def test_refused_input(simulated):
    a, _ = simulated
    with pytest.raises(rotor.EngineError, match="cylinders"):
        rotor.calibrate(rotor.load_engine("4chn15"), a)
    with pytest.raises(rotor.EngineError, match="pressure_gain"):
        rotor.calibrate(_engine(), a, pressure_gain=-1.0)
    with pytest.raises(rotor.EngineError, match="scaling"):
        rotor.calibrate(_engine(), a, scaling="diesel")
    import dataclasses

    with pytest.raises(rotor.EngineError, match="no pressure channel"):
        rotor.calibrate(_engine(), dataclasses.replace(a, pressure=None))


def _calibration(**kw):
    te = rotor.ToothErrors(wheel="60-2", errors_rad=np.linspace(-1e-3, 1e-3, 58))
    d = dict(
        engine="e",
        inertia_kgm2=0.016,
        tdc_after_gap_deg=29.4,
        pressure_gain_pa=5e6,
        pressure_offset_pa=-3e6,
        loss_torque_Nm=8.0,
        scaling="charge",
        charge_scale=0.98,
        wheel="60-2",
        tooth_errors=te,
        source="x",
        fit={"energy_balance_inertia_kgm2": 0.0172, "cycles": 11, "list": [1.0, 2.0]},
    )
    d.update(kw)
    return rotor.Calibration(**d)


def test_json_round_trip(tmp_path):
    cal = _calibration()
    p = tmp_path / "cal.json"
    cal.save(p)
    back = rotor.Calibration.load(p)
    for k in (
        "engine",
        "inertia_kgm2",
        "tdc_after_gap_deg",
        "pressure_gain_pa",
        "pressure_offset_pa",
        "loss_torque_Nm",
        "scaling",
        "charge_scale",
        "wheel",
        "source",
        "fit",
    ):
        assert getattr(back, k) == getattr(cal, k), k
    np.testing.assert_allclose(back.tooth_errors.errors_rad, cal.tooth_errors.errors_rad, rtol=0, atol=1e-15)
    eng = back.apply(rotor.load_engine("tue-single"))
    assert float(eng.crankshaft.inertia_kgm2) == 0.016
    # no tooth errors
    _calibration(tooth_errors=None).save(p)
    assert rotor.Calibration.load(p).tooth_errors is None


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: d.pop("inertia_kgm2"), "missing key 'inertia_kgm2'"),
        (lambda d: d.update(inertia_kgm2=-1), "key 'inertia_kgm2' = -1: must be a positive"),
        (lambda d: d.update(tdc_after_gap_deg="29"), "key 'tdc_after_gap_deg'"),
        (lambda d: d.update(format="rotor-engine"), "key 'format'"),
        (lambda d: d.update(version=7), "key 'version'"),
        (lambda d: d.update(scaling="diesel"), "key 'scaling'"),
        (lambda d: d.update(tooth_errors={"wheel": "60-2", "errors_rad": [0.0] * 3}), "tooth_errors"),
        (lambda d: d.update(tooth_errors=[1, 2]), "key 'tooth_errors'"),
        (lambda d: d.update(fit=3), "key 'fit'"),
    ],
)
def test_malformed_file_names_the_key(tmp_path, change, message):
    d = _calibration().to_json_dict()
    change(d)
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(d))
    with pytest.raises(rotor.EngineError, match=message) as e:
        rotor.Calibration.load(p)
    assert str(p) in str(e.value) and "\n" not in str(e.value)


def test_not_json(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text("{inertia: 1")
    with pytest.raises(rotor.EngineError, match="not a calibration file"):
        rotor.Calibration.load(p)
    p.write_text("[1, 2]")
    with pytest.raises(rotor.EngineError, match="JSON object"):
        rotor.Calibration.load(p)


@pytest.fixture(scope="module")
def real_calibration():
    if not TUE.is_dir():
        pytest.skip(f"shared data not found at {TUE}")
    return rotor.calibrate(
        rotor.load_engine("tue-single"),
        TUE / "full_load.txt",
        wheel="60-2",
        columns="time,pressure_v,encoder_v",
        pressure_gain=README_GAIN,
    )


@needs_data
def test_real_calibration_is_physical(real_calibration):
    cal = real_calibration
    assert 0.013 < cal.fit["energy_balance_inertia_kgm2"] < 0.020  # the preset's estimate range, 0.013…0.018
    assert 0.013 < cal.inertia_kgm2 < 0.020
    assert abs(cal.tdc_after_gap_deg - 28.9) < 2.0  # benchmarks/calibrate_presets.py
    assert cal.fit["energy_balance_r2"] > 0.99
    assert cal.loss_torque_Nm == pytest.approx(cal.fit["imep_measured_pa"] * 1.98e-4 / (4 * np.pi), rel=0.05)
    assert abs(cal.fit["identified_imep_mismatch"]) < 1e-3
    # the losses carry the indicated work at a steady speed: their mean pressure is the IMEP (within 1 %)
    assert cal.fit["loss_mep_pa"] == pytest.approx(cal.fit["imep_measured_pa"], rel=0.01)


@needs_data
@pytest.mark.parametrize("name, mean_tol, rms_tol", [("half_load", 0.10e5, 0.12e5), ("No_load", 0.25e5, 0.25e5)])
def test_real_imep_from_speed_alone(real_calibration, name, mean_tol, rms_tol):
    eng = rotor.load_engine("tue-single")
    cal = real_calibration
    ident = rotor.diagnose(eng, TUE / f"{name}.txt", cal, columns="time,-,encoder_v")
    assert ident.analysis.pressure is None  # speed alone
    assert ident.analysis.tdc_method == "given"
    pressure = rotor.analyze_log(
        TUE / f"{name}.txt",
        "60-2",
        columns="time,pressure_v,encoder_v",
        tdc_deg=cal.tdc_after_gap_deg,
        tooth_errors=cal.tooth_errors,
    )
    np.testing.assert_allclose(pressure.t_start_s, ident.t_start_s, atol=1e-9)  # the same cycles
    measured = rotor.measured_imep(eng, pressure, cal.pressure_gain_pa)
    err = ident.imep_pa[:, 0] - measured
    assert abs(np.mean(err)) < mean_tol
    assert np.sqrt(np.mean(err**2)) < rms_tol
    assert not ident.misfire.any()


def test_engine_identity_is_stored_and_checked(tmp_path):
    """A calibration stores the engine's cylinders, strokes and geometry and refuses another engine; an
    older file without them is checked by the name alone."""
    eng = rotor.load_engine("tue-single")
    d = _calibration().to_json_dict()
    d.update(
        engine=eng.name,
        cylinders=1,
        strokes=4,
        geometry={k: float(getattr(eng.geometry, k)) for k in ("bore_m", "stroke_m", "rod_length_m")},
    )
    cal = rotor.Calibration.from_json_dict(d)
    cal.check_engine(eng)
    p = tmp_path / "c.json"
    cal.save(p)
    assert rotor.Calibration.load(p).geometry == cal.geometry and rotor.Calibration.load(p).cylinders == 1
    with pytest.raises(rotor.EngineError, match="another engine .*MWM"):
        cal.check_engine(rotor.load_engine("mwm6"))
    with pytest.raises(rotor.EngineError, match="bore_m"):
        cal.check_engine(eqx.tree_at(lambda e: e.geometry.bore_m, eng, 0.07))
    old = {k: v for k, v in d.items() if k not in ("cylinders", "strokes", "geometry")}
    cal_old = rotor.Calibration.from_json_dict(old)
    assert cal_old.cylinders == 0 and cal_old.geometry == {}
    cal_old.check_engine(eng)
    with pytest.raises(rotor.EngineError, match="geometry"):
        rotor.Calibration.from_json_dict({**d, "geometry": {"bore_m": "wide"}})
    with pytest.raises(rotor.EngineError, match="cylinders"):
        rotor.Calibration.from_json_dict({**d, "cylinders": -1})


def test_a_calibration_with_no_angle_for_tdc_is_refused_by_itself(tmp_path, capsys):
    from importlib import resources

    from conftest import run_cli

    d = json.loads((resources.files("rotor.presets") / "tue-single.calibration.json").read_text())
    d["tdc_after_gap_deg"] = 1e300
    (tmp_path / "cal.json").write_text(json.dumps(d))
    log = rotor.simulated_recording(tmp_path / "sim.txt", "tue-single", cycles=4, seed=1)
    rc, _, err = run_cli(
        capsys, "diagnose", str(log), "--engine", "tue-single", "--calibration", str(tmp_path / "cal.json")
    )
    assert rc == 2 and "calibration tdc_after_gap_deg = 1e+300" in err and "sim.txt" not in err


def test_a_calibration_of_another_wheel_is_named_as_the_cause(tmp_path, capsys):
    from importlib import resources

    from conftest import run_cli

    d = json.loads((resources.files("rotor.presets") / "tue-single.calibration.json").read_text())
    d["wheel"] = "36-1"
    d.pop("tooth_errors", None)
    (tmp_path / "cal.json").write_text(json.dumps(d))
    log = rotor.simulated_recording(tmp_path / "sim.txt", "tue-single", cycles=4, seed=1)
    rc, _, err = run_cli(
        capsys, "diagnose", str(log), "--engine", "tue-single", "--calibration", str(tmp_path / "cal.json")
    )
    assert rc == 2 and "was made on a 36-1 wheel, which this log's edges do not fit" in err
