"""Long transient runs: wall time and peak memory of ``rotor.simulate`` against the cycle count.

Each size runs in a fresh Python process (so that its peak resident memory,
``resource.getrusage(RUSAGE_SELF).ru_maxrss``, is its own): the engine is loaded and a short
run of a few chunks compiles the kernels (``compile_s``, with the import apart), then the
run of N cycles is timed (``run_s``). Runs longer than ``--keep-cycles`` keep only the
last cycles' samples (``keep_cycles``) and the per-cycle figures of every cycle, so that
memory stays bounded; the load balances the mean engine torque at the start speed, as
``rotor simulate`` gives it.

    .venv/bin/python benchmarks/long_run.py                        # 1e3, 1e4, 1e5, 1e6 cycles, method grid
    .venv/bin/python benchmarks/long_run.py --sizes 1000 10000     # chosen sizes
    .venv/bin/python benchmarks/long_run.py --quick                # 100 and 1000 cycles

Writes benchmarks/results/long_run.json and benchmarks/figures/long_run.png.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
FIGURES = ROOT / "benchmarks" / "figures"

CHILD = r"""
import json, resource, sys, time, warnings
t0 = time.perf_counter()
import rotor
from rotor.dynamics.transient import chunk_cycles
imported = time.perf_counter() - t0
engine_name, method, cycles, keep = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
engine = rotor.load_engine(engine_name)
load = rotor.ConstantLoad(float(rotor.steady_state(engine).load_torque_Nm))
warnings.simplefilter("ignore")
size = chunk_cycles(method, 10**9, 1440, 2880)
t1 = time.perf_counter()
rotor.simulate(engine, cycles=2 * size + 1, load=load, method=method, keep_cycles=2)  # compiles the chunk kernels
compile_s = time.perf_counter() - t1
t2 = time.perf_counter()
res = rotor.simulate(engine, cycles=cycles, load=load, method=method, keep_cycles=keep if keep < cycles else None)
run_s = time.perf_counter() - t2
d = res.to_json_dict()
print(json.dumps({
    "cycles": cycles, "method": method, "keep_cycles": keep if keep < cycles else None, "chunk_cycles": size,
    "import_s": imported, "compile_s": compile_s, "run_s": run_s, "run_per_cycle_ms": 1e3 * run_s / cycles,
    "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    "samples_held": int(res.omega.shape[0]), "delta": d["delta"], "delta_max": d["delta_max"],
    "mean_rpm": d["mean_rpm"],
}))
"""


def _versions() -> dict:
    import jax
    import numpy

    import rotor

    return {
        "python": platform.python_version(),
        "jax": jax.__version__,
        "numpy": numpy.__version__,
        "rotor": getattr(rotor, "__version__", "?"),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
    }


def _plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = [r["cycles"] for r in rows]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    a1.loglog(n, [r["run_s"] for r in rows], "o-", label="run")
    a1.loglog(n, [r["compile_s"] for r in rows], "s--", label="compile (a short run)")
    a1.set_xlabel("cycles")
    a1.set_ylabel("wall time [s]")
    a1.legend()
    a1.grid(True, which="both", alpha=0.3)
    a2.semilogx(n, [r["peak_rss_mb"] for r in rows], "o-")
    a2.set_xlabel("cycles")
    a2.set_ylabel("peak resident memory [MB]")
    a2.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"rotor.simulate, {rows[0]['method']}, samples of the last cycles kept")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engine", default="4chn15")
    ap.add_argument("--method", default="grid", choices=("grid", "closed", "angle"))
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 10_000, 100_000, 1_000_000])
    ap.add_argument("--keep-cycles", type=int, default=100, help="samples kept of runs longer than this")
    ap.add_argument("--quick", action="store_true", help="100 and 1000 cycles only")
    ap.add_argument("--out", default=str(RESULTS / "long_run.json"))
    args = ap.parse_args()
    sizes = [100, 1000] if args.quick else args.sizes
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    rows = []
    for n in sizes:
        start = time.perf_counter()
        out = subprocess.run(
            [sys.executable, "-c", CHILD, args.engine, args.method, str(n), str(args.keep_cycles)],
            env=env,
            check=True,
            capture_output=True,
            text=True,
        )
        row = json.loads(out.stdout.strip().splitlines()[-1])
        row["process_s"] = time.perf_counter() - start
        rows.append(row)
        print(
            f"{n:>9} cycles: run {row['run_s']:8.2f} s ({row['run_per_cycle_ms']:.3f} ms/cycle), "
            f"compile {row['compile_s']:.2f} s, peak {row['peak_rss_mb']:.0f} MB, {row['samples_held']} samples held",
            flush=True,
        )
        result = {"engine": args.engine, "method": args.method, "versions": _versions(), "runs": rows}
        path = Path(args.out)  # after every size: a long last size leaves the others written
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result, indent=2) + "\n")
    _plot(rows, FIGURES / "long_run.png")
    print(f"wrote {path} and {FIGURES / 'long_run.png'}")


if __name__ == "__main__":
    main()
