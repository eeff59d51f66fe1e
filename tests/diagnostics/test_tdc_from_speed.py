"""TDC from the crank speed alone, and a calibration checked against the recording: a simulated engine whose wheel is mounted 30°, 90° and 180° away from the
calibration's TDC, firing steadily and with an ignition cut, is corrected from the speed and
diagnosed within the synthetic recordings' usual IMEP error (1 %, tests/diagnostics/test_synthetic.py),
never as misfires; a speed without the engine's signature is refused with the reason."""

from __future__ import annotations

import json

import numpy as np
import pytest

import rotor
from rotor.cli import main
from rotor.diagnostics.phase import TdcNotDetermined, TdcVerdict, check_tdc, tdc_from_speed
from rotor.diagnostics.synthetic import (
    DEFAULT_GAP_DEG,
    simulated_tooth_errors,
    simulated_tooth_times,
)

ENGINE = rotor.load_engine("tue-single")
TDC = -DEFAULT_GAP_DEG  # the calibration's: 29.4° after the gap
OFFSETS = (30.0, 90.0, 180.0)
CUT = (3, 4)  # cycles of the ignition cut
IMEP_REL = 0.01  # the usual IMEP error on a simulated recording (tests/diagnostics/test_synthetic.py)
TDC_TOL_DEG = 1.0


@pytest.fixture(scope="module", autouse=True)
def _compilation_cache():
    """The test session's own persistent compilation cache (conftest.py sets its folder; the
    CLI switches it on anyway): this module and tests/diagnostics/test_tdc_from_speed.py /
    tests/diagnostics/test_calibrate_cli.py compile the same steady state and identification, and the
    second reuses the first's code after conftest drops the compiled executables."""
    rotor.enable_compilation_cache()


def _calibration():
    """A calibration of another installation of the same engine and wheel: the file's inertia,
    the wheel's own tooth errors, TDC 29.4° after the gap."""
    return rotor.Calibration(
        engine=ENGINE.name,
        inertia_kgm2=float(ENGINE.crankshaft.inertia_kgm2),
        tdc_after_gap_deg=TDC,
        pressure_gain_pa=1e5,
        pressure_offset_pa=0.0,
        loss_torque_Nm=0.0,
        scaling="none",
        wheel="60-2",
        tooth_errors=simulated_tooth_errors(),
        source="another bench",
        cylinders=1,
        strokes=4,
    )


def _err(found, true):
    return (found - true + 180.0) % 360.0 - 180.0


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Tooth-time logs of 8 simulated cycles at 3000 rpm, starting 200° into the first, with
    the wheel's gap moved by each offset: firing steadily, and with an ignition cut in
    cycles 3–4."""
    folder = tmp_path_factory.mktemp("tdc")
    ss = rotor.steady_state(ENGINE, 3000.0)
    load = rotor.ConstantLoad(float(ss.load_torque_Nm))
    runs = {}
    for name, pattern in (("steady", np.ones((8, 1))), ("cut", np.ones((8, 1)))):
        if name == "cut":
            pattern[list(CUT)] = 0.0
        runs[name] = rotor.simulate(
            ENGINE, rpm=3000.0, cycles=8, load=load, combustion=pattern, step_deg=0.5, progress=False
        )
    paths = {
        (name, off): simulated_tooth_times(
            folder / f"{name}{off:g}.txt", runs[name], gap_deg=DEFAULT_GAP_DEG - off, start_deg=200.0, seed=int(off)
        )
        for name in runs
        for off in (0.0, *OFFSETS)
    }
    return paths, runs, folder


@pytest.mark.parametrize("off", OFFSETS)
def test_tdc_from_speed_alone_within_a_degree(files, off):
    """The offset from the speed alone (cycles cut at 0° after the gap, the wheel's tooth errors
    estimated from the same record) within 1° (measured: under 0.9°), determined, its ± about
    the error's size, and the firing revolution the one that puts the cycles where the
    simulation's are (their IMEP comes back, see below)."""
    paths, _, _ = files
    a = rotor.analyze_log(paths["steady", off], "60-2", tdc_deg=0.0)
    fit = tdc_from_speed(ENGINE, a)
    true = TDC + off
    assert fit.determined, fit.reason
    assert abs(_err(fit.tdc_after_gap_deg, true)) < TDC_TOL_DEG
    assert 0.05 < fit.std_deg < 3.0 and fit.separation > 10 and fit.r2 > 0.95
    assert np.all(fit.cycle_combustion > 0.8)
    assert fit.to_json_dict()["determined"] is True and len(fit.to_pandas()) == a.cycles
    assert "TDC" in fit.summary()
    if off == OFFSETS[0]:  # the plot (rotor.plotting.diagnostics.plot_speed_tdc)
        import matplotlib.pyplot as plt

        ax = fit.plot()
        assert ax.get_title().startswith("TDC from the speed") and len(ax.lines) == 2
        plt.close(ax.figure)


