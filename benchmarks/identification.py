"""Model-based identification (rotor.identify): IMEP error and misfire detection over speed
and load, and the time to identify 100 cycles.

    nice -n 19 .venv/bin/python benchmarks/identification.py [--cycles 40] [--seeds 2] [--repeats 5]

Each case: a preset (4chn15, mwm6) at a speed and a load (the combustion scaled to that
fraction of the engine file's, the load torque balancing it at the steady speed), each
cylinder's IMEP drawn uniformly within ±10 % of it, 2 % cycle-to-cycle variation, random
misfires (3 % of the firings), simulated (rotor.simulate), turned into the tooth times of a
60-2 wheel with ±0.2° tooth errors and 20 ns timer jitter, analysed (rotor.analyze_log with
the wheel's errors from a coast-down calibration) and identified. Also coast-downs (no
firing at all) of both presets.

Writes ``benchmarks/results/identification.json``:

- ``cases``: per engine, rpm and load: the IMEP error of every firing relative to the
  cylinder's nominal IMEP (max, rms, 95th percentile) [%], the largest error of a
  cylinder's mean IMEP over the record [%], the misfires and normal firings
  counted, and the misses and false alarms at the default threshold;
- ``summary``: the IMEP error by engine and speed and by engine and load;
- ``misfire_rates``: miss and false-alarm rates against the threshold, over all cases at
  loads of 20 % and up and over the 10 % cases apart;
- ``coast_down``: firings flagged out of all, the largest |scale| and index;
- ``timing``: 100 cycles of each preset identified, after compile: median of
  ``--repeats`` runs; the compile (first call); versions of jax, jaxlib, optimistix, numpy.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

import rotor
from rotor.logs.wheel import TWO_PI
from rotor.units import RPM_PER_RAD_S

sys.path.insert(0, str(Path(__file__).resolve().parent))
import synthetic_wheel  # noqa: E402
from synthetic_wheel import WHEEL  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "identification.json"
GAP_DEG = -60.0
SPEEDS = {"4chn15": [800.0, 1250.0, 1800.0], "mwm6": [1200.0, 1700.0, 2200.0]}
LOADS = [0.1, 0.2, 0.5, 1.0]
THRESHOLDS = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]


def tooth_times(t_of_theta, lo, hi, gap, rng, jitter_s=20e-9):
    return synthetic_wheel.tooth_times(t_of_theta, lo, hi, gap, rng, jitter_s)


def calibration():
    """The wheel's errors from a bare-wheel coast-down 3000 → 500 rpm (as tests/logs/test_analyze_roundtrip.py)."""
    edges = synthetic_wheel.coast_down_edges(20e-9)
    return rotor.estimate_tooth_errors(rotor.locate_teeth(edges, WHEEL), engine_orders=())


def analyse(res, te, seed):
    theta, t = np.asarray(res.theta), np.asarray(res.t)
    edges = tooth_times(CubicSpline(theta, t), theta[0], theta[-1], np.deg2rad(GAP_DEG), np.random.default_rng(seed))
    first_ref = np.deg2rad(GAP_DEG) + TWO_PI * np.ceil((theta[0] - np.deg2rad(GAP_DEG)) / TWO_PI)
    parity = int(np.floor((TWO_PI - first_ref) / TWO_PI)) % 2
    an = rotor.analyze_log(
        rotor.Log.from_arrays(tooth_time_s=edges), WHEEL, tdc_deg=-GAP_DEG, firing=parity, tooth_errors=te
    )
    P = res.points_per_cycle
    t_sim = np.asarray(res.t)[: res.uniform_cycles * P : P]
    k = np.array([int(np.argmin(np.abs(t_sim - t0))) for t0 in an.t_start_s])
    return an, k


