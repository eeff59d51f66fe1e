"""How much δ and the first engine orders of the steady state change between model choices.

For each preset at its ``[operating] rpm`` (balanced constant load, no friction), the
steady state at the ``"variable"`` (exact I(θ)), ``"coefficients"`` (seed 003 A/B/C form)
and ``"constant"`` (mean inertia + textbook inertia torque) fidelity levels, and the
seed 004 textbook δ = L_excess/(J·ω²). Then, at the variable level:

- ``friction``: FMEP = 0.5 bar + 0.06 bar per m/s of mean piston speed, on;
- ``table_pchip_5deg``: the preset's pressure sampled every 5° and read back by rotor's
  periodic PCHIP (what a coarse measured table gives);
- ``table_linear_5deg``: the same 5° samples interpolated linearly (re-tabulated every
  0.25° by ``np.interp``), as a user's own table lookup would.

Differences are relative to ``"variable"`` with the preset's own pressure.

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


def _row(r):
    o = r.orders(max_order=max(ORDERS))
    amp = dict(zip(np.round(o.order, 3), np.asarray(o.speed_amplitude_rad_s)))
    return {
        "delta": float(r.delta),
        "textbook_delta": float(r.info["textbook_delta"]),
        "speed_amplitude_rad_s": {str(k): float(amp[k]) for k in ORDERS},
    }


def _retabulated(engine, step_deg, linear):
    cycle = 180.0 * engine.strokes
    coarse = np.arange(0.0, cycle, step_deg)
    p = np.asarray(engine.pressure(np.deg2rad(coarse), engine.geometry, engine.strokes))
    if linear:
        fine = np.arange(0.0, cycle, 0.25)
        coarse, p = fine, np.interp(fine, coarse, p, period=cycle)
    return engine.replace(pressure=rotor.PressureTable(coarse, p, engine.pressure.crankcase_pa))


def measure(name: str) -> dict:
    engine = rotor.load_engine(name)
    rows = {fid: _row(rotor.steady_state(engine, fidelity=fid)) for fid in ("variable", "coefficients", "constant")}
    friction = rotor.Friction(fmep_pa=0.5e5, fmep_per_speed_pa_s_per_m=0.06e5)
    rows["friction"] = _row(rotor.steady_state(engine, friction=friction))
    rows["table_pchip_5deg"] = _row(rotor.steady_state(_retabulated(engine, 5.0, linear=False)))
    rows["table_linear_5deg"] = _row(rotor.steady_state(_retabulated(engine, 5.0, linear=True)))
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
    print()
    print("| preset | friction on | 5° table, PCHIP | 5° table, linear | largest order change, linear table |")
    print("|---|---|---|---|---|")
    for name, rows in results.items():
        v = rows["variable"]["delta"]
        rel = {k: 100 * (rows[k]["delta"] / v - 1) for k in ("friction", "table_pchip_5deg", "table_linear_5deg")}
        amps = rows["variable"]["speed_amplitude_rad_s"]
        top = max(amps.values())
        worst = max(((k, rows["table_linear_5deg"]["speed_amplitude_rad_s"][k] / a - 1) for k, a in amps.items()
                     if a > 1e-3 * top), key=lambda x: abs(x[1]))
        print(f"| {name} | {rel['friction']:+.2f} % | {rel['table_pchip_5deg']:+.3f} % | "
              f"{rel['table_linear_5deg']:+.3f} % | {float(worst[0]):g}: {100 * worst[1]:+.2f} % |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
