"""Flywheel design through the simulator against the textbook and against a bisection.

    nice -n 19 .venv/bin/python benchmarks/flywheel.py [--quick] [--repeats 5]

For the four-cylinder (4chn15) and six-cylinder (mwm6) presets, at δ targets from 0.002 to
0.1, and for two lists of operating points (the rated point alone, and idle to rated with
part-load fuelling at the lower speeds):

- ``design``: ``rotor.design_flywheel`` (Newton on log δ(log J), dδ/dJ by autodiff through
  ``rotor.steady_state``): the [crankshaft] inertia, the binding point, δ there;
- ``bisection``: the inertia with δ = δ_target at the binding point by bisection on δ(J),
  δ from ``steady_state(method="shooting")`` (an RK4 cycle map and Newton, not the closed
  form the design uses), to 1e-9 relative;
- ``time_domain_delta``: δ of the second cycle of ``rotor.simulate(method="time")`` (diffrax,
  adaptive) started on the designed steady state;
- ``textbook_ratio``: the textbook's [crankshaft] inertia (J₀ = L_excess/(δ·ω²) less the
  rods' and pistons' mean inertia) at the point where it asks most, over the design;
  ``textbook_rated_ratio``: the same from the rated point alone (the textbook's practice);
- ``timing``: the design's first call (compile and run, in a process that has made no other
  design) and the median of ``--repeats`` later calls, and a bisection on the same jitted
  closed-form δ(J) (``rotor.design.flywheel.DeltaOfInertia``) to the same tolerance as Newton's, for the ratio.

Writes ``benchmarks/results/flywheel.json`` and ``benchmarks/figures/flywheel_textbook.png``.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import rotor
from rotor.design.flywheel import DeltaOfInertia, OperatingPoint, with_crankshaft_inertia
from rotor.fileio import atomic_path
from rotor.units import rad_s_to_rpm

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "flywheel.json"
FIG = ROOT / "benchmarks" / "figures" / "flywheel_textbook.png"
DELTAS = [0.002, 0.005, 0.01, 0.02, 0.05, 0.1]
POINTS = {
    "4chn15": {
        "rated": [OperatingPoint(1250.0)],
        "idle to rated": [OperatingPoint(600.0, 0.25), OperatingPoint(900.0, 0.6), OperatingPoint(1250.0)],
    },
    "mwm6": {
        "rated": [OperatingPoint(2200.0)],
        "idle to rated": [OperatingPoint(800.0, 0.25), OperatingPoint(1500.0, 0.6), OperatingPoint(2200.0)],
    },
}


def shooting_delta(engine, J, p):
    return float(
        rotor.steady_state(
            with_crankshaft_inertia(engine, J), p.rpm, p.load, imep_scale=p.imep_scale, method="shooting"
        ).delta
    )


def bisect(f, target, lo, hi, rel):
    """The J in [lo, hi] with f(J) = target for a decreasing f, by bisection in log J; the
    number of evaluations."""
    n = 0
    while hi / lo - 1 > rel:
        mid = math.sqrt(lo * hi)
        n += 1
        lo, hi = (mid, hi) if f(mid) > target else (lo, mid)
    return math.sqrt(lo * hi), n


def case(engine, preset, label, points, delta):
    d = rotor.design_flywheel(engine, delta, points)
    J = d.crankshaft_inertia_kgm2
    p = next(q for q in points if q.rpm == d.binding_rpm)
    J_bis, n_bis = bisect(lambda j: shooting_delta(engine, j, p), delta, 0.7 * J, 1.4 * J, 1e-9)
    r = rotor.steady_state(with_crankshaft_inertia(engine, J), p.rpm, p.load, imep_scale=p.imep_scale)
    run = rotor.simulate(
        with_crankshaft_inertia(engine, J),
        rpm=rad_s_to_rpm(float(r.omega[0])),
        cycles=2,
        method="time",
        load=rotor.ConstantLoad(float(r.load_torque_Nm)),
        combustion=np.full((2, engine.cylinders), p.imep_scale),
        progress=False,
    )
    rated = next(pt for pt in d.points if pt.rpm == max(q.rpm for q in points))
    row = {
        "preset": preset,
        "points": label,
        "delta_target": delta,
        "crankshaft_inertia_kgm2": J,
        "binding_rpm": d.binding_rpm,
        "delta_achieved": d.delta_achieved,
        "bisection_inertia_kgm2": J_bis,
        "bisection_evaluations": n_bis,
        "design_vs_bisection": J / J_bis - 1,
        "shooting_delta_at_design": shooting_delta(engine, J, p),
        "time_domain_delta": float(run.delta_per_cycle[-1]),
        "textbook_inertia_kgm2": d.textbook_inertia_kgm2,
        "textbook_ratio": d.textbook_ratio,
        "textbook_rated_ratio": rated.textbook.crankshaft_inertia_kgm2 / J,
        "textbook_flywheel_kgm2": d.textbook.flywheel_kgm2,
        "textbook_mass_kg": d.textbook.mass_kg,
        "newton_steps": [pt.newton_steps for pt in d.points],
    }
    print(
        f"{preset:7} {label:14} δ={delta:<6g} J={J:9.4f} bind {d.binding_rpm:6g} rpm  vs bisection "
        f"{row['design_vs_bisection']:+.1e}  time-domain δ/target−1 {row['time_domain_delta'] / delta - 1:+.1e}  "
        f"textbook ×{d.textbook_ratio:.4f} (rated only ×{row['textbook_rated_ratio']:.4f})",
        flush=True,
    )
    return row


def timing(engine, points, delta, repeats):
    t = time.perf_counter()
    rotor.design_flywheel(engine, delta, points)
    first = time.perf_counter() - t
    runs = []
    for _ in range(repeats):
        t = time.perf_counter()
        d = rotor.design_flywheel(engine, delta, points)
        runs.append(time.perf_counter() - t)
    # the same problem by bisection on the same jitted closed-form δ(J), to Newton's tolerance
    ev = DeltaOfInertia(engine, "variable", None, 0.25)
    J = d.crankshaft_inertia_kgm2
    for p in points:  # compiled already by the design; warm the eager conversion too
        ev.delta(J, p)
    bis = []
    for _ in range(repeats):
        t = time.perf_counter()
        for p in points:
            bisect(lambda j: ev.delta(j, p), delta, 0.1 * J, 10 * J, 1e-10)
        bis.append(time.perf_counter() - t)
    return {
        "first_call_s": first,
        "design_median_s": statistics.median(runs),
        "bisection_median_s": statistics.median(bis),
        "bisection_over_design": statistics.median(bis) / statistics.median(runs),
    }


def figure(rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    for i, preset in enumerate(POINTS):
        for label, style in (("rated", "o-"), ("idle to rated", "s--")):
            rs = [r for r in rows if r["preset"] == preset and r["points"] == label]
            x = [r["delta_target"] for r in rs]
            ax.plot(x, [100 * (r["textbook_ratio"] - 1) for r in rs], style, color=f"C{i}", label=f"{preset}, {label}")
            if label == "idle to rated":
                bx.plot(
                    x,
                    [100 * (r["textbook_rated_ratio"] - 1) for r in rs],
                    style,
                    color=f"C{i}",
                    label=f"{preset}, {label}",
                )
    ax.set_title("textbook J₀ = L_excess/(δ·ω²) at each point, the largest", fontsize=9)
    bx.set_title("textbook at the rated point only (one turning-moment diagram)", fontsize=9)
    for a in (ax, bx):
        a.set_xscale("log")
        a.set_xlabel("target δ")
        a.axhline(0, color="k", lw=0.7)
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    ax.set_ylabel("textbook [crankshaft] inertia / design − 1 [%]")
    FIG.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(FIG) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="δ = 0.01 only, 2 repeats")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--figure-only", action="store_true", help="redraw the figure from the saved JSON")
    args = ap.parse_args()
    if args.figure_only:
        figure(json.loads(OUT.read_text())["rows"])
        return 0
    deltas = [0.01] if args.quick else DELTAS
    repeats = 2 if args.quick else args.repeats
    engines = {name: rotor.load_engine(name) for name in POINTS}
    timings = {name: timing(engines[name], POINTS[name]["idle to rated"], 0.01, repeats) for name in POINTS}
    for name, t in timings.items():
        print(
            f"{name}: first call {t['first_call_s']:.2f} s, then {t['design_median_s'] * 1e3:.0f} ms; bisection on "
            f"the same δ(J) {t['bisection_median_s'] * 1e3:.0f} ms ({t['bisection_over_design']:.1f}×)"
        )
    rows = [
        case(engines[name], name, label, pts, d)
        for name in POINTS
        for label, pts in POINTS[name].items()
        for d in deltas
    ]
    import jax
    import jaxlib

    out = {
        "rows": rows,
        "timing": timings,
        "worst_design_vs_bisection": max(abs(r["design_vs_bisection"]) for r in rows),
        "worst_time_domain": max(abs(r["time_domain_delta"] / r["delta_target"] - 1) for r in rows),
        "versions": {
            "jax": jax.__version__,
            "jaxlib": jaxlib.__version__,
            "python": platform.python_version(),
            "numpy": np.__version__,
            "rotor": rotor.__version__,
        },
        "machine": platform.platform(),
        "quick": args.quick,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(OUT) as tmp:
        Path(tmp).write_text(json.dumps(out, indent=2))
    if not args.quick:
        figure(rows)
    print(
        f"worst design vs bisection {out['worst_design_vs_bisection']:.1e}, worst time-domain δ "
        f"{out['worst_time_domain']:.1e}; wrote {OUT.relative_to(ROOT)}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