def run_case(name, rpm, load, cycles, seed, te):
    e = rotor.load_engine(name)
    n = e.cylinders
    rng = np.random.default_rng(1000 * seed + int(rpm) + int(100 * load))
    s = load * rng.uniform(0.9, 1.1, n)
    st = rotor.steady_state(e, rpm=rpm, imep_scale=s)
    comb = rotor.combustion_pattern(
        cycles, n, imep_scale=s, cov=0.02, misfire_rate=0.03, seed=int(rng.integers(1 << 30))
    )
    res = rotor.simulate(
        e,
        rpm=float(st.omega[0]) * RPM_PER_RAD_S,
        cycles=cycles,
        load=rotor.ConstantLoad(float(st.load_torque_Nm)),
        step_deg=0.25,
        combustion=comb,
        progress=False,
    )
    an, k = analyse(res, te, seed)
    idf = rotor.identify(e, an)
    truth = comb[k]
    tr = rotor.crank_train(e)
    imep_true = np.asarray(tr.imep_motored_pa) + truth * np.asarray(tr.imep_combustion_pa)
    ok = idf.identified
    err_all = (idf.imep_pa - imep_true) / idf.imep_nominal_pa
    err = err_all[ok]
    normal = ok & (truth > 0)
    cyl_mean = np.array([err_all[normal[:, c], c].mean() for c in range(n)])  # each cylinder's mean IMEP
    mis = (truth == 0)[ok]
    index = idf.contribution[ok]
    return {
        "engine": name,
        "rpm": rpm,
        "load": load,
        "seed": seed,
        "cycles": int(idf.cycles),
        "firings": int(ok.sum()),
        "misfires": int(mis.sum()),
        "imep_error_max_pct": float(100 * np.abs(err).max()),
        "imep_error_rms_pct": float(100 * np.sqrt(np.mean(err**2))),
        "imep_error_p95_pct": float(100 * np.percentile(np.abs(err), 95)),
        "cylinder_mean_imep_error_max_pct": float(100 * np.abs(cyl_mean).max()),
        "missed": int(np.sum(mis & ~idf.misfire[ok])),
        "false_alarms": int(np.sum(~mis & idf.misfire[ok])),
        "index_normal_min": float(index[~mis].min()),
        "index_misfire_max": float(index[mis].max()) if mis.any() else None,
        "rms_residual_rad_s": idf.rms_residual,
        "r2": idf.fit_r2,
        "scale_std_median": float(np.median(idf.scale_std)),
        "_index": index,
        "_mis": mis,
    }


def coast_down(name, te):
    e = rotor.load_engine(name)
    rpm = float(e.operating.rpm)
    cycles = 12
    # a constant drag that slows the crankshaft to 70 % of its speed over the run
    e0 = 0.5 * float(rotor.mean_reduced_inertia(e)) * (rpm / 30 * np.pi) ** 2
    load = e0 * (1 - 0.7**2) / (cycles * float(e.cycle_rad))
    res = rotor.simulate(
        e,
        rpm=rpm,
        cycles=cycles,
        load=rotor.ConstantLoad(load),
        step_deg=0.25,
        combustion=np.zeros((cycles, e.cylinders)),
        progress=False,
    )
    an, _ = analyse(res, te, 5)
    idf = rotor.identify(e, an)
    return {
        "engine": name,
        "rpm_first_last": [float(an.mean_rpm[0]), float(an.mean_rpm[-1])],
        "firings": int(idf.identified.sum()),
        "flagged": int(idf.misfire[idf.identified].sum()),
        "max_abs_scale": float(np.abs(idf.scale).max()),
        "max_abs_index": float(np.abs(idf.contribution).max()),
        "load_torque_Nm": load,
        "load_found_Nm_mean": float(idf.load_torque_Nm.mean()),
        "notes": list(idf.notes),
    }


def timing(name, te, repeats):
    e = rotor.load_engine(name)
    n = e.cylinders
    comb = rotor.combustion_pattern(104, n, imep_scale=np.linspace(0.9, 1.1, n), misfire_rate=0.02, seed=3)
    st = rotor.steady_state(e, imep_scale=np.linspace(0.9, 1.1, n))
    res = rotor.simulate(
        e,
        rpm=float(st.omega[0]) * RPM_PER_RAD_S,
        cycles=104,
        load=rotor.ConstantLoad(float(st.load_torque_Nm)),
        step_deg=0.25,
        combustion=comb,
        progress=False,
    )
    an, k = analyse(res, te, 3)
    sel = k[:100]
    an100 = _first_cycles(an, 100)
    t0 = time.perf_counter()
    idf = rotor.identify(e, an100)
    first = time.perf_counter() - t0
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        idf = rotor.identify(e, an100)
        walls.append(time.perf_counter() - t0)
    found = idf.misfires()
    truth = [(int(a) + 1, int(b) + 1) for a, b in np.argwhere(comb[sel] == 0)]  # counted from 1, as misfires()
    return {
        "engine": name,
        "cycles": idf.cycles,
        "points_per_cycle": an100.points_per_cycle,
        "blocks": idf.blocks,
        "first_call_s": first,
        "median_s": statistics.median(walls),
        "runs_s": walls,
        "misfires_true": len(truth),
        "misfires_found_equal": found == truth,
    }


