"""How much δ and the first engine orders of the steady state change between model choices.

For each preset at its ``[operating] rpm`` (balanced constant load, no friction), the
steady state at the ``"variable"`` (exact I(θ)), ``"series"`` (λ-series kinematics in I(θ)
and the gas torque), ``"coefficients"`` (the A·cos²θ + B·cosθ + C form of Anisimov, Yelenich & Melnyk) and ``"constant"`` (mean
inertia + textbook inertia torque) fidelity levels, and the textbook
δ = L_excess/(J·ω²) of Shishkov, "Dinamika dvigatelei" (SUSU 2014), §3.2.12. Then, at the variable level:

- ``friction``: FMEP = 0.5 bar + 0.06 bar per m/s of mean piston speed, on;
- ``table_pchip_5deg``: the preset's pressure sampled every 5° and read back by rotor's
  periodic PCHIP (what a coarse measured table gives);
- ``table_linear_5deg``: the same 5° samples interpolated linearly (re-tabulated every
  0.25° by ``np.interp``), as a user's own table lookup would.

Differences are relative to ``"variable"`` with the preset's own pressure: δ and the speed
amplitude of the five lowest engine orders present (orders of an even-firing engine that
cancel, below 1e-3 of the largest, are skipped).

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

ORDERS = tuple(0.5 * k for k in range(1, 25))  # 0.5 … 12
OUT = Path(__file__).parent / "results"
MODELS = ("variable", "series", "coefficients", "constant")
CHOICES = {
    "series": "λ-series kinematics",
    "coefficients": "A·cos²θ+B·cosθ+C inertia",
    "constant": "constant inertia + inertia torque",
    "friction": "friction on (FMEP 0.5 bar + 0.06 bar/(m/s))",
    "table_pchip_5deg": "pressure as a 5° table, PCHIP",
    "table_linear_5deg": "pressure as a 5° table, linear",
}


def _row(r):
    o = r.orders(max_order=max(ORDERS))
    amp = dict(zip(np.round(o.order, 3), np.asarray(o.speed_amplitude_rad_s)))
    return {
        "delta": float(r.delta),
        "textbook_delta": float(r.textbook_delta),
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
    rows = {fid: _row(rotor.steady_state(engine, fidelity=fid)) for fid in MODELS}
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
    for name, rows in results.items():
        v = rows["variable"]
        amps = v["speed_amplitude_rad_s"]
        top = max(amps.values())
        orders = [k for k, a in amps.items() if a > 1e-3 * top][:5]
        print(f"\n{name}: δ = {v['delta']:.5g} (variable inertia, exact kinematics); change against it")
        print("| model choice | δ | " + " | ".join(f"order {float(k):g}" for k in orders) + " |")
        print("|---" * (2 + len(orders)) + "|")
        print("| variable (reference), amplitude [rad/s] | — | " + " | ".join(f"{amps[k]:.4g}" for k in orders) + " |")
        for key, label in CHOICES.items():
            r = rows[key]
            cells = [f"{100 * (r['speed_amplitude_rad_s'][k] / amps[k] - 1):+.3g} %" for k in orders]
            print(f"| {label} | {100 * (r['delta'] / v['delta'] - 1):+.3g} % | " + " | ".join(cells) + " |")
        print(
            f"| textbook δ = L_excess/(J·ω²) | {100 * (v['textbook_delta'] / v['delta'] - 1):+.3g} % |"
            + " |" * len(orders)
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
