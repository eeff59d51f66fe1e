"""Markdown tables for benchmarks/README.md from the JSON the benchmark scripts write.

    .venv/bin/python benchmarks/report.py      # reads benchmarks/results/*.json

Reads work_precision.json (and work_precision_4deg.json if present: the "rotor closed 4°"
family and numba run apart; that ratio is taken within that run), compile_time.json;
prints the tables, nothing measured here.
"""

from __future__ import annotations

import json
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
LEVELS = (1e-3, 1e-6, 1e-9)


def load(name):
    path = RESULTS / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else None


def fmt_s(x):
    return f"{x * 1e3:.3g} ms" if x < 1 else f"{x:.3g} s"


def best(rows, families, level):
    ok = [r for r in rows if r["family"] in families and "median_s" in r and r["error"]["omega_rel"] <= level]
    return min(ok, key=lambda r: r["median_s"]) if ok else None


def families(rows):
    return list(dict.fromkeys(r["family"] for r in rows if not r["family"].startswith("model")))


def work_precision(wp, extra):
    print(
        f"Versions: {', '.join(f'{k} {v}' for k, v in wp['versions'].items())}. "
        f"`import rotor`: {wp['import_rotor']['median_s']:.2f} s (whole process).\n"
    )
    print(
        "At error ω ≤ 1e-6 (max |ω − ω_ref| / mean ω over the last cycle), the fastest measured setting "
        "of each group, median wall time after compile:\n"
    )
    print(
        "| preset | cycles | rotor (1° samples) | rotor, 4° samples | best scipy | numba RK4 | scipy / rotor | "
        "rotor / numba (1°; 4°) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, p in wp["presets"].items():
        for n, res in p["horizons"].items():
            rows = res["runs"]
            more = extra["presets"].get(name, {}).get("horizons", {}).get(n, {}).get("runs", []) if extra else []
            r = best(rows, ("rotor closed", "rotor grid", "rotor angle", "rotor time"), 1e-6)
            r4 = best(rows + more, ("rotor closed 4°",), 1e-6)
            s = best(rows, ("scipy RK45", "scipy DOP853", "scipy LSODA"), 1e-6)
            nb = best(rows, ("numba RK4",), 1e-6)
            nb4 = best(more, ("numba RK4",), 1e-6) if more else nb  # the 4° ratio within its own run
            skipped = [x for x in rows if x["family"].startswith("scipy") and x.get("skipped")]

            def cell(b):
                return (
                    f"{b['family'].replace('rotor ', '').replace('scipy ', '')} {b['setting']}: "
                    f"{fmt_s(b['median_s'])} ({b['error']['omega_rel']:.0e})"
                    if b
                    else "—"
                )

            scipy_cell = (
                cell(s)
                if s
                else (
                    "not within the cap"
                    + (f" (predicted ≥ {min(x['predicted_s'] for x in skipped):.0f} s)" if skipped else "")
                    if int(n) <= wp.get("scipy_max_cycles", 1000)
                    else "not run"
                )
            )
            ratio_s = f"{s['median_s'] / r['median_s']:.0f}×" if s and r else "—"
            ratio_n = (
                (f"{r['median_s'] / nb['median_s']:.1f}" if r and nb else "—")
                + "; "
                + (f"{r4['median_s'] / nb4['median_s']:.1f}" if r4 and nb4 else "—")
            )
            print(f"| {name} | {n} | {cell(r)} | {cell(r4)} | {scipy_cell} | {cell(nb)} | {ratio_s} | {ratio_n} |")
    print(
        "\nThe cheapest setting of every family per accuracy level (1000 cycles where measured, else the "
        "longest horizon), median time:\n"
    )
    print("| preset | family | " + " | ".join(f"ω ≤ {lv:g}" for lv in LEVELS) + " |")
    print("|---|---|" + "---|" * len(LEVELS))
    for name, p in wp["presets"].items():
        n = "1000" if "1000" in p["horizons"] else list(p["horizons"])[-1]
        rows = p["horizons"][n]["runs"] + (
            extra["presets"].get(name, {}).get("horizons", {}).get(n, {}).get("runs", []) if extra else []
        )
        for fam in families(rows):
            cells = []
            for lv in LEVELS:
                b = best(rows, (fam,), lv)
                cells.append(f"{b['setting']}: {fmt_s(b['median_s'])}" if b else "—")
            print(f"| {name} ({n}) | {fam} | " + " | ".join(cells) + " |")
    print("\nCompile time of rotor's runs in this study (first call − median, in-process, no cache):")
    for name, p in wp["presets"].items():
        c = [res["summary"]["rotor_compile_s"] for res in p["horizons"].values()]
        print(f"- {name}: {min(x['min'] for x in c):.1f}–{max(x['max'] for x in c):.1f} s")


def compile_table(ct):
    print(
        f"\n`import rotor`: {ct['import_rotor']['median_s']:.2f} s (median of {ct['import_rotor']['repeats']}, "
        "process minus an empty one).\n"
    )
    entries = list(next(iter(ct["presets"].values())))
    print("| preset | " + " | ".join(f"{e}: cold / warm" for e in entries) + " |")
    print("|---|" + "---|" * len(entries))
    for name, p in ct["presets"].items():
        print(
            f"| {name} | "
            + " | ".join(f"{p[e]['cold']['compile_s']:.1f} / {p[e]['warm']['compile_s']:.1f} s" for e in entries)
            + " |"
        )


def main():
    wp = load("work_precision")
    if wp:
        work_precision(wp, load("work_precision_4deg"))
    ct = load("compile_time")
    if ct:
        compile_table(ct)


if __name__ == "__main__":
    main()