def _first_cycles(an, c):
    import dataclasses

    per_cycle = ("t_start_s", "mean_omega", "delta", "amplitude_rad_s", "phase_rad", "omega", "cycle_start_rad")
    return dataclasses.replace(an, **{f: getattr(an, f)[:c] for f in per_cycle})


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--cycles", type=int, default=40)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    import equinox
    import jax
    import jaxlib
    import optimistix

    result = {
        "versions": {
            "jax": jax.__version__,
            "jaxlib": jaxlib.__version__,
            "optimistix": optimistix.__version__,
            "equinox": equinox.__version__,
            "numpy": np.__version__,
            "python": platform.python_version(),
            "rotor": rotor.__version__,
            "machine": platform.machine(),
            "cpus": os.cpu_count(),
        },
        "setup": {
            "wheel": "60-2",
            "tooth_errors_deg": 0.2,
            "jitter_s": 20e-9,
            "imep_spread": "±10 % uniform",
            "cov": 0.02,
            "misfire_rate": 0.03,
            "cycles_simulated": args.cycles,
            "seeds": args.seeds,
            "threshold": rotor.diagnostics.identification.MISFIRE_THRESHOLD,
        },
    }
    te = calibration()
    cases = []
    for name, speeds in SPEEDS.items():
        for rpm in speeds:
            for load in LOADS:
                for seed in range(args.seeds):
                    c = run_case(name, rpm, load, args.cycles, seed, te)
                    cases.append(c)
                    print(
                        f"{name} {rpm:6.0f} rpm load {load:4.0%} seed {seed}: IMEP error max "
                        f"{c['imep_error_max_pct']:.2f} % rms {c['imep_error_rms_pct']:.2f} %; misfires "
                        f"{c['misfires']}, missed {c['missed']}, false {c['false_alarms']}; index normal ≥ "
                        f"{c['index_normal_min']:.3f}",
                        flush=True,
                    )
    summary = {}
    for name in SPEEDS:
        mine = [c for c in cases if c["engine"] == name]
        summary[name] = {
            "by_rpm": {
                str(r): {
                    "max_pct": max(c["imep_error_max_pct"] for c in mine if c["rpm"] == r),
                    "rms_pct": float(np.sqrt(np.mean([c["imep_error_rms_pct"] ** 2 for c in mine if c["rpm"] == r]))),
                }
                for r in SPEEDS[name]
            },
            "by_load": {
                str(ld): {
                    "max_pct": max(c["imep_error_max_pct"] for c in mine if c["load"] == ld),
                    "rms_pct": float(np.sqrt(np.mean([c["imep_error_rms_pct"] ** 2 for c in mine if c["load"] == ld]))),
                }
                for ld in LOADS
            },
        }
    result["summary"] = summary
    rates = {}
    for label, sel in (("load_20pct_and_up", lambda c: c["load"] >= 0.2), ("load_10pct", lambda c: c["load"] < 0.2)):
        idx = np.concatenate([c["_index"] for c in cases if sel(c)])
        mis = np.concatenate([c["_mis"] for c in cases if sel(c)])
        rates[label] = {
            "misfires": int(mis.sum()),
            "normal_firings": int((~mis).sum()),
            "by_threshold": [
                {
                    "threshold": t,
                    "miss_rate": float(np.mean(idx[mis] >= t)) if mis.any() else None,
                    "false_alarm_rate": float(np.mean(idx[~mis] < t)),
                }
                for t in THRESHOLDS
            ],
            "index_normal_min": float(idx[~mis].min()),
            "index_misfire_max": float(idx[mis].max()) if mis.any() else None,
        }
        print(
            label,
            rates[label]["misfires"],
            "misfires,",
            rates[label]["normal_firings"],
            "normal; index normal ≥",
            f"{rates[label]['index_normal_min']:.3f}, misfire ≤ {rates[label]['index_misfire_max']}",
        )
    result["misfire_rates"] = rates
    for c in cases:
        del c["_index"], c["_mis"]
    result["cases"] = cases
    result["coast_down"] = [coast_down(name, te) for name in SPEEDS]
    for c in result["coast_down"]:
        print("coast-down", c["engine"], f"{c['flagged']}/{c['firings']} flagged, max |scale| {c['max_abs_scale']:.4f}")
    result["timing"] = [timing(name, te, args.repeats) for name in SPEEDS]
    for t in result["timing"]:
        print(
            f"timing {t['engine']}: {t['cycles']} cycles in {t['median_s'] * 1e3:.0f} ms (median of {args.repeats}); "
            f"first call {t['first_call_s']:.1f} s"
        )
    OUT.parent.mkdir(parents=True, exist_ok=True)
    from rotor.fileio import write_text_atomic

    write_text_atomic(OUT, json.dumps(result, indent=1) + "\n")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
