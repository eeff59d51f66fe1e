"""rotor.diagnostics.synthetic.simulated_recording: a simulated raw bench recording in the format of the
real tue-4gb10 files, read back by the same code path (read_log, analyze_log, calibrate,
diagnose) and compared with the simulator it was made from."""

import os

import equinox as eqx
import numpy as np
import pytest
from conftest import SHARED_DATA

import rotor
from rotor.diagnostics.synthetic import (
    BENCH_GAIN_PA_PER_V,
    DEFAULT_GAP_DEG,
    simulated_recording,
    simulated_tooth_errors,
)

COLUMNS = "time,pressure_v,encoder_v"  # the real files' column spec
ENGINE = rotor.load_engine("tue-single")
ROD_RATIO = float(ENGINE.geometry.stroke_m) / 2 / float(ENGINE.geometry.rod_length_m)
FIT = dict(columns=COLUMNS, compression_ratio=8.5, rod_ratio=ROD_RATIO)


def _charge_scaled(engine, s):
    return eqx.tree_at(lambda e: e.pressure, engine, engine.pressure.scale_charge(s))


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    """The default recording: tue-single at 3000 rpm, full load, 12 cycles."""
    return simulated_recording(tmp_path_factory.mktemp("sim") / "full_load.txt")


@pytest.fixture(scope="module")
def steady():
    return rotor.steady_state(ENGINE)


def test_reads_back_like_the_real_files(full):
    text = full.read_text().splitlines()
    assert len(text[0].split("\t")) == 3 and not text[0].startswith("#")  # tab separated, no header, as the bench's
    log = rotor.read_log(full, COLUMNS)
    t, pv, ev = log["time"], log["pressure_v"], log["encoder_v"]
    assert t[0] == 0.0 and np.allclose(np.diff(t), 1e-5, rtol=0, atol=1e-12)  # 100 kHz
    assert 0.45 < t[-1] < 0.55  # 12 cycles at 3000 rpm: about the real files' 0.5 s
    # the bench calibration read back: bar = (V/5 − 0.115)/0.00385; intake ≈ 0.77 bar, peak ≈ 20 bar
    bar = (pv / 5 - 0.115) / 0.00385
    assert 0.6 < np.percentile(bar, 1) < 1.2 and 18 < bar.max() < 22
    lo, hi = np.percentile(ev, [1, 99])
    assert abs(lo - -0.73) < 0.05 and abs(hi - 4.0) < 0.05
    if (SHARED_DATA / "tue-4gb10" / "full_load.txt").is_file():  # the same levels as the real encoder signal
        real = rotor.read_log(SHARED_DATA / "tue-4gb10" / "full_load.txt", COLUMNS)
        rlo, rhi = np.percentile(real["encoder_v"], [1, 99])
        assert abs(lo - rlo) < 0.1 and abs(hi - rhi) < 0.6
        assert np.median(real["pressure_v"]) == pytest.approx(np.median(pv), abs=0.05)


def test_analyze_finds_every_tooth_the_speed_and_tdc(full):
    a = rotor.analyze_log(full, "60-2", **FIT)
    assert a.cycles == 12  # exactly the cycles asked for
    tr = a.track
    assert tr.wheel.edges_per_rev == 58 and tr.gap_ratio == pytest.approx(3.0, abs=0.2)
    # every tooth: the edges found are the record's rising edges, one per tooth, none missed or doubled
    duration = rotor.read_log(full, COLUMNS)["time"][-1]
    assert abs(tr.t.size - duration * 3000 / 60 * 58) <= 2
    assert a.edges.times.size == tr.t.size
    np.testing.assert_allclose(a.mean_rpm, 3000.0, rtol=5e-3)  # asked: within 0.5 % (measured 1e-7)
    assert abs(np.mean(a.mean_rpm) / 3000 - 1) < 1e-5
    # TDC from the pressure's polytropic fit: 0.3° late on the simulator's own cycle (the combustion
    # starts 14.9° before TDC, inside the fit's −90…−10° window); the wheel's gap is at −29.4°
    assert np.rad2deg(a.tdc_rad) == pytest.approx(-DEFAULT_GAP_DEG, abs=0.5)
    assert a.firing_method.startswith("pressure")


