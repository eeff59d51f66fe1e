"""What the torsional modal analysis and the Campbell sweep cost: a 100-mass chain's natural
frequencies and mode shapes, Holzer's method on the same chain, and a 1000-speed Campbell
sweep (the MWM six of the presets, and the 100-mass chain with 100 firing throws' worth of
phase sums), each with its compile time apart from its run time.

    .venv/bin/python benchmarks/torsion_modes.py [--repeats 7]

Writes ``benchmarks/results/torsion_modes.json``: for each case the first call's wall time
(compile and run), the median wall time of ``--repeats`` further calls and every run's time,
the median CPU time (``time.process_time``; on a shared machine the wall time also counts
the waits for a core) and the versions. The issue asks for "well under a second after
compile" for the 100-mass modal analysis and the 1000-speed sweep.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import scipy

import rotor
from rotor.torsion.campbell import campbell_arrays, engine_orders
from rotor.torsion.modes import natural_frequencies_of

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "torsion_modes.json"


def chain_100(seed: int = 0) -> rotor.TorsionalChain:
    """A 100-mass chain of throw-like masses (0.01…0.1 kg·m²) on crankshaft-like sections
    (1e5…1e7 N·m/rad), the throws on masses 2…97."""
    rng = np.random.default_rng(seed)
    return rotor.TorsionalChain(rng.uniform(0.01, 0.1, 100), rng.uniform(1e5, 1e7, 99), throw_masses=list(range(1, 97)))


def time_it(fn, repeats):
    """(first call [s], median wall [s], every run's wall [s], median CPU [s])."""
    t0 = time.perf_counter()
    fn()
    first = time.perf_counter() - t0
    walls, cpus = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return {
        "first_call_s": first,
        "median_s": statistics.median(walls),
        "runs_s": walls,
        "median_cpu_s": statistics.median(cpus),
    }


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    chain = chain_100()
    J, k = chain.inertias_kgm2, chain.stiffnesses_Nm_per_rad
    mwm6 = rotor.load_engine("mwm6")
    speeds = jnp.linspace(600.0, 2600.0, 1000)
    orders = jnp.asarray(engine_orders(4))
    phases = jnp.asarray(np.deg2rad(np.arange(96) * 7.5))
    cyl_mass = jnp.asarray(np.arange(1, 97), dtype=jnp.int32)

    cases = {
        "eigen_100_masses_jit": (
            "natural frequencies of the 100-mass chain, compiled (jnp.linalg.eigh)",
            lambda: natural_frequencies_of(J, k).block_until_ready(),
        ),
        "torsional_modes_100_masses": (
            "rotor.torsional_modes(chain): frequencies, shapes, participation (the whole result)",
            lambda: rotor.torsional_modes(chain),
        ),
        "holzer_100_masses": (
            "rotor.holzer_frequencies(chain): Sturm bisection, then bisection on the Holzer residual (numpy)",
            lambda: rotor.holzer_frequencies(chain),
        ),
        "campbell_arrays_100_masses_1000_speeds": (
            "the compiled Campbell sweep: 99 modes x 24 orders x 1000 speeds, 96 cylinders' phase sums",
            lambda: jax.block_until_ready(campbell_arrays(J, k, orders, speeds, phases, cyl_mass)),
        ),
        "campbell_mwm6_1000_speeds": (
            "rotor.campbell(mwm6, rpm=(600, 2600)): 1000 speeds, the result with the frequency band over θ",
            lambda: rotor.campbell(mwm6, rpm=(600.0, 2600.0)),
        ),
        "torsional_modes_mwm6": (
            "rotor.torsional_modes(mwm6): the engine's chain, damped modes and the band over 360 crank angles",
            lambda: rotor.torsional_modes(mwm6),
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
            "cpus": len(__import__("os").sched_getaffinity(0)),
        },
        "repeats": args.repeats,
    }
    for key, (what, fn) in cases.items():
        res[key] = {"what": what, **time_it(fn, args.repeats)}
        print(f"{key:42} first {res[key]['first_call_s']:8.3f} s   median {res[key]['median_s'] * 1e3:9.2f} ms")
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(res, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
