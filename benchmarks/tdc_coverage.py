"""Coverage of the stated uncertainty of TDC from crank speed alone
(rotor.diagnostics.phase.tdc_from_speed): how often the true TDC lies within ±1σ and ±3σ
of the speed's estimate, on simulated recordings over the presets, speeds, loads, noise,
tooth errors and wheels, and on the real tue-4gb10 recordings against their pressure
channel.

    nice -n 10 .venv/bin/python benchmarks/tdc_coverage.py [--records 240] [--quick] \
        [--data ../shared/data]

(about 10 min on 2 shared CPUs; ``--quick``: 24 records.)

**Simulated** (``--records``, drawn with a fixed seed, the presets and wheels in turn): a
preset (tue-single, 4chn15, mwm6, v8) run by :func:`rotor.simulate` at 0.45–1.3 times its
operating speed under the constant load of its steady state, at a load (``imep_scale``)
of 0.25, 0.5 or 1 (a Wiebe cycle's whole charge scaled, a pressure table's combustion),
with or without 3 % cycle-to-cycle variation of the combustion
(:func:`rotor.combustion_pattern`), written as the tooth times of a 60-2, 60-1, 36-1 or
36-2-1 wheel (:func:`rotor.diagnostics.synthetic.simulated_tooth_times`; for 36-2-1,
whose teeth are not contiguous, the same construction on the wheel's tooth angles) mounted
at a random angle, with tooth-spacing errors of 0, 0.1 or 0.3° and 20 ns, 200 ns or 1 µs of
timer jitter, 6, 8 or 12 cycles starting anywhere in the second cycle of the run. Each
record is analysed with its cycles cut at the gap and the wheel's tooth errors estimated
from the record itself (as ``rotor diagnose`` does), and fitted; the error is the TDC
found less the true one, wrapped to the shift the speed cannot tell apart (alike
cylinders: 180° for the four-cylinder, 120° for the six, 90° for the V8; 360° for the
single, whose firing revolution is a separate question).

**Real** (``--data``/tue-4gb10, skipped when absent): each recording's encoder column
alone (wheel 60-2, cycles cut at the gap), fitted with the tue-single engine carrying the
preset's own calibration, against TDC from the same recording's pressure channel (the
polytropic fit of the compression with compression ratio 8.5 and rod ratio 27.5/84.2).

Writes ``benchmarks/results/tdc_coverage.json`` (every record, the coverage table, the
real recordings, the versions) and prints the tables.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import tempfile
import time
from pathlib import Path

import equinox as eqx
import numpy as np
import scipy
from scipy.interpolate import CubicSpline

import rotor
from rotor.diagnostics.phase import tdc_from_speed
from rotor.diagnostics.synthetic import simulated_tooth_times
from rotor.fileio import write_text_atomic
from rotor.logs.wheel import Wheel

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT / ".." / "shared" / "data"
OUT = ROOT / "benchmarks" / "results" / "tdc_coverage.json"
PRESETS = ("tue-single", "4chn15", "mwm6", "v8")
WHEELS = ("60-2", "36-1", "36-2-1", "60-1")
LOADS = (0.25, 0.5, 1.0)
JITTER_S = (20e-9, 200e-9, 1e-6)
TOOTH_ERROR_DEG = (0.0, 0.1, 0.3)
CYCLES = (6, 8, 12)
COV = (0.0, 0.03)
RUN_CYCLES = 15  # every run as long, so that each preset compiles once
RECORDINGS = ("full_load", "half_load", "No_load")


def wrap(x, period=360.0):
    return (x + period / 2) % period - period / 2


def wheel_of(spec):
    """A wheel with its tooth angles: 36-2-1 as on Ford's (the single gap half a revolution
    after the double one)."""
    if spec == "36-2-1":
        return Wheel(36, 3, gaps=(2, 1), layout=(16, 17))
    return rotor.parse_wheel(spec)


def tooth_times(path, run, spec, gap_deg, tooth_error_deg, jitter_s, start_deg, end_deg, seed):
    """The record's tooth-time log: simulated_tooth_times where the wheel's teeth follow its
    one gap, the same construction on the tooth angles of a wheel with several gaps."""
    if spec != "36-2-1":
        return simulated_tooth_times(
            path,
            run,
            wheel=spec,
            gap_deg=gap_deg,
            tooth_error_deg=tooth_error_deg,
            jitter_s=jitter_s,
            start_deg=start_deg,
            end_deg=end_deg,
            seed=seed,
        )
    w = wheel_of(spec)
    th, t = np.asarray(run.theta, dtype=np.float64), np.asarray(run.t, dtype=np.float64)
    keep = np.concatenate([[True], np.diff(th) > 0])
    th, t = th[keep], t[keep]
    lo, hi = np.deg2rad(start_deg), np.deg2rad(end_deg)
    gap = np.deg2rad(gap_deg)
    err = np.random.default_rng(0).uniform(-1.0, 1.0, w.edges_per_rev) * np.deg2rad(tooth_error_deg)
    err -= err.mean()
    rev = np.arange(int(math.floor((lo - gap) / (2 * np.pi))) - 1, int(math.ceil((hi - gap) / (2 * np.pi))) + 2)
    ang = (gap + 2 * np.pi * rev[:, None] + np.asarray(w.tooth_angles_rad)[None, :] + err[None, :]).ravel()
    ang = ang[(ang >= lo) & (ang <= hi)]
    times = CubicSpline(th, t)(ang) + np.random.default_rng(seed).normal(0.0, jitter_s, ang.size)
    np.savetxt(path, times - times[0], fmt="%.10f")
    return path


def draw(n, seed=2026):
    """The matrix: ``n`` records, presets and wheels in turn, the rest drawn."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        out.append(
            {
                "preset": PRESETS[i % len(PRESETS)],
                "wheel": WHEELS[(i // len(PRESETS)) % len(WHEELS)],
                "speed_factor": float(rng.uniform(0.45, 1.3)),
                "load": float(rng.choice(LOADS)),
                "cov": float(rng.choice(COV)),
                "jitter_s": float(rng.choice(JITTER_S)),
                "tooth_error_deg": float(rng.choice(TOOTH_ERROR_DEG)),
                "cycles": int(rng.choice(CYCLES)),
                "tdc_after_gap_deg": float(rng.uniform(0.0, 360.0)),
                "start_in_cycle": float(rng.uniform(0.0, 1.0)),
                "seed": i,
            }
        )
    return out


def simulated_run(engine, spec):
    """The run of one record (θ from 0 at cylinder 1's TDC before intake)."""
    rpm = spec["speed_factor"] * float(engine.operating.rpm)
    if engine.pressure.charge_scalable:
        eng = eqx.tree_at(lambda e: e.pressure, engine, engine.pressure.scale_charge(spec["load"]))
        scale = 1.0
    else:
        eng, scale = engine, spec["load"]
    ss = rotor.steady_state(eng, rpm, imep_scale=scale)
    pattern = rotor.combustion_pattern(
        RUN_CYCLES, int(engine.cylinders), imep_scale=scale, cov=spec["cov"], seed=spec["seed"]
    )
    run = rotor.simulate(
        eng,
        rpm=rpm,
        cycles=RUN_CYCLES,
        load=rotor.ConstantLoad(float(ss.load_torque_Nm)),
        combustion=pattern,
        step_deg=0.5,
        progress=False,
    )
    return run, rpm


def one(engines, spec, folder):
    engine = engines[spec["preset"]]
    run, rpm = simulated_run(engine, spec)
    cyc = float(np.rad2deg(engine.cycle_rad))
    start = cyc * (1.0 + spec["start_in_cycle"])
    end = start + cyc * (spec["cycles"] + 1.0)
    path = folder / f"rec{spec['seed']}.txt"
    tooth_times(
        path,
        run,
        spec["wheel"],
        -spec["tdc_after_gap_deg"],
        spec["tooth_error_deg"],
        spec["jitter_s"],
        start,
        end,
        spec["seed"],
    )
    a = rotor.analyze_log(
        path,
        spec["wheel"],
        tdc_deg=0.0,
        strokes=engine.strokes,
        cylinders=engine.cylinders,
    )
    t0 = time.perf_counter()
    fit = tdc_from_speed(engine, a)
    wall = time.perf_counter() - t0
    period = min(fit.period_deg, 360.0)
    err = float(wrap(fit.tdc_after_gap_deg - spec["tdc_after_gap_deg"], period))
    return {
        **spec,
        "rpm": rpm,
        "analysed_cycles": a.cycles,
        "error_deg": err,
        "std_deg": fit.std_deg,
        "std_statistical_deg": fit.std_statistical_deg,
        "std_model_deg": fit.std_model_deg,
        "charge_scale": fit.charge_scale,
        "period_deg": fit.period_deg,
        "r2": fit.r2,
        "separation_sigma": fit.separation,
        "determined": fit.determined,
        "wall_s": wall,
    }


def coverage(rows):
    z = np.array([abs(r["error_deg"]) / r["std_deg"] for r in rows])
    return {
        "records": len(rows),
        "within_1sigma": float(np.mean(z <= 1.0)) if len(z) else float("nan"),
        "within_3sigma": float(np.mean(z <= 3.0)) if len(z) else float("nan"),
        "median_abs_error_deg": float(np.median([abs(r["error_deg"]) for r in rows])) if rows else float("nan"),
        "median_std_deg": float(np.median([r["std_deg"] for r in rows])) if rows else float("nan"),
        "max_error_over_std": float(np.max(z)) if len(z) else float("nan"),
    }


def summarise(rows):
    det = [r for r in rows if r["determined"]]
    out = {"overall": coverage(rows), "determined": coverage(det), "by_preset": {}, "by_wheel": {}}
    for p in PRESETS:
        out["by_preset"][p] = coverage([r for r in rows if r["preset"] == p])
    for w in WHEELS:
        out["by_wheel"][w] = coverage([r for r in rows if r["wheel"] == w])
    out["undetermined"] = len(rows) - len(det)
    return out


def real(folder):
    from rotor.diagnostics.calibration_record import preset_calibration

    engine = rotor.load_engine("tue-single")
    cal = preset_calibration(engine)
    eng = cal[0].apply(engine) if cal is not None else engine
    out = {}
    for name in RECORDINGS:
        path = folder / f"{name}.txt"
        ap = rotor.analyze_log(
            path, "60-2", columns="time,pressure_v,encoder_v", compression_ratio=8.5, rod_ratio=27.5 / 84.2
        )
        a = rotor.analyze_log(path, "60-2", columns="time,-,encoder_v", tdc_deg=0.0)
        fit = tdc_from_speed(eng, a)
        truth = float(np.rad2deg(ap.tdc_rad))
        err = float(wrap(fit.tdc_after_gap_deg - truth))
        out[name] = {
            "pressure_tdc_after_gap_deg": truth,
            "speed_tdc_after_gap_deg": fit.tdc_after_gap_deg,
            "error_deg": err,
            "std_deg": fit.std_deg,
            "std_statistical_deg": fit.std_statistical_deg,
            "std_model_deg": fit.std_model_deg,
            "error_over_std": abs(err) / fit.std_deg,
            "charge_scale": fit.charge_scale,
            "r2": fit.r2,
            "determined": fit.determined,
            "calibration_tdc_deg": float(cal[0].tdc_after_gap_deg) if cal is not None else None,
        }
        print(
            f"  {name:9s}: speed {fit.tdc_after_gap_deg:.1f}° ± {fit.std_deg:.1f}° (statistical "
            f"{fit.std_statistical_deg:.1f}°, model {fit.std_model_deg:.1f}°), pressure {truth:.1f}°: "
            f"{err:+.1f}° = {abs(err) / fit.std_deg:.1f} σ",
            flush=True,
        )
    return out


def table(summary, real_res):
    def row(name, c):
        return (
            f"| {name} | {c['records']} | {c['within_1sigma']:.0%} | {c['within_3sigma']:.1%} | "
            f"{c['median_abs_error_deg']:.2f}° | {c['median_std_deg']:.2f}° | {c['max_error_over_std']:.1f} |"
        )

    lines = [
        "| records | n | within ±1σ | within ±3σ | median abs error | median σ | worst error/σ |",
        "|---|---|---|---|---|---|---|",
        row("all", summary["overall"]),
        row("determined", summary["determined"]),
    ]
    lines += [row(p, c) for p, c in summary["by_preset"].items()]
    lines += [row(w, c) for w, c in summary["by_wheel"].items()]
    if real_res:
        lines += [
            "",
            "| tue-4gb10 | pressure TDC | speed TDC ± σ (statistical, model) | error | error/σ |",
            "|---|---|---|---|---|",
        ]
        for name, r in real_res.items():
            lines.append(
                f"| {name} | {r['pressure_tdc_after_gap_deg']:.1f}° | {r['speed_tdc_after_gap_deg']:.1f}° ± "
                f"{r['std_deg']:.1f}° ({r['std_statistical_deg']:.1f}°, {r['std_model_deg']:.1f}°) | "
                f"{r['error_deg']:+.1f}° | {r['error_over_std']:.1f} |"
            )
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=240, help="simulated records (at least 200 for the table)")
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--quick", action="store_true", help="24 records")
    args = ap.parse_args(argv)
    n = 24 if args.quick else args.records
    engines = {p: rotor.load_engine(p) for p in PRESETS}
    t_start = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory(prefix="rotor-tdc-coverage-") as tmp:
        for spec in draw(n):
            r = one(engines, spec, Path(tmp))
            rows.append(r)
            print(
                f"  {len(rows):3d} {r['preset']:10s} {r['wheel']:6s} {r['rpm']:5.0f} rpm load {r['load']:.2f}: "
                f"error {r['error_deg']:+6.2f}° ± {r['std_deg']:.2f}° ({abs(r['error_deg']) / r['std_deg']:.1f} σ)"
                f"{'' if r['determined'] else ' (not determined)'}",
                flush=True,
            )
    summary = summarise(rows)
    real_res = None
    if (args.data / "tue-4gb10").is_dir():
        print("real recordings (tue-4gb10):", flush=True)
        real_res = real(args.data / "tue-4gb10")
    else:
        print(f"no tue-4gb10 recordings under {args.data}: the real comparison is skipped")
    print()
    print(table(summary, real_res))
    import jax
    import jaxlib

    res = {
        "versions": {
            "rotor": rotor.__version__,
            "jax": jax.__version__,
            "jaxlib": jaxlib.__version__,
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "python": platform.python_version(),
            "machine": platform.machine(),
            "cpus": os.cpu_count(),
        },
        "settings": {
            "records": n,
            "presets": list(PRESETS),
            "wheels": list(WHEELS),
            "loads": list(LOADS),
            "jitter_s": list(JITTER_S),
            "tooth_error_deg": list(TOOTH_ERROR_DEG),
            "cycles": list(CYCLES),
            "cov": list(COV),
        },
        "summary": summary,
        "records": rows,
        "real": real_res,
        "wall_s": time.perf_counter() - t_start,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(args.out, json.dumps(res, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
