"""rotor diagnose: the command line over rotor.calibrate / rotor.diagnose (in-process),
its JSON, its one-line errors and its plot; plotting.plot_identification."""

import json

import numpy as np
import pytest

import rotor
from rotor.cli import main
from conftest import SHARED_DATA

TUE = SHARED_DATA / "tue-4gb10"
needs_data = pytest.mark.skipif(not TUE.is_dir(), reason=f"shared data not found at {TUE}")
GAIN = str(1e5 / (5 * 0.00385))


def _run(capsys, *argv):
    try:
        rc = main(list(argv))
    except SystemExit as e:  # argparse's usage errors
        rc = e.code
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """Calibrate on full_load.txt through the CLI: (calibration path, JSON, plot folder)."""
    if not TUE.is_dir():
        pytest.skip(f"shared data not found at {TUE}")
    folder = tmp_path_factory.mktemp("diagnose")
    cal = folder / "tue.json"
    plots = folder / "plots"
    rc = main(["diagnose", str(TUE / "full_load.txt"), "--engine", "tue-single", "--wheel", "60-2", "--columns",
               "time,pressure_v,encoder_v", "--save-calibration", str(cal), "--pressure-gain", GAIN, "--json",
               "--plot", str(plots)])
    assert rc == 0
    return cal, plots


@needs_data
def test_calibrate_and_diagnose_json(saved, capsys):
    cal, plots = saved
    assert (plots / "full_load_diagnosis.png").stat().st_size > 10_000
    c = rotor.Calibration.load(cal)
    assert c.wheel == "60-2" and c.tooth_errors is not None and c.source == "full_load.txt"
    # speed only, with the saved calibration (the pressure column skipped)
    rc, out, err = _run(capsys, "diagnose", str(TUE / "full_load.txt"), "--engine", "tue-single", "--columns",
                        "time,-,encoder_v", "--calibration", str(cal), "--json")
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
    rc, out, err = _run(capsys, "diagnose", str(TUE / "full_load.txt"), "--engine", "tue-single", "--columns",
                        "time,pressure_v,encoder_v", "--calibration", str(cal))
    assert rc == 0, err
    assert "IMEP from the pressure channel" in out and "identified − measured" in out


@needs_data
def test_speed_only_needs_tdc(capsys):
    rc, out, err = _run(capsys, "diagnose", str(TUE / "No_load.txt"), "--engine", "tue-single", "--wheel", "60-2",
                        "--columns", "time,-,encoder_v", "--json")
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
        (["diagnose", str(log), "--engine", "tue-single", "--save-calibration", str(tmp_path / "x" / "c.json")],
         "no folder"),
    ]
    for argv, needle in cases:
        rc, out, err = _run(capsys, *argv)
        assert rc == 2, argv
        assert err.count("\n") == 1 and needle in err, (argv, err)


def test_plot_identification_without_engine(tmp_path):
    """The plot from a plain identify (simulated, direct speed): three panels, misfires marked."""
    import matplotlib

    matplotlib.use("Agg")
    eng = rotor.load_engine("tue-single")
    ss = rotor.steady_state(eng)
    load = rotor.ConstantLoad(float(ss.info["load_torque_Nm"]))
    pattern = rotor.combustion_pattern(6, 1, misfires=[(3, 1)])
    run = rotor.simulate(eng, rpm=float(ss.omega[0]) * 30 / np.pi, cycles=6, load=load, combustion=pattern)
    ident = rotor.identify(eng, run)
    assert ident.misfires() == [(3, 1)]
    axes = ident.plot()
    assert len(axes) == 3 and "1 misfire" in axes[2].get_title()
    axes = ident.plot(engine=eng)
    assert "per cylinder" in axes[1].get_title()
    torque = rotor.cylinder_torques(eng, ident)
    assert torque.shape == (ident.cycles, ident.omega.shape[1], 1)
    from rotor.plotting import save_figure

    save_figure(axes, tmp_path / "ident.png")
    assert (tmp_path / "ident.png").stat().st_size > 10_000
