"""XLA's two CPU emitters for rotor's kernels: compile time, run time and results.

rotor chooses XLA's elemental emitters (``--xla_cpu_use_fusion_emitters=false``, see
``rotor.jaxconfig.XLA_CPU_FLAG``); this script measures that choice against XLA's default
fusion emitters. Each round runs one fresh process per choice, in turn, each with an empty
compilation cache and an empty table folder, on the same workload: the steady state of
mwm6 and 4chn15, and ``simulate`` of each with the closed, grid and angle methods (20
cycles), plus 4chn15 with the time method (2 cycles). A process reports

- the seconds XLA spent compiling (JAX's ``backend_compile_duration`` events) and the
  number of programs,
- the run time of each compiled call (median of 5 calls after the first; a compiled
  ``steady_state`` of the prepared engine: median of 200),
- the results (δ, the last ω of each run), to compare between the two choices.

    .venv/bin/python benchmarks/xla_emitters.py [--rounds 3]   # about 2 min a round

Writes benchmarks/results/xla_emitters.json: per choice the medians over the rounds, the
ratio elemental/fusion of each figure, and the largest relative difference of a result.
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
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
CHOICES = {"elemental": "--xla_cpu_use_fusion_emitters=false", "fusion": "--xla_cpu_use_fusion_emitters=true"}

CHILD = r"""
import json, time, warnings
import jax, numpy as np, rotor
warnings.simplefilter("ignore")
compile_s = [0.0, 0]
def listen(event, duration, **kw):
    if event == "/jax/core/compile/backend_compile_duration":
        compile_s[0] += duration; compile_s[1] += 1
jax.monitoring.register_event_duration_secs_listener(listen)
def median_call(fn, n):
    fn()
    ts = []
    for _ in range(n):
        t = time.perf_counter(); jax.block_until_ready(fn()); ts.append(time.perf_counter() - t)
    return float(np.median(ts))
run_s, results = {}, {}
for name in ("mwm6", "4chn15"):
    e = rotor.load_engine(name)
    ss = rotor.steady_state(e)
    results[f"{name} delta"] = float(ss.delta)
    load = rotor.ConstantLoad(float(ss.load_torque_Nm))
    methods = (("closed", 20), ("grid", 20), ("angle", 20)) + ((("time", 2),) if name == "4chn15" else ())
    for method, cycles in methods:
        call = lambda: rotor.simulate(e, rpm=1200.0, cycles=cycles, method=method, load=load, progress=False).omega
        run_s[f"{name} simulate {method}"] = median_call(call, 5)
        results[f"{name} {method} last omega"] = float(np.asarray(call())[-1])
    prepared = rotor.prepare(e)
    delta = jax.jit(lambda rpm: rotor.steady_state(prepared, rpm=rpm).delta)
    run_s[f"{name} compiled steady state"] = median_call(lambda: delta(1250.0), 200)
print(json.dumps({"compile_s": compile_s[0], "programs": compile_s[1], "run_s": run_s, "results": results}))
"""


def child(flag: str) -> dict:
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as tables:
        env = dict(os.environ, XLA_FLAGS=flag, ROTOR_COMPILATION_CACHE=cache, ROTOR_TABLE_CACHE=tables)
        out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    runs: dict[str, list[dict]] = {k: [] for k in CHOICES}
    for r in range(args.rounds):
        for choice, flag in CHOICES.items():
            runs[choice].append(child(flag))
            print(f"round {r + 1} {choice}: compile {runs[choice][-1]['compile_s']:.1f} s", flush=True)
    summary: dict = {}
    for choice, rs in runs.items():
        summary[choice] = {
            "compile_s": statistics.median(x["compile_s"] for x in rs),
            "compile_s_each": [x["compile_s"] for x in rs],
            "programs": rs[0]["programs"],
            "run_s": {k: statistics.median(x["run_s"][k] for x in rs) for k in rs[0]["run_s"]},
        }
    el, fu = summary["elemental"], summary["fusion"]
    ratios = {"compile": el["compile_s"] / fu["compile_s"]}
    ratios.update({k: el["run_s"][k] / fu["run_s"][k] for k in el["run_s"]})
    res_el, res_fu = runs["elemental"][0]["results"], runs["fusion"][0]["results"]
    rel = {k: abs(res_el[k] - res_fu[k]) / abs(res_fu[k]) for k in res_el}
    import jax
    import numpy

    doc = {
        "choices": CHOICES,
        "rounds": args.rounds,
        "summary": summary,
        "ratio_elemental_over_fusion": ratios,
        "results_relative_difference": rel,
        "results": {"elemental": res_el, "fusion": res_fu},
        "versions": {"python": platform.python_version(), "jax": jax.__version__, "numpy": numpy.__version__},
        "cpus": os.cpu_count(),
    }
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / "xla_emitters.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(doc, indent=1))
    tmp.replace(path)
    print(f"compile: elemental {el['compile_s']:.1f} s, fusion {fu['compile_s']:.1f} s, ratio {ratios['compile']:.2f}")
    for k in el["run_s"]:
        print(f"  {k}: {el['run_s'][k] * 1e3:.3f} ms vs {fu['run_s'][k] * 1e3:.3f} ms, ratio {ratios[k]:.2f}")
    print(f"largest relative difference of a result: {max(rel.values()):.2e} ({max(rel, key=rel.get)})")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