def test_delta_and_orders_against_the_steady_state(full, steady):
    """δ of each analysed cycle against the simulator's steady-state δ (0.0677).

    - with the wheel's true errors (rotor.diagnostics.synthetic.simulated_tooth_errors): within 0.5 %
      (measured 0.3 %; what is left is the 0.01 V noise on the edges, 85 ns of timing jitter);
    - with the errors estimated from this firing run (the default): within 4 % (measured
      −1.9 … −2.2 %). Honest, not loose: a firing run cannot tell the engine's whole orders
      from the wheel's; the estimate leaves orders 1 and 2 to the engine and takes the
      engine's own orders 3 … 5 (0.42, 0.27, 0.12 rad/s at 3000 rpm) for wheel errors, which
      removes them from the speed (README, "How it works", 3);
    - uncorrected, the ±0.1° errors put δ 32 % high: the check above can fail.
    """
    ref = float(steady.delta)
    true = rotor.analyze_log(full, "60-2", tooth_errors=simulated_tooth_errors(), **FIT)
    np.testing.assert_allclose(true.delta, ref, rtol=0.005)
    est = rotor.analyze_log(full, "60-2", **FIT)
    np.testing.assert_allclose(est.delta, ref, rtol=0.04)
    raw = rotor.analyze_log(full, "60-2", tooth_errors=None, **FIT)
    assert np.all(raw.delta > 1.2 * ref)
    # the orders 0.5 … 3 (0.42 … 6.9 rad/s), TDC given, every cycle: amplitude within 0.5 % + 0.01 rad/s (the edge
    # noise moves a cycle's order by about 0.004 rad/s; the means over the cycles agree within 0.06 %), phase
    # within 0.03 rad
    given = rotor.analyze_log(full, "60-2", tooth_errors=simulated_tooth_errors(), tdc_deg=-DEFAULT_GAP_DEG, **FIT)
    o = steady.orders(max_order=3)
    for q, amp, ph in zip(np.asarray(o.order), np.asarray(o.speed_amplitude_rad_s), np.asarray(o.speed_phase_rad)):
        np.testing.assert_allclose(given.amplitude_of(q), amp, rtol=0.005, atol=0.01)
        assert np.mean(given.amplitude_of(q)) == pytest.approx(amp, rel=0.002)
        j = int(np.flatnonzero(np.isclose(given.order, q))[0])
        assert np.max(np.abs(np.angle(np.exp(1j * (given.phase_rad[:, j] - ph))))) < 0.03


def test_other_speed_load_and_a_clean_wheel(tmp_path):
    """rpm and imep_scale are honoured: a clean wheel without noise (tooth_error_deg=0,
    noise_v=0) at 2400 rpm and 60 % charge gives the steady state's δ within 0.5 % with
    no correction at all, and the mean speed to 1e-5."""
    p = simulated_recording(
        tmp_path / "r.txt", rpm=2400, cycles=4, imep_scale=0.6, tooth_error_deg=0.0, noise_v=0.0, seed=3
    )
    a = rotor.analyze_log(p, "60-2", tooth_errors=None, **FIT)
    assert a.cycles == 4
    assert abs(np.mean(a.mean_rpm) / 2400 - 1) < 1e-5
    ref = float(rotor.steady_state(_charge_scaled(ENGINE, 0.6), 2400).delta)
    np.testing.assert_allclose(a.delta, ref, rtol=0.005)


