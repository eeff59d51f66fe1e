"""rotor diagnose: the command line over rotor.calibrate / rotor.diagnose (in-process),
its JSON, its one-line errors and its plot; plotting.plot_identification."""

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_DATA, run_cli

import rotor
from rotor.cli import main
from rotor.units import PA_PER_BAR, RPM_PER_RAD_S

TUE = SHARED_DATA / "tue-4gb10"
needs_data = pytest.mark.skipif(not TUE.is_dir(), reason=f"shared data not found at {TUE}")
GAIN = str(PA_PER_BAR / (5 * 0.00385))


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """Calibrate on full_load.txt through the CLI: (calibration path, JSON, plot folder)."""
    if not TUE.is_dir():
        pytest.skip(f"shared data not found at {TUE}")
    folder = tmp_path_factory.mktemp("diagnose")
    cal = folder / "tue.json"
    plots = folder / "plots"
    rc = main(
        [
            "diagnose",
            str(TUE / "full_load.txt"),
            "--engine",
            "tue-single",
            "--wheel",
            "60-2",
            "--columns",
            "time,pressure_v,encoder_v",
            "--save-calibration",
            str(cal),
            "--pressure-gain",
            GAIN,
            "--json",
            "--plot",
            str(plots),
        ]
    )
    assert rc == 0
    return cal, plots


@needs_data
def test_calibrate_and_diagnose_json(saved, capsys):
    cal, plots = saved
    assert (plots / "full_load_diagnosis.png").stat().st_size > 10_000
    c = rotor.Calibration.load(cal)
    assert c.wheel == "60-2" and c.tooth_errors is not None and c.source == "full_load.txt"
    # speed only, with the saved calibration (the pressure column skipped)
    rc, out, err = run_cli(
        capsys,
        "diagnose",
        str(TUE / "full_load.txt"),
        "--engine",
        "tue-single",
        "--columns",
        "time,-,encoder_v",
        "--calibration",
        str(cal),
        "--json",
    )
    assert rc == 0, err
    d = json.loads(out)
    assert len(d["cycles"]) == 11 and d["cylinders"] == 1
    for row in d["cycles"]:
        assert set(row) >= {"t_start_s", "mean_rpm", "imep_pa", "misfire"}
        assert len(row["imep_pa"]) == 1 and len(row["misfire"]) == 1 and row["misfire"] == [False]
        assert 2900 < row["mean_rpm"] < 3100 and 4.4e5 < row["imep_pa"][0] < 5.8e5
        assert "measured_imep_pa" not in row  # no pressure channel read
    assert d["calibration"]["inertia_kgm2"] == pytest.approx(c.inertia_kgm2)
    assert d["tdc_method"] == "given" and d["scaling"] == "charge"
    # the calibration recording's own mean IMEP comes back (the identification inertia's definition)
    mean = np.mean([r["imep_pa"][0] for r in d["cycles"]])
    assert mean == pytest.approx(c.fit["imep_measured_pa"], rel=2e-3)


@needs_data
def test_text_output_compares_with_the_pressure(saved, capsys):
    cal, _ = saved
    rc, out, err = run_cli(
        capsys,
        "diagnose",
        str(TUE / "full_load.txt"),
        "--engine",
        "tue-single",
        "--columns",
        "time,pressure_v,encoder_v",
        "--calibration",
        str(cal),
    )
    assert rc == 0, err
    assert "IMEP from the pressure channel" in out and "identified − measured" in out


@needs_data
def test_speed_only_needs_tdc(capsys):
    rc, out, err = run_cli(
        capsys,
        "diagnose",
        str(TUE / "No_load.txt"),
        "--engine",
        "tue-single",
        "--wheel",
        "60-2",
        "--columns",
        "time,-,encoder_v",
        "--no-calibration",
        "--json",
    )
    assert rc == 2 and out == ""
    assert err.count("\n") == 1 and "TDC is not known" in err


def test_one_line_errors(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "rotor-calibration", "version": 1, "inertia_kgm2": "big"}')
    log = tmp_path / "log.csv"
    log.write_text("0.0\n")
    cases = [
        (["diagnose", str(log)], "--engine"),
        (["diagnose", str(log), "--engine", "tue-single", "--calibration", str(bad)], "inertia_kgm2"),
        (["diagnose", str(log), "--engine", "tue-single", "--calibration", str(tmp_path / "none.json")], "none.json"),
        (["diagnose", str(log), "--engine", "no-such-engine"], "no-such-engine"),
        (
            ["diagnose", str(log), "--engine", "tue-single", "--save-calibration", str(tmp_path / "x" / "c.json")],
            "no folder",
        ),
    ]
    for argv, needle in cases:
        rc, out, err = run_cli(capsys, *argv)
        assert rc == 2, argv
        assert err.count("\n") == 1 and needle in err, (argv, err)


