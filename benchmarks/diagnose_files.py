"""Files per second for ``rotor diagnose`` over N short simulated recordings:

- ``separate``: N separate ``rotor diagnose LOG --json`` commands (a shell loop);
- ``one_call_jobs1``: one ``rotor diagnose 'DIR/*.txt' --json --jobs 1`` (in its process);
- ``one_call_jobs2``: the same with ``--jobs 2`` (two threads of the one process);
- ``dask_2_workers``: the same with ``--scheduler`` on a local Dask cluster of two worker
  processes (one thread each), started once: its first run (the workers compile) and the
  median of the runs after it (a long-lived cluster);
- and, to choose the local pool, in Python (one process each, imports included):
  ``python_sequential``, ``python_threads2`` (a ThreadPoolExecutor of 2 around
  ``rotor.diagnose``) and ``python_processes2`` (``diagnose_many(jobs=2,
  pool="process")``: two spawned processes), each a fresh process; and ``warm_sequential``
  against ``warm_threads2``: the same 20 files again in a process that has compiled
  everything (the work alone, without imports and compiling).

    .venv/bin/python benchmarks/diagnose_files.py [--n 20] [--repeats 1]

Every command runs with a persistent compilation cache of the benchmark's own, filled by
one ``rotor diagnose`` before the timings (``first_call_cold_cache_s``): the figures are
those of a machine that has run rotor before. Wall times (the machine may be shared: the
CPU count is recorded), medians of ``--repeats``; writes
``benchmarks/results/diagnose_files.json`` with the versions.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "diagnose_files.json"
ROTOR = [sys.executable, "-m", "rotor.cli"]
OPTS = ["--engine", "tue-single", "--columns", "time,-,encoder_v", "--json", "--quiet"]

PY_SEQ = """
import sys, rotor
rotor.enable_compilation_cache()  # as the rotor command does
eng = rotor.load_engine("tue-single")
for p in sys.argv[1:]:
    rotor.diagnose(eng, p, columns="time,-,encoder_v")
"""
PY_THREADS = """
import sys, rotor
rotor.enable_compilation_cache()
from concurrent.futures import ThreadPoolExecutor
eng = rotor.load_engine("tue-single")
with ThreadPoolExecutor(2) as ex:
    list(ex.map(lambda p: rotor.diagnose(eng, p, columns="time,-,encoder_v"), sys.argv[1:]))
"""
PY_PROCESSES = """
import sys, rotor
rotor.enable_compilation_cache()
from rotor.diagnostics.bulk import diagnose_many
got = diagnose_many("tue-single", sys.argv[1:], columns="time,-,encoder_v", jobs=2, pool="process", progress=False)
assert not any(isinstance(g, Exception) for g in got), got
"""

PY_WARM = """
import sys, time, json, rotor
from concurrent.futures import ThreadPoolExecutor
rotor.enable_compilation_cache()
eng = rotor.load_engine("tue-single")
f = lambda p: rotor.diagnose(eng, p, columns="time,-,encoder_v")
f(sys.argv[1])
seq, thr = [], []
for _ in range(3):
    t = time.perf_counter(); [f(p) for p in sys.argv[1:]]; seq.append(time.perf_counter() - t)
    t = time.perf_counter()
    with ThreadPoolExecutor(2) as ex:
        list(ex.map(f, sys.argv[1:]))
    thr.append(time.perf_counter() - t)
