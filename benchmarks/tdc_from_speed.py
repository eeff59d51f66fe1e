"""Accuracy of TDC from crank speed alone (rotor.diagnostics.phase.tdc_from_speed): simulated
recordings with the wheel mounted anywhere, and the real tue-4gb10 recordings against their
pressure channel.

    nice -n 19 .venv/bin/python benchmarks/tdc_from_speed.py [--seeds 3] [--repeats 3] \
        [--data ../shared/data] [--quick]

(1.5–3 min on 2 CPUs; ``--quick``: one seed, steady and cut only.)

**Simulated** (tue-single at 3000 rpm through a 60-2 wheel with ±0.1° tooth errors, the
wheel's gap moved 0/30/90/180° from the bench's 29.4° before TDC; each record starts at a
seeded angle in its first cycle): ``steady`` (8 cycles, constant load), ``cut`` (an
ignition cut of cycles 3–4), ``coast`` (no firing, a constant drag slowing the crank to
about 70 % of its speed over 8 cycles), each as tooth times with 20 ns of timer jitter,
``steady`` also with 200 ns (``steady-200ns``), and ``bench`` (steady, the raw analog bench
signal of :func:`rotor.diagnostics.synthetic.simulated_recording`, ten times the real
files' noise). Each record is analysed with its cycles cut at the gap (``tdc_deg=0``) and
the wheel's tooth errors estimated from the same record (``estimated``) or the true ones
(``true``), and fitted. Per case: the error of the TDC found (after the gap [deg], wrapped
to ±180°), whether the firing revolution is the simulated one (the cycle start, cut where
the fit puts it, within 10° of a simulated cycle start), the stated ± (``std_deg``), the
separation [σ] and R², each the median (and the worst) over ``--seeds`` seeds.

**Real** (``--data``/tue-4gb10, skipped when absent): each recording analysed from its
encoder column alone (cycles cut at the gap, its own tooth-error estimate) and fitted with
the engine file carrying the preset's own calibration (its inertia), against TDC from the
same recording's pressure channel (the polytropic fit of the compression with the
engine's compression and rod ratio, :func:`rotor.tdc_from_pressure`): the difference in
the firing TDC over the whole 720° cycle [deg].

**Time**: the wall time of one ``tdc_from_speed`` call (the engine's two steady states and
the fit) after compile, the median of ``--repeats`` calls on the first steady record; the
compile (the first call in the process less that median) apart.

Writes ``benchmarks/results/tdc_from_speed.json`` (every case and seed, the summary table,
the real recordings, the timing, the versions) and
``benchmarks/figures/tdc_from_speed.png`` (the error per case and offset; the real
recordings' residual against the offset), and prints the table.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy
from scipy.interpolate import CubicSpline

import rotor
from rotor.diagnostics.calibration_record import preset_calibration
from rotor.diagnostics.phase import tdc_from_speed
from rotor.diagnostics.synthetic import (
    DEFAULT_GAP_DEG,
    simulated_recording,
    simulated_tooth_errors,
    simulated_tooth_times,
)
from rotor.fileio import write_text_atomic

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT / ".." / "shared" / "data"
OUT = ROOT / "benchmarks" / "results" / "tdc_from_speed.json"
FIG = ROOT / "benchmarks" / "figures" / "tdc_from_speed.png"
RPM = 3000.0
CYCLES = 8
CUT = (3, 4)
OFFSETS = (0.0, 30.0, 90.0, 180.0)
TDC_DEG = -DEFAULT_GAP_DEG  # the bench's TDC after the gap [deg]
RECORDINGS = ("full_load", "half_load", "No_load")
PARITY_DEG = 10.0  # a cycle start within this of a simulated one: the right firing revolution


def wrap(x, period=360.0):
    return (x + period / 2) % period - period / 2


def runs(engine, quick):
    """The simulated runs: steady, ignition cut, coast-down (θ from 0 at TDC before intake)."""
    ss = rotor.steady_state(engine, RPM)
    load = rotor.ConstantLoad(float(ss.load_torque_Nm))
    cut = np.ones((CYCLES, 1))
    cut[list(CUT)] = 0.0
    out = {
        "steady": rotor.simulate(engine, rpm=RPM, cycles=CYCLES, load=load, step_deg=0.5, progress=False),
        "cut": rotor.simulate(engine, rpm=RPM, cycles=CYCLES, load=load, combustion=cut, step_deg=0.5, progress=False),
    }
    if not quick:
        # a constant drag that slows the crank to about 70 % of its speed over the run (no firing)
        e0 = 0.5 * float(rotor.mean_reduced_inertia(engine)) * (RPM / 30 * np.pi) ** 2
        drag = e0 * (1 - 0.7**2) / (CYCLES * float(engine.cycle_rad))
        out["coast"] = rotor.simulate(
            engine,
            rpm=RPM,
            cycles=CYCLES,
            load=rotor.ConstantLoad(drag),
            combustion=np.zeros((CYCLES, 1)),
            step_deg=0.5,
            progress=False,
        )
    return out


def first_edge_angle(gap_deg, start_deg, teeth_errors):
    """The crank angle [rad] of the first tooth edge at or after ``start_deg`` of a 60-2 wheel
    whose first edge after the gap sits at ``gap_deg`` (as simulated_tooth_times places them)."""
    w = rotor.Wheel(60, 2)
    gap, lo = np.deg2rad(gap_deg), np.deg2rad(start_deg)
    r0 = int(np.floor((lo - gap) / (2 * np.pi))) - 1
    rev = np.arange(r0, r0 + 4)
    ang = (gap + 2 * np.pi * rev[:, None] + w.pitch_rad * np.arange(w.edges_per_rev)[None, :] + teeth_errors).ravel()
    return float(ang[ang >= lo].min())


def right_revolution(path, fit, te, run, gap_deg, start_deg, true_te):
    """Whether the cycles cut where the fit puts TDC (and its firing revolution) start at a
    simulated cycle start (within PARITY_DEG)."""
    a2 = rotor.analyze_log(path, "60-2", tdc_deg=fit.tdc_after_gap_deg, firing=fit.firing_parity, tooth_errors=te)
    th, t = np.asarray(run.theta, dtype=np.float64), np.asarray(run.t, dtype=np.float64)
    keep = np.concatenate([[True], np.diff(th) > 0])
    t_of = CubicSpline(th[keep], t[keep])
    t0 = float(t_of(first_edge_angle(gap_deg, start_deg, true_te)))
    cyc = float(run.cycle_rad)
    starts = t_of(cyc * np.arange(int(th[-1] // cyc) + 1)) - t0
    dt = np.min(np.abs(starts[None, :] - np.asarray(a2.t_start_s)[:, None]), axis=1)
    return bool(np.all(dt * np.mean(a2.mean_omega) < np.deg2rad(PARITY_DEG)))


def fitted(engine, path, te_mode, true_offset, columns=None):
    """Analyse ``path`` with its cycles cut at the gap and fit; the figures of the fit."""
    te = simulated_tooth_errors() if te_mode == "true" else "estimate"
    a = rotor.analyze_log(path, "60-2", columns=columns, tdc_deg=0.0, tooth_errors=te)
    t0 = time.perf_counter()
    fit = tdc_from_speed(engine, a)
    wall = time.perf_counter() - t0
    return (
        fit,
        te,
        {
            "error_deg": float(wrap(fit.tdc_after_gap_deg - (TDC_DEG + true_offset))),
            "std_deg": fit.std_deg,
            "separation_sigma": fit.separation,
            "r2": fit.r2,
            "determined": fit.determined,
            "cycles": fit.cycles,
            "mean_rpm": fit.mean_rpm,
            "wall_s": wall,
        },
    )


def simulated(engine, seeds, quick, folder):
    sims = runs(engine, quick)
    scenarios = [("steady", "steady", 20e-9), ("cut", "cut", 20e-9)]
    if not quick:
        scenarios += [("coast", "coast", 20e-9), ("steady-200ns", "steady", 200e-9), ("bench", None, 0.0)]
    true_te = simulated_tooth_errors().errors_rad
    rows = []
    for label, run_name, jitter in scenarios:
        for off in OFFSETS:
            gap_deg = DEFAULT_GAP_DEG - off
            for seed in range(seeds):
                start_deg = 100.0 + 97.0 * seed  # anywhere in the first cycle
                path = folder / f"{label}_{off:g}_{seed}.txt"
                if run_name is None:  # the raw analog bench signal (starts where its seed puts it)
                    simulated_recording(path, engine, RPM, cycles=CYCLES, gap_deg=gap_deg, seed=seed)
                    columns = "time,pressure_v,encoder_v"
                else:
                    simulated_tooth_times(
                        path, sims[run_name], gap_deg=gap_deg, start_deg=start_deg, jitter_s=jitter, seed=seed
                    )
                    columns = None
                for te_mode in ("estimated", "true"):
                    fit, te, r = fitted(engine, path, te_mode, off, columns)
                    rev = (
                        right_revolution(path, fit, te, sims[run_name], gap_deg, start_deg, true_te)
                        if run_name is not None
                        else None
                    )
                    rows.append(
                        {
                            "case": label,
                            "offset_deg": off,
                            "tooth_errors": te_mode,
                            "seed": seed,
                            **r,
                            "right_revolution": rev,
                        }
                    )
                print(
                    f"  {label:13s} offset {off:5.0f}°  seed {seed}: error "
                    + ", ".join(f"{x['tooth_errors']} {x['error_deg']:+.2f}°" for x in rows[-2:]),
                    flush=True,
                )
    return rows


def summarise(rows):
    """Per case and tooth-error mode: median and worst |error| over offsets and seeds, etc."""
    out = []
    keys = sorted({(r["case"], r["tooth_errors"]) for r in rows}, key=lambda k: (k[0], k[1]))
    for c, te in keys:
        sel = [r for r in rows if r["case"] == c and r["tooth_errors"] == te]
        err = np.abs([r["error_deg"] for r in sel])
        revs = [r["right_revolution"] for r in sel if r["right_revolution"] is not None]
        out.append(
            {
                "case": c,
                "tooth_errors": te,
                "records": len(sel),
                "median_abs_error_deg": float(np.median(err)),
                "max_abs_error_deg": float(np.max(err)),
                "median_std_deg": float(np.median([r["std_deg"] for r in sel])),
                "max_std_deg": float(np.max([r["std_deg"] for r in sel])),
                "beyond_std": int(sum(abs(r["error_deg"]) > r["std_deg"] for r in sel)),
                "max_error_over_std": float(np.max([abs(r["error_deg"]) / r["std_deg"] for r in sel])),
                "min_separation_sigma": float(np.min([r["separation_sigma"] for r in sel])),
                "min_r2": float(np.min([r["r2"] for r in sel])),
                "determined": int(sum(r["determined"] for r in sel)),
                "right_revolution": None if not revs else int(sum(revs)),
                "revolution_checked": len(revs),
            }
        )
    return out


def real(engine, folder):
    cal = preset_calibration(engine)
    eng = cal[0].apply(engine) if cal is not None else engine
    cr = float(engine.pressure.compression_ratio)
    rod = float(engine.geometry.stroke_m) / 2 / float(engine.geometry.rod_length_m)
    out = {}
    for name in RECORDINGS:
        path = folder / f"{name}.txt"
        ap = rotor.analyze_log(path, "60-2", columns="time,pressure_v,encoder_v", compression_ratio=cr, rod_ratio=rod)
        a = rotor.analyze_log(path, "60-2", columns="time,-,encoder_v", tdc_deg=0.0)
        fit = tdc_from_speed(eng, a)
        p_firing = float(np.rad2deg(ap.cycle_start_rad[0])) + 360.0  # firing TDC, wheel angle [deg]
        diff = float(wrap(fit.firing_tdc_wheel_deg - p_firing, 720.0))
        out[name] = {
            "pressure_tdc_after_gap_deg": float(np.rad2deg(ap.tdc_rad)),
            "pressure_tdc_method": ap.tdc_method,
            "speed_tdc_after_gap_deg": fit.tdc_after_gap_deg,
            "speed_minus_pressure_deg": diff,
            "std_deg": fit.std_deg,
            "separation_sigma": fit.separation,
            "r2": fit.r2,
            "determined": fit.determined,
            "cycles": fit.cycles,
            "mean_rpm": fit.mean_rpm,
            "candidates_deg": fit.candidates_deg.tolist(),
            "residual": fit.residual.tolist(),
            "offset_deg": fit.offset_deg,
            "pressure_offset_deg": float(wrap(fit.offset_deg - diff, 720.0) % 720.0),
        }
        print(
            f"  {name:9s}: speed − pressure {diff:+6.1f}° (pressure {out[name]['pressure_tdc_after_gap_deg']:.1f}°, "
            f"speed {fit.tdc_after_gap_deg:.1f}° ± {fit.std_deg:.2f}°, R² {fit.r2:.3f}, "
            f"separation {fit.separation:.0f} σ)",
            flush=True,
        )
    return out


def timing(engine, folder, repeats):
    path = folder / "steady_0_0.txt"
    a = rotor.analyze_log(path, "60-2", tdc_deg=0.0)
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        tdc_from_speed(engine, a)
        walls.append(time.perf_counter() - t0)
    return statistics.median(walls), walls


def figure(summary_rows, rows, real_res, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rotor.plotting.common import save_figure

    fig, axes = plt.subplots(1, 2 if real_res else 1, figsize=(12 if real_res else 7, 4.5), layout="constrained")
    axes = np.atleast_1d(axes)
    ax = axes[0]
    cases = sorted({r["case"] for r in rows})
    for i, c in enumerate(cases):
        for j, te in enumerate(("estimated", "true")):
            sel = [r for r in rows if r["case"] == c and r["tooth_errors"] == te]
            x = np.array([OFFSETS.index(r["offset_deg"]) for r in sel]) + 0.12 * (i - len(cases) / 2) + 0.04 * j
            ax.plot(
                x,
                np.abs([r["error_deg"] for r in sel]),
                "o" if te == "estimated" else "x",
                color=f"C{i}",
                ms=4,
                label=f"{c} ({te} tooth errors)",
            )
    ax.set_xticks(range(len(OFFSETS)), [f"{o:g}°" for o in OFFSETS])
    ax.set_yscale("log")
    ax.set_xlabel("the wheel's gap moved by")
    ax.set_ylabel("|TDC error| [deg]")
    ax.set_title("simulated tue-single, 3000 rpm, 60-2 wheel")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    if real_res:
        ax = axes[1]
        for i, (name, r) in enumerate(real_res.items()):
            ax.plot(r["candidates_deg"], r["residual"], lw=0.9, color=f"C{i}", label=f"{name} (R² {r['r2']:.2f})")
            ax.axvline(r["pressure_offset_deg"], color=f"C{i}", ls=":", lw=1)
        ax.set_xlim(0, 720)
        ax.set_xticks(np.arange(0, 721, 90))
        ax.set_xlabel("offset of TDC from the cycle grid's start [deg] (dotted: the pressure channel's)")
        ax.set_ylabel("residual / fluctuation power [-]")
        ax.set_title("real tue-4gb10 recordings: the fit against the offset")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig.axes[0], path)


def table(summary_rows, real_res):
    lines = [
        "| case | tooth errors | records | median abs error | worst abs error | stated ± (median, worst) "
        "| error beyond ± | min separation | min R² | determined | firing revolution right |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for s in summary_rows:
        rev = "—" if s["right_revolution"] is None else f"{s['right_revolution']}/{s['revolution_checked']}"
        lines.append(
            f"| {s['case']} | {s['tooth_errors']} | {s['records']} | {s['median_abs_error_deg']:.2f}° | "
            f"{s['max_abs_error_deg']:.2f}° | {s['median_std_deg']:.2f}°, {s['max_std_deg']:.2f}° | "
            f"{s['beyond_std']} (max {s['max_error_over_std']:.1f}×) | {s['min_separation_sigma']:.0f} σ | {s['min_r2']:.3f} | {s['determined']}/{s['records']} | {rev} |"
        )
    if real_res:
        lines += [
            "",
            "| tue-4gb10 | pressure TDC | speed TDC | speed − pressure | stated ± | R² | separation |",
            "|---|---|---|---|---|---|---|",
        ]
        for name, r in real_res.items():
            lines.append(
                f"| {name} | {r['pressure_tdc_after_gap_deg']:.1f}° | {r['speed_tdc_after_gap_deg']:.1f}° | "
                f"{r['speed_minus_pressure_deg']:+.1f}° | {r['std_deg']:.2f}° | {r['r2']:.3f} | "
                f"{r['separation_sigma']:.0f} σ |"
            )
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3, help="seeds (start angle, noise) per case and offset")
    ap.add_argument("--repeats", type=int, default=3, help="timed calls after compile")
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--figure", type=Path, default=FIG)
    ap.add_argument("--quick", action="store_true", help="steady and cut only, one seed")
    args = ap.parse_args(argv)
    seeds = 1 if args.quick else args.seeds
    engine = rotor.load_engine("tue-single")
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="rotor-tdc-bench-") as tmp:
        folder = Path(tmp)
        # the first call compiles: time it on a steady record before anything else is fitted
        sims_first = runs(engine, True)["steady"]
        simulated_tooth_times(folder / "steady_0_0.txt", sims_first, start_deg=100.0)
        a = rotor.analyze_log(folder / "steady_0_0.txt", "60-2", tdc_deg=0.0)
        t0 = time.perf_counter()
        tdc_from_speed(engine, a)
        first = time.perf_counter() - t0
        med, walls = timing(engine, folder, args.repeats)
        print(f"tdc_from_speed: {med * 1e3:.0f} ms a call (median of {args.repeats}), compile {first - med:.1f} s")
        print("simulated recordings:", flush=True)
        rows = simulated(engine, seeds, args.quick, folder)
    summary_rows = summarise(rows)
    real_res = None
    if (args.data / "tue-4gb10").is_dir():
        print("real recordings (tue-4gb10):", flush=True)
        real_res = real(engine, args.data / "tue-4gb10")
    else:
        print(f"no tue-4gb10 recordings under {args.data}: the real comparison is skipped")
    print()
    print(table(summary_rows, real_res))
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
            "engine": "tue-single",
            "rpm": RPM,
            "cycles": CYCLES,
            "ignition_cut_cycles": list(CUT),
            "offsets_deg": list(OFFSETS),
            "seeds": seeds,
            "tooth_error_deg": 0.1,
            "true_tdc_after_gap_deg": TDC_DEG,
        },
        "timing": {"median_s": med, "runs_s": walls, "compile_s": first - med, "first_call_s": first},
        "summary": summary_rows,
        "cases": rows,
        "real": None
        if real_res is None
        else {k: {x: y for x, y in v.items() if x not in ("candidates_deg", "residual")} for k, v in real_res.items()},
        "wall_s": time.perf_counter() - t_start,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(args.out, json.dumps(res, indent=1) + "\n")
    figure(summary_rows, rows, real_res, args.figure)
    print(f"wrote {args.out} and {args.figure}")


if __name__ == "__main__":
    main()
