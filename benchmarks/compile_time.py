"""Compile time of each method and `import rotor`, cold and with the compilation cache.

For each preset and each entry point (``steady_state``; ``simulate`` with ``closed``,
``grid``, ``angle``, ``time``; 100 cycles under the work-precision scene's propeller load)
a fresh Python process makes the first call and then 3 more: compile time = first call −
median of the others. "Cold" runs with an empty compilation cache (what a user's very
first run costs); "warm" runs in a second fresh process that finds the first one's cache
(every later run: what is left is tracing the Python code). One process per entry point,
so each pays for its own tables. `import rotor` is timed as a whole process
(``python -c 'import rotor'``) minus an empty one (``python -c pass``).

    .venv/bin/python benchmarks/compile_time.py           # four presets, about 4 min
    .venv/bin/python benchmarks/compile_time.py --quick   # 4chn15 only

Writes benchmarks/results/compile_time.json and compile_time.png.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
ENTRIES = ("steady", "closed", "grid", "angle", "time")
TARGET_S = 2.0

CHILD = r"""
import json, statistics, sys, time
t0 = time.perf_counter()
import jax, rotor
t_import = time.perf_counter() - t0
name, entry = sys.argv[1], sys.argv[2]
e = rotor.load_engine(name)
rpm = float(e.operating.rpm)
load = rotor.PropellerLoad(float(rotor.mean_gas_torque(e)), rpm)
def call():
    if entry == "steady":
        r = rotor.steady_state(e, rpm)
    else:
        r = rotor.simulate(e, rpm=0.95 * rpm, cycles=100, load=load, method=entry)
    jax.block_until_ready((r.omega, r.t))
    return r
times = []
for _ in range(4):
    s = time.perf_counter(); r = call(); times.append(time.perf_counter() - s)
run = statistics.median(times[1:])
print(json.dumps({"import_s": t_import, "first_call_s": times[0], "run_s": run, "compile_s": times[0] - run,
                  "method": r.method}))
"""


def child(name, entry, cache_dir):
    env = dict(os.environ, ROTOR_COMPILATION_CACHE=cache_dir)
    out = subprocess.run([sys.executable, "-c", CHILD, name, entry], env=env, capture_output=True, text=True)
    if out.returncode:
        raise RuntimeError(f"{name} {entry}: {out.stderr.strip().splitlines()[-1]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def import_time(repeats=5):
    def wall(code):
        s = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True, env=dict(os.environ, ROTOR_COMPILATION_CACHE="off"))
        return time.perf_counter() - s

    empty = statistics.median(wall("pass") for _ in range(repeats))
    whole = [wall("import rotor") for _ in range(repeats)]
    return {
        "median_s": statistics.median(whole) - empty,
        "process_s": whole,
        "empty_process_s": empty,
        "repeats": repeats,
    }


def versions():
    import platform

    import diffrax
    import equinox
    import jax
    import jaxlib

    return {m.__name__: m.__version__ for m in (jax, jaxlib, diffrax, equinox)} | {
        "python": platform.python_version(),
        "cpu_count": os.cpu_count(),
    }


def plot(out, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from rotor.fileio import atomic_path

    presets = list(out["presets"])
    fig, axes = plt.subplots(1, len(presets), figsize=(3.2 * len(presets), 3.6), sharey=True, squeeze=False)
    x = np.arange(len(ENTRIES))
    for ax, name in zip(axes[0], presets):
        p = out["presets"][name]
        for i, kind in enumerate(("cold", "warm")):
            ax.bar(x + (i - 0.5) * 0.38, [p[e][kind]["compile_s"] for e in ENTRIES], 0.38, label=kind)
        ax.axhline(TARGET_S, color="grey", ls="--", lw=0.8)
        ax.set_xticks(x, ENTRIES, rotation=30)
        ax.set_title(name)
    axes[0][0].set_ylabel("first call − later call [s]")
    axes[0][0].legend()
    fig.suptitle(f"compile time per entry point; import rotor {out['import_rotor']['median_s']:.2f} s")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="4chn15 only")
    args = ap.parse_args()
    presets = ["4chn15"] if args.quick else ["tue-single", "4chn15", "mwm6", "v8"]
    out = {"versions": versions(), "target_s": TARGET_S, "import_rotor": import_time(), "presets": {}}
    print(f"import rotor: {out['import_rotor']['median_s']:.2f} s")
    print(f"{'preset':11s} {'entry':7s} {'cold':>7s} {'warm':>7s} {'run':>8s}")
    for name in presets:
        p = out["presets"][name] = {}
        for entry in ENTRIES:
            with tempfile.TemporaryDirectory() as cache:
                cold = child(name, entry, cache)
                warm = child(name, entry, cache)
            p[entry] = {"cold": cold, "warm": warm}
            print(
                f"{name:11s} {entry:7s} {cold['compile_s']:6.2f}s {warm['compile_s']:6.2f}s "
                f"{cold['run_s'] * 1e3:6.1f}ms",
                flush=True,
            )
    RESULTS.mkdir(parents=True, exist_ok=True)
    stem = "compile_time_quick" if args.quick else "compile_time"
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from rotor.fileio import write_text_atomic

    write_text_atomic(RESULTS / f"{stem}.json", json.dumps(out, indent=1))
    plot(out, RESULTS / f"{stem}.png")
    print(f"wrote {RESULTS / (stem + '.json')} and {stem}.png")


if __name__ == "__main__":
    main()
