"""Where the time of a repeated default ``rotor.steady_state(engine, rpm=…)`` goes.

One process, 4chn15 at 1250 rpm, the engine object's tables found (warm-up calls first),
then ``--repeats`` calls: the median of the whole call and of its parts, each timed by
wrapping the function that does it: the compiled program's dispatch (the kept program's
call, which returns before the program has run), the copy of its packed result (which
waits for it), ``_finish`` (building the result) and how many calls ran the host's
invariant checks (``check_speed_result``: none where the program's flag says they hold);
in a second round, the whole call with the program's flag ignored, so that the host checks
the arrays as well (what the flag saves, measured rather than added up); δ read off a
finished result (``float(result.delta)``, which ``steady_limit.py``'s default call
includes); the whole call with the compilation cache on (in a new folder), as the
``rotor`` command runs it: the kernel's program kept and called through
:mod:`rotor.programs` instead of ``jax.jit``'s dispatch; and last the closed form's
compiled program alone, with the tables as arguments (as the default passes them) and
with all but the speed closed over, in turn (the same numbers to 1e-12, asserted).
``benchmarks/steady_limit.py`` compares the call with the compiled one and with scipy.

    .venv/bin/python benchmarks/steady_call_profile.py [--repeats 400]   # about 5 s

Writes ``benchmarks/results/steady_call_profile.json``.
"""

from __future__ import annotations

import argparse
import collections
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import equinox as eqx  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from simulator_speed import versions  # noqa: E402

import rotor  # noqa: E402
from rotor.dynamics import steady  # noqa: E402
from rotor.fileio import write_text_atomic  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
KERNEL = "_closed_steady"  # the closed form's compiled program, wrapped by name as the parts below
UNPACK = "_unpack"  # its packed vector read back (waits for the program)


def program_alone(engine, repeats: int) -> dict[str, float]:
    """The closed form's compiled program alone, called and its packed result copied to
    NumPy: with the arguments the default call passes it (the tables among them), and with
    everything but the speed closed over (the tables, fuelling and losses constants of the
    program, which XLA folds); the two in turn, medians [µs]."""
    seen = []
    program = getattr(steady, KERNEL)

    def record(*a, **k):
        seen.append((a, k))
        return program(*a, **k)

    setattr(steady, KERNEL, record)
    try:
        rotor.steady_state(engine, rpm=1250.0)
    finally:
        setattr(steady, KERNEL, program)
    (args, _), fn = seen[0], program.fn  # fn: the kernel's Python, before jax.jit
    train, numbers, load, balance, flat, passes = args  # numbers: ..., the mean speed last
    static = {"balance": balance, "flat": flat, "passes": passes}
    constants = jax.tree_util.tree_map(lambda v: jnp.asarray(v) if eqx.is_array(v) else v, (train, numbers, load))
    as_arguments = jax.jit(lambda *d: fn(*d, **static))
    closed = jax.jit(lambda omega: fn(constants[0], constants[1].at[-1].set(omega), constants[2], **static))
    omega = jnp.asarray(numbers[-1])
    calls = {
        "the tables as arguments": lambda: np.asarray(as_arguments(train, numbers, load)),
        "all but the speed closed over": lambda: np.asarray(closed(omega)),
    }
    a, b = calls["the tables as arguments"](), calls["all but the speed closed over"]()
    assert np.allclose(a, b, rtol=1e-12, atol=0.0), "the two programs disagree"  # XLA's folding rounds apart
    times: dict[str, list[float]] = {name: [] for name in calls}
    for _ in range(repeats):
        for name, call in calls.items():
            t = time.perf_counter()
            call()
            times[name].append(time.perf_counter() - t)
    return {name: 1e6 * statistics.median(v) for name, v in times.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=400)
    args = ap.parse_args()
    engine = rotor.load_engine("4chn15")
    parts: dict[str, list[float]] = collections.defaultdict(list)
    originals = {}

    def timed(name: str, label: str) -> None:
        f = originals[name] = getattr(steady, name)

        def wrapper(*a, **k):
            t = time.perf_counter()
            out = f(*a, **k)
            parts[label].append(time.perf_counter() - t)
            return out

        setattr(steady, name, wrapper)

    def whole() -> float:
        for _ in range(50):
            rotor.steady_state(engine, rpm=1250.0)
        parts.clear()
        runs = []
        for _ in range(args.repeats):
            t = time.perf_counter()
            rotor.steady_state(engine, rpm=1250.0)
            runs.append(time.perf_counter() - t)
        return 1e6 * statistics.median(runs)

    total = whole()
    timed(KERNEL, "compiled program's dispatch")
    timed(UNPACK, "the packed result's copy (waits for the program)")
    timed("_finish", "_finish (the result built)")
    timed("check_speed_result", "the host's invariant checks")
    with_parts = whole()
    medians = {k: 1e6 * statistics.median(v) for k, v in parts.items()}
    host_checks = len(parts.get("the host's invariant checks", []))
    for name, f in originals.items():  # the rounds below without the timing wrappers
        setattr(steady, name, f)
    unpack = getattr(steady, UNPACK)

    def flag_ignored(*a, **k):  # the program's invariant flag cleared: the host checks every call
        t, x, ok, arrays = unpack(*a, **k)
        return t, x, ok, {**arrays, "invariants_hold": False}

    setattr(steady, UNPACK, flag_ignored)
    host_checked = whole()
    setattr(steady, UNPACK, unpack)
    finished = rotor.steady_state(engine, rpm=1250.0)
    delta_runs = []
    for _ in range(args.repeats):
        t = time.perf_counter()
        float(finished.delta)
        delta_runs.append(time.perf_counter() - t)
    delta_us = 1e6 * statistics.median(delta_runs)
    program = program_alone(engine, args.repeats)
    with tempfile.TemporaryDirectory() as folder:
        rotor.enable_compilation_cache(folder)
        kept = whole()
    out = {
        "measured": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "versions": versions(),
        "case": "4chn15, rpm=1250.0, the same engine object every call",
        "repeats": args.repeats,
        "call_us": total,
        "call_with_parts_timed_us": with_parts,
        "parts_us": medians,
        "calls_that_ran_the_host_checks": host_checks,
        "call_with_the_host_checking_the_arrays_us": host_checked,
        "delta_of_a_finished_result_us": delta_us,
        "call_with_kept_programs_us": kept,
        "program_alone_us": program,
    }
    print(f"steady_state(engine, rpm=1250.0): {total:.0f} µs a call (median of {args.repeats})")
    for k, v in medians.items():
        print(f"  {k:45s} {v:7.0f} µs")
    print(f"  calls that ran the host's invariant checks: {host_checks} of {args.repeats}")
    print(
        f"  the whole call with the program's invariant flag ignored (the host checks the arrays): {host_checked:.0f} µs"
    )
    print(f"float(result.delta) of a finished result: {delta_us:.1f} µs")
    print(f"the whole call with the compilation cache on (programs kept): {kept:.0f} µs")
    for k, v in program.items():
        print(f"the closed form's program alone, {k}: {v:.0f} µs")
    RESULTS.mkdir(parents=True, exist_ok=True)
    write_text_atomic(RESULTS / "steady_call_profile.json", json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