def test_plot_identification(tmp_path):
    """The plot from a plain identify (simulated, direct speed): three panels, the identified
    engine's cylinder torques, misfires marked."""
    import matplotlib

    matplotlib.use("Agg")
    eng = rotor.load_engine("tue-single")
    ss = rotor.steady_state(eng)
    load = rotor.ConstantLoad(float(ss.load_torque_Nm))
    pattern = rotor.combustion_pattern(6, 1, misfires=[(4, 1)])
    run = rotor.simulate(eng, rpm=float(ss.omega[0]) * RPM_PER_RAD_S, cycles=6, load=load, combustion=pattern)
    ident = rotor.identify(eng, run)
    assert ident.misfires() == [(4, 1)]  # cycles count from 1, as planted
    axes = ident.plot()
    assert len(axes) == 3 and "1 misfire" in axes[2].get_title()
    assert "per cylinder" in axes[1].get_title()
    torque = ident.cylinder_torques()
    assert torque.shape == (ident.cycles, ident.omega.shape[1], 1)
    from rotor.plotting import save_figure

    save_figure(axes, tmp_path / "ident.png")
    assert (tmp_path / "ident.png").stat().st_size > 10_000


# ----------------------------------------------------------------------------- the preset's calibration, coast-down, failures
PRESET_CAL = str(Path(rotor.__file__).parent / "presets" / "tue-single.calibration.json")


def _tue_coast_teeth(tmp_path):
    """A tue-single coast-down (no firing, 12 cycles from 3000 rpm against half the full-load torque), as the
    tooth times of a 60-2 wheel whose gap lies 29.4° before TDC (20 ns jitter): (file, simulated run)."""
    from scipy.interpolate import CubicSpline

    from rotor.logs.wheel import TWO_PI

    w, gap = rotor.Wheel(60, 2), np.deg2rad(-29.4)
    e = rotor.Calibration.load(PRESET_CAL).apply(rotor.load_engine("tue-single"))
    load = 0.5 * float(rotor.steady_state(e, rpm=3000).load_torque_Nm)
    res = rotor.simulate(
        e,
        rpm=3000,
        cycles=12,
        load=rotor.ConstantLoad(load),
        step_deg=0.5,
        combustion=np.zeros((12, 1)),
        progress=False,
    )
    th, t = np.asarray(res.theta), np.asarray(res.t)
    r0, r1 = int(np.floor((th[0] - gap) / TWO_PI)) - 1, int(np.ceil((th[-1] - gap) / TWO_PI)) + 1
    ang = (gap + TWO_PI * np.arange(r0, r1)[:, None] + w.pitch_rad * np.arange(w.edges_per_rev)[None]).ravel()
    ang = ang[(ang >= th[0]) & (ang <= th[-1])]
    edges = CubicSpline(th, t)(ang) + np.random.default_rng(0).normal(0, 20e-9, ang.size)
    path = tmp_path / "coast_teeth.txt"
    np.savetxt(path, edges, fmt="%.9f")
    return path, res


def test_coast_down_through_diagnose(tmp_path, capsys):
    """No firing at all, charge scaling (a calibration's default): the charge iteration stops instead of
    running σ off to 1e12 (an OverflowError through Python), every firing is a misfire and the IMEP is
    the motored one (simulated −0.27 bar, identified −0.32 … −0.35 bar: within 0.1 bar)."""
    path, res = _tue_coast_teeth(tmp_path)
    motored = float(np.mean(np.asarray(res.imep_pa)))
    assert motored < 0
    cal = rotor.Calibration.load(PRESET_CAL)
    ident = rotor.diagnose(rotor.load_engine("tue-single"), path, cal, wheel="60-2")
    assert ident.scaling == "charge" and 0.5 < ident.charge_scale < 2
    assert ident.misfire.all()
    assert np.all(np.isfinite(ident.imep_pa)) and np.abs(ident.imep_pa - motored).max() < 0.1e5
    assert any("no firing" in n for n in ident.notes)
    rc, out, err = run_cli(
        capsys,
        "diagnose",
        str(path),
        "--engine",
        "tue-single",
        "--wheel",
        "60-2",
        "--calibration",
        PRESET_CAL,
        "--json",
    )
    assert rc == 0, err
    d = json.loads(out)
    assert 0.5 < d["charge_scale"] < 2
    assert all(c["misfire"] == [True] for c in d["cycles"]) and len(d["misfires"]) == len(d["cycles"])
    imep = np.array([c["imep_pa"][0] for c in d["cycles"]])
    print("coast-down IMEP [bar]", np.round(imep / 1e5, 3), "simulated", round(motored / 1e5, 3))
    assert np.abs(imep - motored).max() < 0.1e5
    assert d["ambiguous_pairs"] == []


def test_a_diagnosis_holds_its_identification(tmp_path):
    """A Diagnosis is no Identification: it holds one (``identification``) and reads its figures through it."""
    path, _ = _tue_coast_teeth(tmp_path)
    d = rotor.diagnose(rotor.load_engine("tue-single"), path, PRESET_CAL, wheel="60-2")
    assert isinstance(d.identification, rotor.Identification) and not isinstance(d, rotor.Identification)
    assert d.imep_pa is d.identification.imep_pa and d.misfires() == d.identification.misfires()
    assert d.cycles == d.identification.cycles and d.to_pandas().equals(d.identification.to_pandas())