print(json.dumps(seq)); print(json.dumps(thr))
"""


def timed(cmd, env) -> float:
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd[:6])} …: exit {r.returncode}\n{r.stderr[-2000:]}")
    return wall


def entry(walls, n):
    med = statistics.median(walls)
    return {"median_s": med, "runs_s": walls, "files": n, "files_per_s": n / med}


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=20, help="recordings (default 20)")
    ap.add_argument("--repeats", type=int, default=1, help="runs of each one-call form (default 1)")
    args = ap.parse_args(argv)

    import jax
    import numpy as np

    import rotor
    from rotor.diagnostics.synthetic import simulated_recording

    work = Path(tempfile.mkdtemp(prefix="rotor-bench-files-"))
    env = {**os.environ, "ROTOR_COMPILATION_CACHE": str(work / "jax-cache")}
    logs = work / "logs"
    logs.mkdir()
    paths = [str(simulated_recording(logs / f"rec{i:03d}.txt", cycles=3, seed=i)) for i in range(args.n)]
    pattern = str(logs / "*.txt")
    n = args.n
    res: dict = {"n_files": n, "recording": "simulated_recording(tue-single, cycles=3), 100 kHz, 3 columns"}
    res["load_average_at_start"] = os.getloadavg()  # a shared machine: other work slows every figure

    res["first_call_cold_cache_s"] = timed([*ROTOR, "diagnose", paths[0], *OPTS], env)
    print(f"first call (cold cache): {res['first_call_cold_cache_s']:.1f} s")

    walls = [timed([*ROTOR, "diagnose", p, *OPTS], env) for p in paths]
    res["separate"] = {**entry([sum(walls)], n), "per_call_s": walls, "median_per_call_s": statistics.median(walls)}
    print(f"separate: {res['separate']['files_per_s']:.3f} files/s ({sum(walls):.1f} s)")
    for jobs in (1, 2):
        w = [timed([*ROTOR, "diagnose", pattern, *OPTS, "--jobs", str(jobs)], env) for _ in range(args.repeats)]
        res[f"one_call_jobs{jobs}"] = entry(w, n)
        print(f"one call --jobs {jobs}: {res[f'one_call_jobs{jobs}']['files_per_s']:.3f} files/s ({w})")
    for name, code in (
        ("python_sequential", PY_SEQ),
        ("python_threads2", PY_THREADS),
        ("python_processes2", PY_PROCESSES),
    ):
        w = [timed([sys.executable, "-c", code, *paths], env) for _ in range(args.repeats)]
        res[name] = entry(w, n)
        print(f"{name}: {res[name]['files_per_s']:.3f} files/s ({w})")
    code = PY_WARM
    out = subprocess.run([sys.executable, "-c", code, *paths], env=env, capture_output=True, text=True, check=True)
    seq, thr = (json.loads(line) for line in out.stdout.splitlines()[-2:])
    res["warm_sequential"], res["warm_threads2"] = entry(seq, n), entry(thr, n)
    print(f"warm: sequential {statistics.median(seq):.2f} s, 2 threads {statistics.median(thr):.2f} s")
    try:
        import dask
        import distributed
        from dask.distributed import LocalCluster
    except ImportError:
        res["dask_2_workers"] = None
        print("dask_2_workers: skipped (pip install 'crank-rotor[dask]')")
    else:
        os.environ["ROTOR_COMPILATION_CACHE"] = env["ROTOR_COMPILATION_CACHE"]  # the workers' environment
        t0 = time.perf_counter()
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
            start = time.perf_counter() - t0
            cmd = [*ROTOR, "diagnose", pattern, *OPTS, "--scheduler", cluster.scheduler_address]
            first = timed(cmd, env)
            w = [timed(cmd, env) for _ in range(max(args.repeats, 1))]
        res["dask_2_workers"] = {**entry(w, n), "cluster_start_s": start, "first_run_s": first}
        res["dask_2_workers"]["first_run_files_per_s"] = n / first
        print(f"dask: first run {n / first:.3f} files/s, then {res['dask_2_workers']['files_per_s']:.3f} files/s")
        res["versions_dask"] = {"dask": dask.__version__, "distributed": distributed.__version__}
    res["load_average_at_end"] = os.getloadavg()
    res["versions"] = {
        "rotor": rotor.__version__,
        "jax": jax.__version__,
        "numpy": np.__version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    from rotor.fileio import write_text_atomic

    write_text_atomic(OUT, json.dumps(res, indent=1) + "\n")
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
