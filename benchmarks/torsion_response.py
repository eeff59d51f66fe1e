"""What the torsional forced response costs: one periodic steady state of the MWM six's
nine-mass chain (harmonic balance, :func:`rotor.torsional_response`) on the default 0.25°
grid and on the 1° grid, a 50-speed :func:`rotor.torsional_sweep` on its default 1° grid,
and the gradient of the flywheel's speed irregularity with respect to the six cylinders'
``imep_scale`` (``jax.grad`` through the response), each with its compile time apart from
its run time.

    .venv/bin/python benchmarks/torsion_response.py [--repeats 5] [--sweep-repeats 3]

Writes ``benchmarks/results/torsion_response.json``: for each case the first call's wall
time (compile and run), the median wall time of the further calls and every run's time, the
median CPU time (``time.process_time``; on a shared machine the wall time also counts the
waits for a core), the Newton steps where there are any, and the versions.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import scipy

import rotor

sys.path.insert(0, str(Path(__file__).resolve().parent))
from torsion_modes import time_it  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "torsion_response.json"
RPM = 1500.0
SWEEP = np.linspace(900.0, 2500.0, 50)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--sweep-repeats", type=int, default=3)
    args = ap.parse_args(argv)
    mwm6 = rotor.load_engine("mwm6")
    spread = jnp.asarray([1.00, 1.08, 0.92, 1.04, 0.96, 1.00])

    def flywheel_ms(scale):
        r = rotor.torsional_response(mwm6, RPM, imep_scale=scale, grid_deg=1.0)
        w = jnp.asarray(r.omega)[r.reference_mass]
        return jnp.mean((w - jnp.mean(w)) ** 2)

    grad = jax.grad(flywheel_ms)
    cases = {
        "response_mwm6_0.25deg": (
            f"rotor.torsional_response(mwm6, {RPM:g}) on the 0.25° grid (2880 nodes x 9 masses)",
            lambda: rotor.torsional_response(mwm6, RPM),
            args.repeats,
        ),
        "response_mwm6_1deg": (
            f"rotor.torsional_response(mwm6, {RPM:g}, grid_deg=1.0) (720 nodes x 9 masses)",
            lambda: rotor.torsional_response(mwm6, RPM, grid_deg=1.0),
            args.repeats,
        ),
        "sweep_mwm6_50_speeds_1deg": (
            f"rotor.torsional_sweep(mwm6, {SWEEP.size} speeds {SWEEP[0]:g}..{SWEEP[-1]:g} rpm), 1° grid, batch 1 on CPU",
            lambda: rotor.torsional_sweep(mwm6, SWEEP),
            args.sweep_repeats,
        ),
        "grad_flywheel_ms_imep_scale_1deg": (
            "jax.grad of the flywheel's mean-square speed fluctuation w.r.t. the 6 imep_scale (1° grid, reverse mode)",
            lambda: grad(spread).block_until_ready(),
            args.repeats,
        ),
    }
    res: dict = {
        "versions": {
            "jax": jax.__version__,
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "python": platform.python_version(),
            "rotor": rotor.__version__,
            "machine": platform.machine(),
            "device": str(jax.devices()[0]),
            "cpus": len(os.sched_getaffinity(0)),
        },
        "repeats": args.repeats,
        "sweep_repeats": args.sweep_repeats,
    }
    for key, (what, fn, repeats) in cases.items():
        res[key] = {"what": what, **time_it(fn, repeats)}
        print(f"{key:34} first {res[key]['first_call_s']:8.3f} s   median {res[key]['median_s']:8.3f} s")
    r = rotor.torsional_response(mwm6, RPM)
    res["response_mwm6_0.25deg"]["newton_steps"] = int(r.newton_steps)
    sw = rotor.torsional_sweep(mwm6, SWEEP)
    res["sweep_mwm6_50_speeds_1deg"]["converged"] = int(np.sum(sw.converged))
    res["sweep_mwm6_50_speeds_1deg"]["per_speed_s"] = res["sweep_mwm6_50_speeds_1deg"]["median_s"] / SWEEP.size
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(res, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
