"""A diagnosis says when its fit is poor, and its plot shows the IMEP the pressure channel
measured."""

from __future__ import annotations

import json

import numpy as np
import pytest

import rotor
from rotor.cli import main
from rotor.diagnostics.identification import POOR_FIT_R2
from rotor.diagnostics.synthetic import BENCH_GAIN_PA_PER_V, simulated_recording
from rotor.units import PA_PER_BAR

ENGINE = rotor.load_engine("tue-single")


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """A simulated tue-single bench recording (its own wheel) and a calibration made on it."""
    path = simulated_recording(tmp_path_factory.mktemp("honest") / "sim.txt")
    cal = rotor.calibrate(
        ENGINE, path, wheel="60-2", columns="time,pressure_v,encoder_v", pressure_gain=BENCH_GAIN_PA_PER_V
    )
    return path, cal


def test_a_good_fit_has_no_warning_and_the_plot_shows_the_measured_imep(recording):
    import matplotlib

    matplotlib.use("Agg")
    path, cal = recording
    d = rotor.diagnose(ENGINE, path, cal, columns="time,pressure_v,encoder_v")
    assert d.fit_r2 > POOR_FIT_R2 and d.warnings == ()
    assert "warning" not in d.summary() and d.to_json_dict()["warnings"] == []
    assert d.measured_imep_pa is not None and d.measured_imep_pa.shape == (d.cycles,)
    axes = d.plot()
    lines = [ln for ln in axes[2].get_lines() if "pressure channel" in str(ln.get_label())]
    assert len(lines) == 1
    np.testing.assert_allclose(lines[0].get_ydata(), d.measured_imep_pa / PA_PER_BAR)
    assert "cylinder 1, pressure channel" in [t.get_text() for t in axes[2].get_legend().get_texts()]
    matplotlib.pyplot.close("all")


def test_no_measured_line_without_a_pressure_channel(recording):
    import matplotlib

    matplotlib.use("Agg")
    path, cal = recording
    d = rotor.diagnose(ENGINE, path, cal, columns="time,-,encoder_v")
    assert d.measured_imep_pa is None
    axes = d.plot()
    assert not [ln for ln in axes[2].get_lines() if "pressure channel" in str(ln.get_label())]
    matplotlib.pyplot.close("all")


def test_a_recording_the_model_cannot_explain_warns(recording, capsys):
    """The simulated recording read with the real bench's calibration (another wheel's tooth
    errors, another inertia): the model explains a fifth of the speed (R² about 0.18) and the
    IMEP comes out about 10 % low. The text, the JSON and stderr say the fit is poor."""
    path, _ = recording
    d = rotor.diagnose(ENGINE, path, "preset", columns="time,-,encoder_v")
    assert d.fit_r2 < POOR_FIT_R2
    assert len(d.warnings) == 1 and "poor fit" in d.warnings[0] and "IMEP" in d.warnings[0]
    assert f"R² {d.fit_r2:.2f}" in d.warnings[0]
    text = d.summary()
    assert "warning: poor fit" in text
    assert text.index("warning") < text.index("IMEP mean")  # before the numbers it doubts
    assert d.to_json_dict()["warnings"] == list(d.warnings)
    assert "(poor fit)" in d.plot()[0].get_title()

    rc = main(["diagnose", str(path), "--engine", "tue-single", "--columns", "time,-,encoder_v", "--json"])
    out, err = capsys.readouterr()
    assert rc == 0
    data = json.loads(out)
    assert len(data["warnings"]) == 1 and "poor fit" in data["warnings"][0]
    assert "rotor: warning:" in err and "poor fit" in err and str(path) in err
    assert len(err.strip().splitlines()) == 1


def test_identification_warns_too():
    """The same property on a plain identification: a steady speed buried in white noise three
    times its own fluctuation (R² about 0.1) warns; the clean speed does not."""
    ss = rotor.steady_state(ENGINE)
    omega = np.tile(np.asarray(ss.omega).reshape(-1), (4, 1))
    clean = rotor.identify(ENGINE, omega)
    assert clean.fit_r2 > POOR_FIT_R2 and clean.warnings == ()
    noisy = omega + np.random.default_rng(1).normal(0.0, 3 * float(np.std(omega)), omega.shape)
    ident = rotor.identify(ENGINE, noisy)
    assert ident.fit_r2 < POOR_FIT_R2
    assert ident.warnings and "warning: poor fit" in ident.summary()
    assert ident.to_json_dict()["warnings"] == list(ident.warnings)