def test_arithmetic_failure_is_one_line(tmp_path, capsys, monkeypatch):
    """Whatever arithmetic still fails inside the charge iteration is a one-line error (exit 2)."""
    import rotor.diagnostics.identification

    path, _ = _tue_coast_teeth(tmp_path)

    def boom(*a, **k):
        raise OverflowError("math range error")

    monkeypatch.setattr(rotor.diagnostics.identification, "identify", boom)
    with pytest.raises(rotor.EngineError, match="charge-scale iteration failed"):
        rotor.diagnose(rotor.load_engine("tue-single"), path, PRESET_CAL, wheel="60-2")
    rc, out, err = run_cli(capsys, "diagnose", str(path), "--engine", "tue-single", "--wheel", "60-2", "--json")
    assert rc == 2 and out == "" and err.count("\n") == 1 and "math range error" in err


def test_calibration_of_another_engine_is_refused(tmp_path, capsys):
    cal = rotor.Calibration.load(PRESET_CAL)
    log = tmp_path / "log.csv"
    log.write_text("0.0\n")
    rc, out, err = run_cli(
        capsys, "diagnose", str(log), "--engine", "mwm6", "--calibration", PRESET_CAL, "--scaling", "none", "--json"
    )
    assert rc == 2 and out == "" and err.count("\n") == 1 and "another engine" in err and "MWM" in err
    with pytest.raises(rotor.EngineError, match="another engine"):
        rotor.diagnose(rotor.load_engine("mwm6"), log, cal, scaling="none")
    # the same name, another cylinder count or geometry (an edited engine file)
    for change in ({"cylinders": 2}, {"geometry": {**cal.geometry, "stroke_m": 0.06}}):
        d = {**cal.to_json_dict(), **change}
        other = tmp_path / "other.json"
        other.write_text(json.dumps(d))
        rc, out, err = run_cli(capsys, "diagnose", str(log), "--engine", "tue-single", "--calibration", str(other))
        assert rc == 2 and "another engine" in err, err


def test_shipped_preset_calibration():
    """rotor/presets/tue-single.calibration.json (benchmarks/diagnose_real.py from full_load.txt) is the
    tue-single preset's, and diagnose finds it by default."""
    from rotor.diagnostics.calibration_record import preset_calibration

    eng = rotor.load_engine("tue-single")
    cal, path = preset_calibration(eng)
    assert path.endswith("tue-single.calibration.json")
    assert cal.engine == eng.name and cal.cylinders == eng.cylinders == 1 and cal.strokes == eng.strokes
    cal.check_engine(eng)
    assert cal.wheel == "60-2" and cal.tooth_errors is not None and cal.scaling == "charge"
    assert cal.inertia_kgm2 == pytest.approx(0.01609, abs=5e-5)
    assert cal.fit["energy_balance_inertia_kgm2"] == pytest.approx(float(eng.crankshaft.inertia_kgm2), abs=5e-5)
    assert cal.tdc_after_gap_deg == pytest.approx(29.40, abs=0.01)
    assert preset_calibration(rotor.load_engine("mwm6")) is None
    import tomllib

    pyproject = tomllib.loads((Path(rotor.__file__).parents[1] / "pyproject.toml").read_text())
    assert "*.json" in pyproject["tool"]["setuptools"]["package-data"]["rotor.presets"]


@needs_data
def test_half_load_from_speed_with_the_preset_calibration(capsys):
    """No --calibration: the preset's own; half load's IMEP within the README's 0.10 bar of its pressure
    channel (measured −0.058 bar)."""
    rc, out, err = run_cli(
        capsys,
        "diagnose",
        str(TUE / "half_load.txt"),
        "--engine",
        "tue-single",
        "--wheel",
        "60-2",
        "--columns",
        "time,-,encoder_v",
        "--json",
    )
    assert rc == 0, err
    d = json.loads(out)
    assert d["calibration_source"].startswith("preset") and d["calibration"]["loaded_from"].startswith("preset")
    assert any("preset's own" in n for n in d["notes"]) and d["ambiguous_pairs"] == []
    cal = rotor.Calibration.load(PRESET_CAL)
    pressure = rotor.analyze_log(
        TUE / "half_load.txt",
        "60-2",
        columns="time,pressure_v,encoder_v",
        tdc_deg=cal.tdc_after_gap_deg,
        tooth_errors=cal.tooth_errors,
    )
    meas = rotor.measured_imep(rotor.load_engine("tue-single"), pressure, cal.pressure_gain_pa)
    ident = np.array([c["imep_pa"][0] for c in d["cycles"]])
    assert ident.size == meas.size
    err = ident - meas
    print(f"half load: mean error {np.mean(err) / 1e5:+.3f} bar, rms {np.sqrt(np.mean(err**2)) / 1e5:.3f} bar")
    assert abs(np.mean(err)) < 0.10e5 and np.sqrt(np.mean(err**2)) < 0.12e5
