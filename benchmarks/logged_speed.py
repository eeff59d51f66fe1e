"""Logged crankshaft speed: speed of the analysis and the real-data validation report.

    .venv/bin/python benchmarks/logged_speed.py [--data ../shared/data] [--repeats 5]

Writes ``benchmarks/results/logged_speed.json``:

- ``speed``: 10⁶ tooth edges of a 60-2 wheel (17 241 revolutions at 3000 rpm with a
  half-order and a second-order fluctuation, 20 ns jitter) through
  :func:`rotor.analyze_log` (gap detection, tooth-error estimate, angle-domain
  resampling, per-cycle orders and δ): median wall time of ``--repeats`` runs, and the
  same for the sampled encoder signal of a real recording (edge detection included);
- ``tue-4gb10``: per recording, the revolutions and teeth found, each cycle's mean rpm,
  δ with and without the tooth-error correction, the half-order amplitude, the TDC found
  from the pressure, and the tooth errors estimated.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

import numpy as np
import scipy

import rotor

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "logged_speed.json"
COLS = "time,pressure_v,encoder_v"
GEOM = dict(compression_ratio=8.5, rod_ratio=27.5 / 84.2)  # data README: stroke 55 mm, rod 84.2 mm, ε = 8.5


def synthetic_edges(n_edges=1_000_000, rpm=3000.0, seed=0):
    w = rotor.Wheel(60, 2)
    revs = int(np.ceil(n_edges / w.edges_per_rev))
    ang = (0.1 + 2 * np.pi * np.arange(revs)[:, None] + w.pitch_rad * np.arange(58)[None, :]).ravel()[:n_edges]
    w0 = rpm / 30 * np.pi
    # ω = w0 (1 + 0.02 cos(θ/2) + 0.01 cos 2θ) to first order: t = ∫dθ/ω
    t = (ang - 0.04 * np.sin(ang / 2) - 0.005 * np.sin(2 * ang)) / w0
    return t + np.random.default_rng(seed).normal(0, 20e-9, t.size)


def time_it(fn, repeats):
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        walls.append(time.perf_counter() - t0)
    return statistics.median(walls), walls, out


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=str(ROOT / ".." / "shared" / "data"))
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    result = {
        "versions": {
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "python": platform.python_version(),
            "rotor": rotor.__version__,
            "machine": platform.machine(),
            "cpus": __import__("os").cpu_count(),
        }
    }
    edges = synthetic_edges()
    log = rotor.Log.from_arrays(tooth_time_s=edges)
    med, walls, an = time_it(lambda: rotor.analyze_log(log, "60-2", tdc_deg=0.0, firing=0), args.repeats)
    result["speed"] = {
        "tooth_edges": int(edges.size),
        "cycles": an.cycles,
        "median_s": med,
        "runs_s": walls,
        "edges_per_s": edges.size / med,
        "check_half_order_rad_s": float(an.amplitude_of(0.5).mean()),
        "check_half_order_expected_rad_s": 0.02 * 3000 / 30 * np.pi,
    }
    print(f"10^6 tooth edges: {med:.3f} s (median of {args.repeats}), {an.cycles} cycles")
    tue = Path(args.data) / "tue-4gb10"
    if tue.is_dir():
        rep = {}
        for name in ("No_load", "half_load", "full_load"):
            path = tue / f"{name}.txt"
            med, walls, a = time_it(lambda: rotor.analyze_log(path, "60-2", columns=COLS, **GEOM), args.repeats)
            raw = rotor.analyze_log(path, "60-2", columns=COLS, tooth_errors=None, **GEOM)
            w = a.track.to_json_dict()
            per_rev = np.bincount(a.track.rev[a.track.rev >= 0])[:-1]
            rep[name] = {
                "wall_s_with_reading": med,
                "edges": w["edges"],
                "complete_revolutions": w["complete_revolutions"],
                "teeth_per_complete_revolution": sorted(set(int(x) for x in per_rev)),
                "gap_period_ratio": w["gap_period_ratio"],
                "cycles": a.cycles,
                "mean_rpm_per_cycle": [round(float(x), 2) for x in a.mean_rpm],
                "mean_rpm": float(a.mean_rpm.mean()),
                "delta_per_cycle": [round(float(x), 5) for x in a.delta],
                "delta_mean": float(a.delta.mean()),
                "delta_std": float(a.delta.std(ddof=1)),
                "delta_uncorrected_mean": float(raw.delta.mean()),
                "half_order_amplitude_rad_s_mean": float(a.amplitude_of(0.5).mean()),
                "half_order_amplitude_rad_s_std": float(a.amplitude_of(0.5).std(ddof=1)),
                "first_order_amplitude_rad_s_mean": float(a.amplitude_of(1.0).mean()),
                "half_order_uncorrected_rad_s_mean": float(raw.amplitude_of(0.5).mean()),
                "tdc_after_gap_deg": float(np.rad2deg(a.tdc_rad)),
                "tdc_method": a.tdc_method,
                "firing_parity": a.firing_parity,
                "tooth_errors_deg_first_last": [
                    float(a.tooth_errors.errors_deg[0]),
                    float(a.tooth_errors.errors_deg[-1]),
                ],
                "tooth_errors_rms_deg": float(np.rad2deg(a.tooth_errors.rms_rad)),
                "engine_orders_left_out": list(a.tooth_errors.engine_orders),
            }
            print(
                f"{name}: {a.cycles} cycles, {a.mean_rpm.mean():.1f} rpm, δ {a.delta.mean():.4f} "
                f"(uncorrected {raw.delta.mean():.4f}), half order {a.amplitude_of(0.5).mean():.3f} rad/s, "
                f"TDC {np.rad2deg(a.tdc_rad):.2f}°, {med:.3f} s"
            )
        errs = np.array(
            [
                rotor.analyze_log(tue / f"{n}.txt", "60-2", columns=COLS, **GEOM).tooth_errors.errors_deg
                for n in ("No_load", "half_load", "full_load")
            ]
        )
        rep["tooth_errors_spread_across_recordings_deg"] = {
            "max_abs_from_mean": float(np.max(np.abs(errs - errs.mean(0)))),
            "rms_from_mean": float(np.sqrt(np.mean((errs - errs.mean(0)) ** 2))),
        }
        result["tue-4gb10"] = rep
    else:
        result["tue-4gb10"] = f"not found at {tue}"
    OUT.parent.mkdir(parents=True, exist_ok=True)
    from rotor.fileio import write_text_atomic

    write_text_atomic(OUT, json.dumps(result, indent=1) + "\n")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
