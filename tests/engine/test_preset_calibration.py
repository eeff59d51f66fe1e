"""The Wiebe cycles of the presets tue-single and mwm6 reproduce the data they were fitted to.

The data live outside the project (``../shared/data``, see its README); the tests that
need them skip when the folder is absent. ``benchmarks/calibrate_presets.py`` does the
fit; here its signal processing is reused (imported from the file) to rebuild the
measured traces, and the presets' pressure is compared with them.

Tolerances, from what the calibration measured (benchmarks/results/calibration.json)
with a margin for the rounding of the preset's numbers and for numerical noise:
- tue-single vs the averaged full-load cycle (1° grid): RMS 0.86 %, max 1.70 % of the
  peak measured; tested RMS < 1.2 %, max < 2.5 %;
- mwm6 vs the scaled digitised points: RMS 0.88 %, max 2.55 % measured; tested
  RMS < 1.2 %, max < 3.5 %;
- peak angle within 3° (measured 1° and 0.2°), peak pressure within 3 % (1.1 % and 0.9 %);
- the preset's imep_pa within 0.5 % of the data's IMEP (it is the data's IMEP, rounded to
  100 Pa), and the preset's own IMEP equal to imep_pa (the heat release is scaled to it).
"""

import importlib.util

import numpy as np
import pytest
from conftest import ROOT, SHARED_DATA

import rotor

DATA = SHARED_DATA
SCRIPT = ROOT / "benchmarks" / "calibrate_presets.py"

needs_data = pytest.mark.skipif(not DATA.is_dir(), reason=f"shared data not found at {DATA}")

TUE_RMS, TUE_MAX = 1.2, 2.5  # % of peak
MWM_RMS, MWM_MAX = 1.2, 3.5  # % of peak
PEAK_ANGLE_DEG = 3.0
PEAK_REL = 0.03
IMEP_REL = 0.005


def _load_script():
    spec = importlib.util.spec_from_file_location("calibrate_presets", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def cal():
    return _load_script()


def _preset_pressure(name, angle_deg):
    e = rotor.load_engine(name)
    return np.asarray(e.pressure(np.deg2rad(np.asarray(angle_deg, dtype=float)), e.geometry, e.strokes))


def _errors(data, model):
    peak = np.max(data)
    err = model - data
    return 100 * np.sqrt(np.mean(err**2)) / peak, 100 * np.max(np.abs(err)) / peak


@pytest.mark.parametrize("name", ["tue-single", "mwm6"])
def test_preset_loads_and_pressure_is_positive_and_finite(name):
    e = rotor.load_engine(name)
    assert isinstance(e.pressure, rotor.WiebeCycle)
    phi = np.linspace(0.0, 4 * np.pi, 2881)
    p = np.asarray(e.pressure(phi, e.geometry, e.strokes))
    assert np.all(np.isfinite(p))
    assert np.all(p > 0)
    # firing near TDC, not somewhere else
    peak_deg = np.rad2deg(phi[np.argmax(p)])
    assert 360.0 < peak_deg < 400.0


@pytest.mark.parametrize("name", ["tue-single", "mwm6"])
def test_preset_imep_equals_its_imep_pa(name):
    e = rotor.load_engine(name)
    assert float(rotor.imep_pa(e)) == pytest.approx(float(e.pressure.imep_pa), rel=1e-9)


def test_mwm6_fires_evenly_in_order_15362_4():
    e = rotor.load_engine("mwm6")
    fire = np.rad2deg(np.asarray(e.firing_angles_rad))
    order = [int(i) + 1 for i in np.argsort(fire)]
    assert order == [1, 5, 3, 6, 2, 4]
    assert np.allclose(np.diff(np.sort(fire)), 120.0)


def test_script_fails_clearly_without_data(cal, tmp_path, capsys):
    assert cal.main(["--data", str(tmp_path / "nowhere"), "--out", str(tmp_path / "x.json")]) != 0
    assert "not there" in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()


@needs_data
def test_mwm6_matches_the_scaled_digitised_curve(cal):
    angle, p_data = cal.mwm_points(DATA, rpm=rotor.load_engine("mwm6").operating.rpm)
    p_model = _preset_pressure("mwm6", angle)
    rms, mx = _errors(p_data, p_model)
    assert rms < MWM_RMS, f"RMS error {rms:.2f} % of peak"
    assert mx < MWM_MAX, f"max error {mx:.2f} % of peak"
    fine = np.arange(300.0, 450.0, 0.1)
    p_fine = _preset_pressure("mwm6", fine)
    assert abs(fine[np.argmax(p_fine)] - angle[np.argmax(p_data)]) <= PEAK_ANGLE_DEG
    assert p_fine.max() == pytest.approx(p_data.max(), rel=PEAK_REL)
    grid, trace = cal.mwm_trace(DATA)
    imep_data = cal.trace_imep_pa(grid, trace, rotor.load_engine("mwm6").geometry)
    assert float(rotor.load_engine("mwm6").pressure.imep_pa) == pytest.approx(imep_data, rel=IMEP_REL)


@needs_data
def test_tue_single_matches_the_averaged_full_load_cycle(cal):
    c = cal.tue_cycle(DATA)
    e = rotor.load_engine("tue-single")
    assert c["cycles"] >= 10
    assert float(e.operating.rpm) == pytest.approx(c["rpm"], abs=5.0)
    angle, p_data = c["angle_deg"], c["pressure_pa"]
    p_model = _preset_pressure("tue-single", angle)
    rms, mx = _errors(p_data, p_model)
    assert rms < TUE_RMS, f"RMS error {rms:.2f} % of peak"
    assert mx < TUE_MAX, f"max error {mx:.2f} % of peak"
    assert abs(angle[np.argmax(p_model)] - angle[np.argmax(p_data)]) <= PEAK_ANGLE_DEG
    assert p_model.max() == pytest.approx(p_data.max(), rel=PEAK_REL)
    imep_data = cal.trace_imep_pa(angle, p_data, e.geometry)
    assert float(e.pressure.imep_pa) == pytest.approx(imep_data, rel=IMEP_REL)


@needs_data
def test_tue_tdc_is_the_same_in_all_three_recordings(cal):
    """The gap-to-TDC angle is a property of the wheel: the three loads must agree."""
    tdc = [cal.tue_cycle(DATA, name)["tdc_after_gap_deg"] for name in ("No_load.txt", "half_load.txt", "full_load.txt")]
    assert max(tdc) - min(tdc) < 2.0, tdc
    assert 25.0 < tdc[2] < 33.0