def test_calibrate_and_diagnose_round_trip(full):
    """rotor.calibrate on the simulated full-load recording (the bench's sensor gain) finds the
    preset's inertia, the sensor offset and TDC; rotor.diagnose from the encoder column alone
    gives back the file's IMEP (5.148 bar). Energy-balance inertia within 2 % (measured +0.25 %),
    offset within 0.3 bar (the offset of V = 5·(0.115 + 0.00385·p[bar]) is −29.87 bar; measured
    −29.85), IMEP within 1 % (measured −0.26 %)."""
    cal = rotor.calibrate(ENGINE, full, wheel="60-2", columns=COLUMNS, pressure_gain=BENCH_GAIN_PA_PER_V)
    assert cal.fit["energy_balance_inertia_kgm2"] == pytest.approx(float(ENGINE.crankshaft.inertia_kgm2), rel=0.02)
    assert cal.pressure_offset_pa / 1e5 == pytest.approx(-0.115 / 0.00385, abs=0.3)
    assert cal.tdc_after_gap_deg == pytest.approx(-DEFAULT_GAP_DEG, abs=0.5)
    ident = rotor.diagnose(ENGINE, full, cal, columns="time,-,encoder_v")
    nominal = float(rotor.imep_pa(ENGINE))
    assert np.mean(ident.imep_pa[:, 0]) == pytest.approx(nominal, rel=0.01)
    assert not np.any(ident.misfire)


def test_deterministic_and_one_wheel_for_every_seed(tmp_path):
    a = simulated_recording(tmp_path / "a.txt", cycles=2)
    b = simulated_recording(tmp_path / "b.txt", cycles=2)
    c = simulated_recording(tmp_path / "c.txt", cycles=2, seed=5)
    assert a.read_bytes() == b.read_bytes() and a.read_bytes() != c.read_bytes()
    assert isinstance(a, type(tmp_path))
    # the same wheel in both: the tooth errors estimated from each agree (the seed draws only noise and start)
    kw = dict(engine_orders=(1, 2, 3, 4, 5, 6), **FIT)
    ta = rotor.analyze_log(a, "60-2", **kw).tooth_errors.errors_rad
    tc = rotor.analyze_log(c, "60-2", **kw).tooth_errors.errors_rad
    assert np.rad2deg(np.max(np.abs(ta - tc))) < 0.02


@pytest.mark.parametrize(
    "kw, words",
    [
        (dict(cycles=1), "cycles = 1"),
        (dict(cycles=2.5), "cycles = 2.5"),
        (dict(rpm=0), "rpm = 0"),
        (dict(rpm=-3000), "rpm = -3000"),
        (dict(rpm=float("nan")), "rpm = nan"),
        (dict(imep_scale=0.0), "imep_scale = 0"),
        (dict(imep_scale=0.01), "imep_scale = 0.01"),
        (dict(sample_rate_hz=20_000), "sample_rate_hz = 20000"),
        (dict(wheel="60"), "wheel = '60'"),
        (dict(wheel="sixty"), "wheel = 'sixty'"),
        (dict(tooth_error_deg=2.0), "tooth_error_deg = 2"),
        (dict(noise_v=-0.1), "noise_v = -0.1"),
        (dict(engine="no-such-engine"), "no-such-engine"),
        (dict(engine=3), "engine = 3"),
        (dict(seed=0.5), "seed = 0.5"),
    ],
)
def test_bad_arguments_are_clear_errors(tmp_path, kw, words):
    path = tmp_path / "r.txt"
    path.write_text("old\n")
    with pytest.raises(rotor.EngineError, match=None) as err:
        simulated_recording(path, **kw)
    assert isinstance(err.value, ValueError) and words in str(err.value)
    assert path.read_text() == "old\n"


def test_missing_folder_and_a_failed_write_leave_nothing(tmp_path, monkeypatch):
    with pytest.raises(rotor.EngineError, match="does not exist"):
        simulated_recording(tmp_path / "nowhere" / "r.txt")
    path = tmp_path / "r.txt"
    path.write_text("old\n")

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savetxt", boom)
    with pytest.raises(OSError):
        simulated_recording(path, cycles=2)
    assert path.read_text() == "old\n" and os.listdir(tmp_path) == ["r.txt"]
