"""Edge and wheel throughput: 10⁶ tooth edges through rotor.analyze_log, on a 60-2 wheel (the
single-gap path) and a 36-2-1 wheel (the pattern follower, rotor.logs.pattern), and 10⁶
logic-analyser transitions (digital edges with glitch removal); the wheel-track stage
(:func:`rotor.logs.track.read_track`) on 10⁶ tooth times (wheel given and ``auto``) and on
an analog signal of 3×10⁷ samples (10⁶ edges at 30 samples a tooth; file parsing excluded)
with both edges tried, the wheel given and found (the level search).

    .venv/bin/python benchmarks/edges_throughput.py [--repeats 5]

Writes ``benchmarks/results/edges_throughput.json``: the median wall time of ``--repeats``
runs of each, every run's time, the median CPU time of the process (``time.process_time``:
on a shared machine the wall time also counts the waits for a core; the CPU time is what
an idle machine's wall time would be, near enough), and the versions.
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
from rotor.logs.digital import digital_edges
from rotor.logs.track import read_track
from rotor.logs.wheel import Wheel

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "edges_throughput.json"


def edges(w: Wheel, n_edges=1_000_000, rpm=3000.0, seed=0):
    revs = int(np.ceil(n_edges / w.edges_per_rev))
    ang = (0.1 + 2 * np.pi * np.arange(revs)[:, None] + w.tooth_angles_rad[None, :]).ravel()[:n_edges]
    w0 = rpm / 30 * np.pi
    t = (ang - 0.04 * np.sin(ang / 2) - 0.005 * np.sin(2 * ang)) / w0
    return t + np.random.default_rng(seed).normal(0, 20e-9, t.size)


def time_it(fn, repeats):
    """(median wall time [s], every run's wall time [s], median CPU time [s]) of ``repeats`` calls of ``fn``."""
    walls, cpus = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return statistics.median(walls), walls, statistics.median(cpus)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--samples", type=float, default=3e7, help="samples of the analog signal (default 3e7)")
    args = ap.parse_args(argv)
    res = {
        "versions": {
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "python": platform.python_version(),
            "rotor": rotor.__version__,
            "machine": platform.machine(),
            "cpus": __import__("os").cpu_count(),
        }
    }
    for name, w in (("60-2", Wheel(60, 2)), ("36-2-1", Wheel(36, 3, (2, 1), (16, 17)))):
        t = edges(w)
        log = rotor.Log.from_arrays(tooth_time_s=t)
        rotor.analyze_log(log, name, tdc_deg=0.0, firing=0)  # warm: imports, caches
        med, walls, cpu = time_it(lambda: rotor.analyze_log(log, name, tdc_deg=0.0, firing=0), args.repeats)
        res[f"analyze_{name}"] = {"tooth_edges": int(t.size), "median_s": med, "runs_s": walls, "median_cpu_s": cpu}
        print(f"{name}: 10^6 tooth edges analysed in {med:.3f} s wall, {cpu:.3f} s CPU (medians of {args.repeats})")
    # the wheel-track stage alone (rotor.logs.track.read_track): 10^6 tooth times, the wheel given and found
    t = edges(Wheel(60, 2))
    log = rotor.Log.from_arrays(tooth_time_s=t)
    for spec in ("60-2", "auto"):
        read_track(log, spec)
        med, walls, cpu = time_it(lambda: read_track(log, spec), args.repeats)
        res[f"read_track_teeth_{spec}"] = {
            "tooth_edges": int(t.size),
            "median_s": med,
            "runs_s": walls,
            "median_cpu_s": cpu,
        }
        print(f"read_track (wheel {spec}): 10^6 tooth times in {med:.3f} s wall, {cpu:.3f} s CPU")
    # an analog Hall signal, 30 samples a tooth pitch, both edges tried (edge="auto") and the wheel given
    n = int(args.samples)
    pos = np.arange(n) / 30.0  # wheel position [pitches]
    q = np.mod(np.floor(pos), 60)
    v = np.where((np.mod(pos, 1.0) < 0.45) & (q < 58), 4.0, -0.7) + np.random.default_rng(1).normal(0, 0.01, n)
    alog = rotor.Log.from_arrays(time=np.arange(n) * 1e-5, encoder_v=v)
    del pos, q, v
    med, walls, cpu = time_it(lambda: read_track(alog, "60-2"), max(1, min(args.repeats, 3)))
    res["read_track_analog"] = {"samples": n, "median_s": med, "runs_s": walls, "median_cpu_s": cpu}
    print(f"read_track (analog, both edges): {n:.3g} samples in {med:.3f} s wall, {cpu:.3f} s CPU")
    # the same signal with its wheel found: every level of the level search tried on both edges
    med, walls, cpu = time_it(lambda: read_track(alog, "auto"), max(1, min(args.repeats, 3)))
    res["read_track_analog_auto"] = {"samples": n, "median_s": med, "runs_s": walls, "median_cpu_s": cpu}
    print(f"read_track (analog, wheel found, level search): {n:.3g} samples in {med:.3f} s wall, {cpu:.3f} s CPU")
    t = edges(Wheel(36, 3, (2, 1), (16, 17)), 500_000)
    tt = np.sort(np.concatenate([t, t + 0.4 * np.median(np.diff(t))]))
    lv = (np.arange(tt.size) % 2 == 0).astype(float)
    med, walls, cpu = time_it(lambda: digital_edges(tt, lv), args.repeats)
    res["digital_edges"] = {"transitions": int(tt.size), "median_s": med, "runs_s": walls, "median_cpu_s": cpu}
    print(f"digital: 10^6 transitions in {med:.3f} s wall, {cpu:.3f} s CPU")
    OUT.parent.mkdir(parents=True, exist_ok=True)
    from rotor.fileio import write_text_atomic

    write_text_atomic(OUT, json.dumps(res, indent=1) + "\n")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
