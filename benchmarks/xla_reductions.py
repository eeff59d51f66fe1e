"""Running sums and extreme indices on a cycle's nodes, compiled by XLA for the CPU.

The steady state's program sums its time integral over the nodes and finds the index of
the speed's extremes; XLA's CPU lowering of each has a cheaper equivalent. One compiled
call per case on a cycle of 2880 float64 values (a 0.25° grid of a four-stroke cycle),
each called on its own with the result waited for, the cases taken in turn for
``--rounds`` rounds after one call that compiles (compile time kept apart):

- the running sum: ``jax.lax.associative_scan(jnp.add, x)`` against ``jnp.cumsum`` (what
  ``rotor.dynamics.equation.hermite_cumulative`` uses: the scan was tried in the steady
  state's program and not kept, its gain taken in turn small and not steady from run to
  run), and the largest difference between the two relative to the total;
- the index of the largest and of the smallest value: ``jnp.argmax`` and ``jnp.argmin``
  against ``rotor.cycles.extreme_index`` (the extreme, then the first index that holds
  it), the indices asserted equal;
- an empty call (the first value returned) for the dispatch and wait every call pays.

Medians [µs] and each case over its baseline, the median of the rounds' ratios.

    .venv/bin/python benchmarks/xla_reductions.py [--rounds 3000]   # about 10 s

Writes ``benchmarks/results/xla_reductions.json``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from simulator_speed import versions  # noqa: E402

import rotor  # noqa: E402, F401  (float64 on, XLA's emitters as rotor runs them)
from rotor.cycles import extreme_index  # noqa: E402
from rotor.fileio import write_text_atomic  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
NODES = 2880


def cases():
    """name → function of the nodes, compiled."""
    return {
        "empty call": jax.jit(lambda x: x[0]),
        "jnp.cumsum": jax.jit(jnp.cumsum),
        "associative_scan": jax.jit(lambda x: jax.lax.associative_scan(jnp.add, x)),
        "jnp.argmax and jnp.argmin": jax.jit(lambda x: (jnp.argmax(x), jnp.argmin(x))),
        "extreme_index, both": jax.jit(lambda x: (extreme_index(jnp, x, True), extreme_index(jnp, x, False))),
    }


BASELINES = {"associative_scan": "jnp.cumsum", "extreme_index, both": "jnp.argmax and jnp.argmin"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=3000)
    args = ap.parse_args()
    theta = np.linspace(0.0, 4 * np.pi, NODES, endpoint=False)
    rng = np.random.default_rng(3)
    x = jnp.asarray(130.0 + np.sin(2 * theta) + 0.3 * np.sin(5 * theta) + 1e-3 * rng.standard_normal(NODES))
    fns = cases()
    compile_s = {}
    for name, fn in fns.items():
        t0 = time.perf_counter()
        jax.block_until_ready(fn(x))
        compile_s[name] = time.perf_counter() - t0
    total = float(jnp.sum(x))
    sum_gap = float(jnp.max(jnp.abs(fns["associative_scan"](x) - fns["jnp.cumsum"](x)))) / total
    index_pairs = [tuple(int(i) for i in fns[k](x)) for k in ("jnp.argmax and jnp.argmin", "extreme_index, both")]
    assert index_pairs[0] == index_pairs[1], index_pairs
    times: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(args.rounds):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            jax.block_until_ready(fn(x))
            times[name].append(time.perf_counter() - t0)
    medians = {name: 1e6 * statistics.median(v) for name, v in times.items()}
    ratios = {
        name: float(np.median(np.asarray(times[base]) / np.asarray(times[name]))) for name, base in BASELINES.items()
    }
    out = {
        "measured": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "versions": versions(),
        "nodes": NODES,
        "rounds": args.rounds,
        "median_us": medians,
        "baseline_over_case": {name: {"baseline": BASELINES[name], "ratio": r} for name, r in ratios.items()},
        "first_call_s": compile_s,
        "running_sums_max_difference_over_total": sum_gap,
        "extreme_indices": index_pairs[0],
    }
    print(f"{NODES} float64 nodes, {args.rounds} rounds in turn, medians:")
    for name, us in medians.items():
        print(f"  {name:28s} {us:7.1f} µs")
    for name, r in ratios.items():
        print(f"  {BASELINES[name]} over {name}: {r:.2f}× (median of the rounds' ratios)")
    print(f"  the two running sums differ by {sum_gap:.1e} of the total; the indices agree {index_pairs[0]}")
    RESULTS.mkdir(parents=True, exist_ok=True)
    write_text_atomic(RESULTS / "xla_reductions.json", json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