@pytest.mark.parametrize("off", OFFSETS)
def test_a_calibration_off_by_offset_is_corrected_and_diagnosed(files, off):
    """Steady firing: the calibration's TDC is corrected (a warning with its ±), the IMEP within
    1 % of the engine file's, no misfire."""
    paths, runs, _ = files
    d = rotor.diagnose(ENGINE, paths["steady", off], _calibration(), wheel="60-2")
    chk = d.tdc_check
    assert chk is not None and chk.verdict is TdcVerdict.DISAGREES and chk.corrected
    assert abs(_err(chk.used_deg, TDC + off)) < TDC_TOL_DEG
    assert any("TDC corrected" in w for w in d.warnings)
    assert not d.misfire.any()
    sim = np.asarray(runs["steady"].imep_pa)[1 : 1 + d.cycles, 0]  # the record starts 200° into cycle 0
    np.testing.assert_allclose(d.imep_pa[:, 0], sim, rtol=IMEP_REL)
    js = d.to_json_dict()
    assert js["tdc_check"]["verdict"] == "disagrees" and js["tdc_check"]["corrected"] and js["tdc_check"]["std_deg"] > 0
    assert abs(_err(js["tdc_after_gap_deg"], TDC + off)) < TDC_TOL_DEG


@pytest.mark.parametrize("off", OFFSETS)
def test_an_ignition_cut_is_corrected_and_only_the_cut_misfires(files, off):
    """An ignition cut in a record that starts mid-cycle: TDC corrected, the cut cycles (and
    only they) misfires, the fired ones within 1 % of the simulated IMEP; the partial cycles at
    the ends are reported."""
    paths, runs, _ = files
    d = rotor.diagnose(ENGINE, paths["cut", off], _calibration(), wheel="60-2")
    assert d.tdc_check is not None and d.tdc_check.verdict is TdcVerdict.DISAGREES
    assert abs(_err(d.tdc_check.used_deg, TDC + off)) < TDC_TOL_DEG
    # the analysed cycles are the simulated cycles 1 … (the record starts 200° into cycle 0)
    assert d.partial_deg[0] > 0 and d.cycles >= 5
    sim = np.asarray(runs["cut"].imep_pa)[1 : 1 + d.cycles, 0]
    fired = sim > 0
    assert np.array_equal(d.misfire[:, 0], ~fired), (d.misfire[:, 0], sim)
    np.testing.assert_allclose(d.imep_pa[fired, 0], sim[fired], rtol=IMEP_REL)
    js = d.to_json_dict()
    assert all("supported" in row and "flag" in row for row in js["cycles"])
    assert js["partial_cycles_deg"]["before_first"] > 0


def test_the_right_calibration_is_kept(files):
    """A calibration whose TDC is right is kept, with a note of how well the speed agrees."""
    paths, _, _ = files
    d = rotor.diagnose(ENGINE, paths["steady", 0.0], _calibration(), wheel="60-2")
    assert d.tdc_check.verdict is TdcVerdict.AGREES and d.tdc_check.used_deg == pytest.approx(TDC)
    assert not any("corrected" in w for w in d.warnings)
    assert any("agrees with the recording's speed" in n for n in d.notes)
    assert "agrees with the recording's speed" in d.summary()
    import matplotlib.pyplot as plt

    ax = d.tdc_check.plot()  # the fit's residual, the best offset and the calibration's TDC marked
    assert len(ax.lines) == 3 and "checked TDC" in ax.get_legend_handles_labels()[1][-1]
    plt.close(ax.figure)


def _constant(folder, jitter_s=200e-9):
    """Tooth times of a wheel turning at a constant 3000 rpm with timer noise: no engine in it."""
    from types import SimpleNamespace

    theta = np.linspace(0.0, 6 * 4 * np.pi, 5000)
    return simulated_tooth_times(
        folder / "constant.txt", SimpleNamespace(theta=theta, t=theta / (3000 * np.pi / 30)), jitter_s=jitter_s
    )


def test_a_speed_without_the_engine_is_refused(files, capsys):
    """A constant speed: TDC can be neither found nor checked — refused with the reason and the
    offset it measured (a one-line error, exit 2), never diagnosed as misfires."""
    _, _, folder = files
    path = _constant(folder)
    with pytest.raises(TdcNotDetermined, match="cannot determine TDC"):
        rotor.diagnose(ENGINE, path, _calibration(), wheel="60-2")
    with pytest.raises(TdcNotDetermined, match="explains"):
        rotor.diagnose(ENGINE, path, None, wheel="60-2", tdc_deg="speed")
    a = rotor.analyze_log(path, "60-2", tdc_deg=0.0)
    fit = tdc_from_speed(ENGINE, a)
    assert not fit.determined and fit.reason
    with pytest.raises(TdcNotDetermined):
        check_tdc(fit, None)
    rc = main(["diagnose", str(path), "--engine", "tue-single", "--wheel", "60-2", "--tdc-deg", "speed", "--json"])
    out, err = capsys.readouterr()
    assert rc == 2 and out == "" and err.count("\n") == 1 and "cannot determine TDC" in err


