"""The engine's own fuel-cut coast-down as a wheel calibration: the speed ripple of its
varying reduced inertia (ω ∝ I(θ)^-½ at constant energy) does not die with speed, so the
coast-down regression takes it for tooth errors unless the engine is given."""

import sys

import numpy as np
import pytest
from conftest import ROOT
from scipy.interpolate import CubicSpline

import rotor

sys.path.insert(0, str(ROOT / "benchmarks"))
import synthetic_wheel  # noqa: E402
from synthetic_wheel import ERRORS, WHEEL  # noqa: E402

GAP_DEG = -60.0  # the first edge after the gap passes 60° before cylinder 1's TDC


def _edges(theta, t, rng):
    return synthetic_wheel.tooth_times(CubicSpline(theta, t), theta[0], theta[-1], np.deg2rad(GAP_DEG), rng, 20e-9)


def _worst_deg(errors):
    d = np.asarray(errors) - ERRORS
    return float(np.rad2deg(np.abs(d - d.mean()).max()))


@pytest.fixture(scope="module")
def fuel_cut():
    engine = rotor.load_engine("4chn15")
    run = rotor.simulate(
        engine,
        rpm=1250,
        cycles=12,
        load=rotor.ConstantLoad(450.0),
        combustion=np.zeros((12, engine.cylinders)),
        step_deg=0.25,
        progress=False,
    )
    track = rotor.locate_teeth(_edges(np.asarray(run.theta), np.asarray(run.t), np.random.default_rng(3)), WHEEL)
    return engine, track


def test_fuel_cut_coast_down_calibrates_with_the_engine(fuel_cut):
    engine, track = fuel_cut
    plain = rotor.estimate_tooth_errors(track, engine_orders=())
    fixed = rotor.estimate_tooth_errors(track, engine_orders=(), engine=engine, tdc_deg=-GAP_DEG)
    assert "coast-down regression" in plain.method and "inertia ripple removed" in fixed.method
    assert _worst_deg(plain.errors_rad) > 0.2  # the ripple of 4 × 9.72 kg taken for the wheel's
    assert _worst_deg(fixed.errors_rad) < 0.02  # measured 0.0095°


def test_wrong_tdc_does_not_help(fuel_cut):
    """The ripple is placed by TDC: 45° off, the estimate stays far off (the test can fail)."""
    engine, track = fuel_cut
    off = rotor.estimate_tooth_errors(track, engine_orders=(), engine=engine, tdc_deg=-GAP_DEG + 45)
    assert _worst_deg(off.errors_rad) > 0.1


def test_engine_needs_tdc(fuel_cut):
    engine, track = fuel_cut
    with pytest.raises(rotor.LogError, match="tdc_deg"):
        rotor.estimate_tooth_errors(track, engine_orders=(), engine=engine)


def test_analyze_log_and_cli_take_the_engine(fuel_cut, tmp_path, capsys):
    import json

    from rotor.cli import main

    engine, track = fuel_cut
    log = rotor.Log.from_arrays(tooth_time_s=track.t)
    a = rotor.analyze_log(log, WHEEL, tdc_deg=-GAP_DEG, engine=engine, engine_orders=())
    assert _worst_deg(a.tooth_errors.errors_rad) < 0.02
    with pytest.raises(rotor.LogError, match="tdc_deg"):
        rotor.analyze_log(log, WHEEL, engine=engine, engine_orders=())
    path = tmp_path / "coast.csv"
    np.savetxt(path, track.t, header="tooth_time_s", comments="")
    out = tmp_path / "wheel.json"
    assert (
        main(
            [
                "analyze",
                str(path),
                "--wheel",
                "60-2",
                "--columns",
                "tooth_time_s",
                "--engine",
                "4chn15",
                "--tdc-deg",
                str(-GAP_DEG),
                "--engine-orders",
                "none",
                "--save-tooth-errors",
                str(out),
                "--json",
            ]
        )
        == 0
    )
    capsys.readouterr()
    saved = json.loads(out.read_text())
    assert _worst_deg(saved["errors_rad"]) < 0.02 and "inertia ripple removed" in saved["method"]
