"""How much δ and the first engine orders of the steady state change between fidelity levels.

For each preset at its ``[operating] rpm`` (balanced constant load, no friction), the
steady state at the ``"variable"`` (exact I(θ)), ``"coefficients"`` (seed 003 A/B/C form)
and ``"constant"`` (mean inertia + textbook inertia torque) fidelity levels, and the
seed 004 textbook δ = L_excess/(J·ω²). Differences are relative to ``"variable"``.

    .venv/bin/python benchmarks/fidelity_differences.py

Writes ``benchmarks/results/fidelity_differences.json`` and prints a Markdown table.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

import rotor

ORDERS = (0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0)
OUT = Path(__file__).parent / "results"


def measure(name: str) -> dict:
    engine = rotor.load_engine(name)
    rows = {}
    for fid in ("variable", "coefficients", "constant"):
        r = rotor.steady_state(engine, fidelity=fid)
        o = r.orders(max_order=max(ORDERS))
        amp = dict(zip(np.round(o.order, 3), np.asarray(o.speed_amplitude_rad_s)))
        rows[fid] = {
            "delta": float(r.delta),
            "textbook_delta": float(r.info["textbook_delta"]),
            "speed_amplitude_rad_s": {str(k): float(amp[k]) for k in ORDERS},
        }
    return rows


def main() -> int:
    presets = sys.argv[1:] or rotor.preset_names()
    results = {name: measure(name) for name in presets}
    OUT.mkdir(exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=OUT, suffix=".json")
    with os.fdopen(fd, "w") as f:
        json.dump(results, f, indent=2)
    os.replace(tmp, OUT / "fidelity_differences.json")
    print("| preset | δ variable | coefficients vs variable | constant vs variable | textbook vs variable | "
          "largest order change, coefficients | largest order change, constant |")
    print("|---|---|---|---|---|---|---|")
    for name, rows in results.items():
        v = rows["variable"]
        rel = lambda fid: rows[fid]["delta"] / v["delta"] - 1  # noqa: E731

        def order_change(fid):
            best = (0.0, None)
            for k, a in v["speed_amplitude_rad_s"].items():
                if a < 1e-3 * max(v["speed_amplitude_rad_s"].values()):
                    continue  # an order that cancels (balanced engine): no relative change
                d = rows[fid]["speed_amplitude_rad_s"][k] / a - 1
                best = max(best, (abs(d), f"{float(k):g}: {100 * d:+.2f} %"), key=lambda x: x[0])
            return best[1]

        print(f"| {name} | {v['delta']:.5f} | {100 * rel('coefficients'):+.3f} % | {100 * rel('constant'):+.3f} % | "
              f"{100 * (v['textbook_delta'] / v['delta'] - 1):+.2f} % | {order_change('coefficients')} | "
              f"{order_change('constant')} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