def test_tdc_deg_speed_on_the_command_line(files, capsys):
    """``rotor diagnose --tdc-deg speed --no-calibration``: TDC from the speed, in the JSON with how sure."""
    paths, _, _ = files
    rc = main(
        [
            "diagnose",
            str(paths["steady", 90.0]),
            "--engine",
            "tue-single",
            "--wheel",
            "60-2",
            "--no-calibration",
            "--tdc-deg",
            "speed",
            "--json",
        ]
    )
    out, err = capsys.readouterr()
    assert rc == 0, err
    d = json.loads(out)
    assert d["tdc_check"]["verdict"] == "found"
    assert abs(_err(d["tdc_after_gap_deg"], TDC + 90.0)) < TDC_TOL_DEG
    assert d["tdc_check"]["std_deg"] > 0 and d["tdc_check"]["separation_sigma"] > 5
    assert not any(c["misfire"][0] for c in d["cycles"])


def _digital_with_cam(path, run, gap_deg, cam_deg, start_deg=200.0):
    """A logic-analyser export (``Time[s], Channel 0, Channel 1``: the 60-2 wheel's 0/1 signal,
    high for half of each pitch from its rising edge, and a cam high for one revolution of each
    cycle from ``cam_deg`` [deg, cycle angle]) of a simulated run, from ``start_deg`` on."""
    from scipy.interpolate import CubicSpline

    w = rotor.Wheel(60, 2)
    th, t = np.asarray(run.theta), np.asarray(run.t)
    t_of = CubicSpline(th, t)
    lo, hi = np.deg2rad(start_deg), th[-1]
    gap = np.deg2rad(gap_deg)
    r = np.arange(int(np.floor((lo - gap) / (2 * np.pi))) - 1, int(np.ceil((hi - gap) / (2 * np.pi))) + 1)
    err = simulated_tooth_errors().errors_rad
    rise = (gap + 2 * np.pi * r[:, None] + w.pitch_rad * np.arange(w.edges_per_rev)[None, :] + err[None, :]).ravel()
    rise = rise[(rise >= lo) & (rise + 0.5 * w.pitch_rad <= hi)]
    tt = np.concatenate([t_of(rise), t_of(rise + 0.5 * w.pitch_rad)])
    level = np.concatenate([np.ones(rise.size), np.zeros(rise.size)])
    o = np.argsort(tt)
    tt, level = tt[o], level[o]
    cam_up = np.deg2rad(cam_deg) + 4 * np.pi * np.arange(-1, int(hi / (4 * np.pi)) + 2)
    edges = np.sort(np.concatenate([cam_up, cam_up + 2 * np.pi]))
    cam = (np.searchsorted(edges, np.interp(tt, t, th), side="right") % 2).astype(float)
    np.savetxt(
        path,
        np.c_[tt - tt[0], level, cam],
        delimiter=", ",
        header="Time[s], Channel 0, Channel 1",
        comments="",
        fmt=["%.9f", "%d", "%d"],
    )
    return path


def test_a_cam_channel_keeps_its_phase_after_the_correction(files):
    """A logic-analyser capture with a cam channel, the wheel 90° away from the calibration's TDC,
    an ignition cut: the TDC is corrected from the speed, the firing revolution stays the cam's
    (and the speed's fit agrees: a note), only the cut misfires. A cam a revolution off is kept
    too, with a warning that the speed's fit puts firing TDC in the other revolution."""
    _, runs, folder = files
    off = 90.0
    gap = DEFAULT_GAP_DEG - off
    # the cam rises 90° before firing TDC (cycle angle 360°): the first TDC after it fires
    right = _digital_with_cam(folder / "cam.csv", runs["cut"], gap, 270.0)
    d = rotor.diagnose(ENGINE, right, _calibration(), wheel="60-2")
    assert d.cycles == 6
    assert d.tdc_check.verdict is TdcVerdict.DISAGREES and abs(_err(d.tdc_check.used_deg, TDC + off)) < TDC_TOL_DEG
    assert d.analysis.firing_method.startswith("cam")
    assert not d.phase_warning and any("where the speed's fit puts it too" in n for n in d.notes)
    sim = np.asarray(runs["cut"].imep_pa)[1 : 1 + d.cycles, 0]
    fired = sim > 0
    assert np.array_equal(d.misfire[:, 0], ~fired), (d.misfire[:, 0], sim)
    np.testing.assert_allclose(d.imep_pa[fired, 0], sim[fired], rtol=IMEP_REL)
    # a revolution later (as many whole cycles as above: the identification's compiled size is shared)
    wrong = _digital_with_cam(folder / "cam_wrong.csv", runs["cut"], gap, 270.0 - 360.0, start_deg=560.0)
    d = rotor.diagnose(ENGINE, wrong, _calibration(), wheel="60-2")
    assert d.analysis.firing_method.startswith("cam")
    assert d.cycles == 6 and "one revolution away" in d.phase_warning and d.phase_warning in d.warnings
