"""Reading simulated analog wheel signals with no options: the full matrix.

Every standard wheel (rotor.logs.identify.STANDARD_WHEELS) × sensor (variable reluctance, whose
amplitude follows the speed; Hall) × the tooth after the gap (regular, weak, early, late) × the
speed (steady with a firing ripple; an ignition cut that drops the speed 30 % in 3 revolutions;
a coast-down to a twentieth of the speed) × the signal and its negation, with white noise and
tooth-spacing errors (rotor.logs.synthetic). Each is read with ``wheel="auto"`` and no edge; a
reading is right where it names the wheel and its δ is within 1 % of the δ read with that wheel
and the documented edge given (the signal's own edge; for a Hall sensor's weak tooth, a narrow
pulse both of whose edges move, the edge rotor took). The suite runs every fifth row
(tests/logs/test_signal_reading.py).

    .venv/bin/python benchmarks/signal_matrix.py      # 432 readings, about 2 min

Writes benchmarks/results/signal_matrix.json: each row (wheel, sensor, gap tooth, speed,
inverted, wheel found, edge taken and the signal's own, δ difference, or the error) and the
counts, with the versions.
"""

from __future__ import annotations

import itertools
import json
import platform
import time
from pathlib import Path

import numpy as np

import rotor
from rotor.errors import LogError
from rotor.fileio import write_text_atomic
from rotor.logs.identify import STANDARD_WHEELS
from rotor.logs.synthetic import speed_profile, wheel_signal

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "signal_matrix.json"
PROFILES = {
    "steady": dict(rpm=2000.0, revolutions=14, ripple=0.04),
    "ignition_cut": dict(rpm=2000.0, revolutions=16, ripple=0.04),
    "coast_down": dict(rpm=1500.0, revolutions=16, ripple=0.02),
}


def main():
    rows = []
    t0 = time.perf_counter()
    for spec, sensor, gap, prof in itertools.product(
        STANDARD_WHEELS, ("vr", "hall"), (None, "weak", "early", "late"), PROFILES
    ):
        p = speed_profile(prof, **PROFILES[prof])
        for inverted in (False, True):
            s = wheel_signal(
                p, spec, sensor=sensor, gap_tooth=gap, inverted=inverted, noise_v=0.02, tooth_error_deg=0.05
            )
            log = rotor.Log.from_arrays(time=s.t_s, encoder_v=s.v)
            row = dict(wheel=spec, sensor=sensor, gap_tooth=gap, speed=prof, inverted=inverted, own_edge=s.edge)
            try:
                a = rotor.analyze_log(log, "auto", firing=0, tdc_deg=0.0)
                doc = s.edge if not (sensor == "hall" and gap == "weak") else a.reading.edge
                g = rotor.analyze_log(log, spec, edge=doc, firing=0, tdc_deg=0.0)
                d = float(abs(np.mean(a.delta) / np.mean(g.delta) - 1))
                row.update(found=a.reading.wheel.spec, edge=a.reading.edge, delta_difference=d)
                row["right"] = a.reading.wheel.spec == spec and d < 0.01
            except LogError as e:
                row.update(error=str(e), right=False)
            rows.append(row)
    right = sum(r["right"] for r in rows)
    res = {
        "readings": len(rows),
        "right": right,
        "wrong_wheel": sum(1 for r in rows if "found" in r and r["found"] != r["wheel"]),
        "refused": sum(1 for r in rows if "error" in r),
        "own_edge_taken": sum(1 for r in rows if r.get("edge") == r["own_edge"]),
        "seconds": time.perf_counter() - t0,
        "rows": rows,
        "versions": {"rotor": rotor.__version__, "numpy": np.__version__, "python": platform.python_version()},
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(OUT, json.dumps(res, indent=1) + "\n")
    print(
        f"{right} of {len(rows)} readings right ({res['wrong_wheel']} wrong wheels, {res['refused']} refused); "
        f"the signal's own edge taken in {res['own_edge_taken']}; {res['seconds']:.0f} s; wrote {OUT}"
    )


if __name__ == "__main__":
    main()
