"""How closely `rotor table 4chn15` reproduces the appendix-5 tables of Shishkov,
"Dinamika dvigatelei" (Engine dynamics: guide to the course project, SUSU 2014) for its
4ChN15/20.5 example.

Prints a markdown table of the worst error of every column, as a percentage of the
column's largest magnitude, for the lambda-series kinematics (the table's default, the
book's own method) and for the exact kinematics, and writes the figures as JSON.

    .venv/bin/python benchmarks/textbook_tables.py [--out benchmarks/results/textbook_tables.json]
"""

from __future__ import annotations

import argparse
import csv
import json
import platform
from pathlib import Path

import numpy as np

import rotor

HERE = Path(__file__).resolve().parent
DATA = HERE.parent / "tests" / "data"
COLUMNS = [
    ("s_m", "s_m", 1),
    ("v_m_s", "v_m_s", 1),
    ("j_m_s2", "j_m_s2", 1),
    ("pg_N", "pg_kN", 1e3),
    ("pj_N", "pj_kN", 1e3),
    ("psum_N", "psum_kN", 1e3),
    ("n_N", "n_kN", 1e3),
    ("k_N", "k_kN", 1e3),
    ("z_N", "z_kN", 1e3),
    ("t_N", "t_kN", 1e3),
]


def _read(name):
    lines = [l for l in (DATA / name).read_text().splitlines() if not l.startswith("#")]
    rows = list(csv.DictReader(lines))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def errors(kinematics):
    table = rotor.crank_table(rotor.load_engine("4chn15"), step_deg=10, kinematics=kinematics)
    kin, dyn = _read("shishkov_kinematics.csv"), _read("shishkov_dynamics.csv")
    out = {}
    for ours, theirs, scale in COLUMNS:
        seed = kin if theirs in kin else dyn
        idx = np.searchsorted(table["angle_deg"], seed["angle_deg"])
        ref = seed[theirs] * scale
        err = np.abs(table[ours][idx] - ref) / np.max(np.abs(ref))
        out[ours] = {"max_error_pct": 100 * float(err.max()), "at_deg": float(seed["angle_deg"][err.argmax()])}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE / "results" / "textbook_tables.json"))
    args = ap.parse_args()
    res = {"series": errors("series"), "exact": errors("exact")}
    print("| column | series: worst error | at | exact: worst error | at |")
    print("|---|---|---|---|---|")
    for col in res["series"]:
        s, e = res["series"][col], res["exact"][col]
        print(
            f"| {col} | {s['max_error_pct']:.3f} % | {s['at_deg']:g}° | {e['max_error_pct']:.3f} % | {e['at_deg']:g}° |"
        )
    import jax

    res["versions"] = {"rotor": rotor.__version__, "jax": jax.__version__, "python": platform.python_version()}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    from rotor.fileio import write_text_atomic

    write_text_atomic(out, json.dumps(res, indent=2))
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
