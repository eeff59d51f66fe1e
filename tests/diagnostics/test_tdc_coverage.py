"""The uncertainty that TDC from the speed states is honest, and the check's verdict rests on it.

``benchmarks/tdc_coverage.py`` measures the coverage of ``std_deg`` on 240 simulated records
(and the real tue-4gb10 recordings); here a smaller matrix of the same kind holds it in the
suite, and the verdict is tested against the stated σ: "agrees" only within 3 σ."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import equinox as eqx
import numpy as np
import pytest
from conftest import SHARED_DATA

import rotor
from rotor.diagnostics.phase import AGREE_SIGMA, TdcVerdict, check_tdc, tdc_from_speed
from rotor.diagnostics.synthetic import simulated_tooth_times

PRESETS = ("tue-single", "4chn15", "mwm6", "v8")
WHEELS = ("60-2", "36-1", "60-1")
DATA = SHARED_DATA / "tue-4gb10"


@pytest.fixture(scope="module", autouse=True)
def _compilation_cache():
    """The test session's persistent compilation cache (conftest.py sets its folder): the
    steady states compiled here are those of tests/diagnostics/test_tdc_from_speed.py."""
    rotor.enable_compilation_cache()


def _steady_run(engine, rpm, load, cycles):
    """``cycles`` repetitions of the periodic steady state at ``rpm`` and ``load`` (a Wiebe
    cycle's charge scaled whole, a pressure table's combustion), θ from 0 at cylinder 1's TDC
    before intake."""
    if engine.pressure.charge_scalable:
        engine = eqx.tree_at(lambda e: e.pressure, engine, engine.pressure.scale_charge(load))
        load = 1.0
    ss = rotor.steady_state(engine, rpm, imep_scale=load)
    th1 = np.asarray(ss.theta, dtype=np.float64)
    t1 = np.asarray(ss.t, dtype=np.float64)
    cyc, period = float(ss.cycle_rad), float(np.asarray(ss.period_s))
    k = np.arange(cycles)[:, None]
    theta = np.append((th1[None, :] + k * cyc).ravel(), cycles * cyc)
    t = np.append((t1[None, :] - t1[0] + k * period).ravel(), cycles * period)
    return SimpleNamespace(theta=theta, t=t)


def _record(folder, i, preset, rng, engines):
    """One simulated record of the matrix and its true TDC after the gap [deg]."""
    engine = engines[preset]
    wheel = WHEELS[i % len(WHEELS)]
    rpm = float(rng.uniform(0.45, 1.3)) * float(engine.operating.rpm)
    load = float(rng.choice((0.25, 0.5, 1.0)))
    cycles = int(rng.choice((6, 8, 12)))
    tdc = float(rng.uniform(0.0, 360.0))
    run = _steady_run(engine, rpm, load, cycles + 3)
    cyc = float(np.rad2deg(engine.cycle_rad))
    start = cyc * float(rng.uniform(0.0, 1.0))
    path = simulated_tooth_times(
        folder / f"r{i}.txt",
        run,
        wheel=wheel,
        gap_deg=-tdc,
        tooth_error_deg=float(rng.choice((0.0, 0.1, 0.3))),
        jitter_s=float(rng.choice((20e-9, 200e-9, 1e-6))),
        start_deg=start,
        end_deg=start + cyc * (cycles + 1.0),
        seed=i,
    )
    return path, tdc, wheel


def _bounds(n):
    """The counts within ±1σ (lo, hi) and within ±3σ (lo3) that n records of an honest σ
    (coverage 0.60–0.76 at 1σ, 0.99 or more at 3σ) fall outside with a probability under 1 %
    each (binomial)."""
    from scipy.stats import binom

    lo = int(binom.ppf(0.01, n, 0.60))  # P(X < lo | p = 0.60) < 1 %
    hi = int(binom.isf(0.01, n, 0.76))  # P(X > hi | p = 0.76) < 1 %
    lo3 = int(binom.ppf(0.01, n, 0.99))
    return lo, hi, lo3


def test_the_stated_sigma_covers_the_true_tdc(tmp_path):
    """40 simulated records: 28 of the single cylinder (0.45–1.3 times its speed, a load of
    0.25, 0.5 or 1, the wheels 60-2, 36-1 and 60-1 mounted anywhere, tooth errors of 0–0.3°,
    timer jitter of 20 ns–1 µs, 6–12 cycles, the tooth errors estimated from the record) and
    4 each of the four-, six- and eight-cylinder presets.

    Where the speed determines TDC, the count of true TDCs within ±1σ and ±3σ must pass a
    binomial test of the claim (an honest σ covers 60–76 % at 1σ and 99 % or more at 3σ): a
    count outside the bounds comes up with a probability under 1 % each when the σ is honest
    (for 28 records: 11–26 within 1σ, 26 or more within 3σ). The σ of the fit's curvature
    alone (the engine model's error left out) covers a few of them; one inflated to agree with
    everything, all within 1σ. Alike cylinders leave up to order 4 too few orders to check the
    model: not determined, and their σ, that of an offset anywhere within the firing interval,
    covers the error within 3σ."""
    engines = {p: rotor.load_engine(p) for p in PRESETS}
    rng = np.random.default_rng(2027)
    presets = ["tue-single"] * 28 + ["4chn15", "mwm6", "v8"] * 4
    z, rows = [], []
    for i, preset in enumerate(presets):
        path, tdc, wheel = _record(tmp_path, i, preset, rng, engines)
        engine = engines[preset]
        a = rotor.analyze_log(path, wheel, tdc_deg=0.0, strokes=engine.strokes, cylinders=engine.cylinders)
        fit = tdc_from_speed(engine, a)
        period = min(fit.period_deg, 360.0)
        err = (fit.tdc_after_gap_deg - tdc + period / 2) % period - period / 2
        assert fit.std_deg > 0 and math.isfinite(fit.std_deg)
        if preset == "tue-single":
            assert fit.std_deg == pytest.approx(math.hypot(fit.std_statistical_deg, fit.std_model_deg))
        else:
            assert not fit.determined and "alike cylinders" in fit.reason
            assert abs(err) <= AGREE_SIGMA * fit.std_deg
        z.append(abs(err) / fit.std_deg)
        rows.append((preset, wheel, fit.determined, round(err, 2), round(fit.std_deg, 2)))
    det = np.array([r[2] for r in rows])
    zd = np.array(z)[det]
    assert det.sum() >= 20, rows
    lo, hi, lo3 = _bounds(int(det.sum()))
    within1, within3 = int(np.sum(zd <= 1.0)), int(np.sum(zd <= AGREE_SIGMA))
    assert lo <= within1 <= hi, (within1, (lo, hi), rows)
    assert within3 >= lo3, (within3, lo3, rows)


@pytest.fixture(scope="module")
def idle(tmp_path_factory):
    """The tue-single engine idling: 1200 rpm at a quarter of its charge, true TDC 29.4° after
    the gap, tooth times of 10 cycles through a 60-2 wheel."""
    engine = rotor.load_engine("tue-single")
    run = _steady_run(engine, 1200.0, 0.22, 12)
    path = simulated_tooth_times(
        tmp_path_factory.mktemp("idle") / "idle.txt", run, gap_deg=-29.4, start_deg=300.0, end_deg=300.0 + 11 * 720.0
    )
    return engine, path


def test_idle_is_not_put_early(idle):
    """At a quarter of the charge the motored part of the signature does not scale with the
    combustion (the exhaust and crankcase pressures stay): fitted with the full-charge
    signature, TDC came out 15° early with ± 3°. With the signature at the charge that fits
    best, within 1.5° and within its σ; the right TDC agrees, one 30° off does not."""
    engine, path = idle
    a = rotor.analyze_log(path, "60-2", tdc_deg=0.0)
    fit = tdc_from_speed(engine, a)
    assert fit.determined, fit.reason
    assert 0.1 < fit.charge_scale < 0.4
    err = fit.tdc_after_gap_deg - 29.4
    assert abs(err) < 1.5 and abs(err) <= AGREE_SIGMA * fit.std_deg
    right = check_tdc(tdc_from_speed(engine, rotor.analyze_log(path, "60-2", tdc_deg=29.4)), 29.4)
    assert right.verdict is TdcVerdict.AGREES and not right.corrected
    wrong = check_tdc(tdc_from_speed(engine, rotor.analyze_log(path, "60-2", tdc_deg=59.4)), 59.4)
    assert wrong.verdict is TdcVerdict.DISAGREES and wrong.corrected
    assert wrong.distance_sigma > AGREE_SIGMA
    assert "59.4°" in wrong.message and f"{wrong.fit.tdc_after_gap_deg:.1f}°" in wrong.message
    assert wrong.to_json_dict()["verdict"] == "disagrees" and right.to_json_dict()["verdict"] == "agrees"


def test_agrees_only_within_three_stated_sigma(idle):
    """The verdict follows the stated σ alone: the same distance agrees at 2.9 σ and disagrees
    at 3.1 σ, whatever the residual there; an undetermined fit keeps the given TDC unchecked."""
    engine, path = idle
    fit = tdc_from_speed(engine, rotor.analyze_log(path, "60-2", tdc_deg=35.0))
    dist = abs((fit.tdc_after_gap_deg - 35.0 + 180.0) % 360.0 - 180.0)
    assert dist > 3.0
    near = check_tdc(dataclasses.replace(fit, std_deg=dist / 2.9), 35.0)
    far = check_tdc(dataclasses.replace(fit, std_deg=dist / 3.1), 35.0)
    assert near.verdict is TdcVerdict.AGREES and near.used_deg == 35.0
    assert far.verdict is TdcVerdict.DISAGREES and far.used_deg == pytest.approx(fit.tdc_after_gap_deg)
    assert near.distance_sigma == pytest.approx(2.9) and far.distance_sigma == pytest.approx(3.1)
    loose = check_tdc(dataclasses.replace(fit, determined=False, reason="too few cycles"), 35.0)
    assert loose.verdict is TdcVerdict.UNDETERMINED and loose.used_deg == 35.0 and not loose.corrected
    assert {v.name for v in TdcVerdict} == {"AGREES", "DISAGREES", "UNDETERMINED", "FOUND"}


@pytest.mark.skipif(not DATA.is_dir(), reason="the tue-4gb10 recordings are not in ../shared/data")
@pytest.mark.parametrize("name", ["full_load", "half_load", "No_load"])
def test_real_recordings_state_the_model_error(name):
    """The real tue-4gb10 recordings, speed alone, the shipped calibration (TDC 29.4°, right
    within 1.5° by the pressure channel): the speed puts TDC 7–19° late (the engine file's
    cycle is not this engine's at part load), and its σ says so — the pressure's TDC within
    3 stated σ, most of σ the model's — so the calibration agrees within 3 σ: never "agrees"
    at 8 σ, never "corrected" to the speed's."""
    engine = rotor.load_engine("tue-single")
    cal = rotor.diagnostics.calibration_record.preset_calibration(engine)[0]
    path = DATA / f"{name}.txt"
    truth = float(
        np.rad2deg(
            rotor.analyze_log(
                path, "60-2", columns="time,pressure_v,encoder_v", compression_ratio=8.5, rod_ratio=27.5 / 84.2
            ).tdc_rad
        )
    )
    a = rotor.analyze_log(path, "60-2", columns="time,-,encoder_v", tdc_deg=cal.tdc_after_gap_deg)
    chk = check_tdc(tdc_from_speed(cal.apply(engine), a), cal.tdc_after_gap_deg)
    fit = chk.fit
    err = (fit.tdc_after_gap_deg - truth + 180.0) % 360.0 - 180.0
    assert abs(err) <= AGREE_SIGMA * fit.std_deg, (err, fit.std_deg)
    assert fit.std_model_deg > fit.std_statistical_deg
    assert chk.verdict is TdcVerdict.AGREES and chk.distance_sigma <= AGREE_SIGMA
