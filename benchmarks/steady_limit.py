"""The steady state at its limit: prepared tables, one compiled call, and batches.

Measured in one run, on one engine (4chn15 at 1250 rpm unless ``--engine``):

1. The baseline: ONE cycle of scipy ``solve_ivp(method="RK45", rtol=1e-8)`` with a plain
   numpy right-hand side (``simulator_speed.NumpyEngine``), as a user would write it.
2. rotor's steady state (the whole periodic solution, not one cycle of an ODE):
   - ``steady_state(engine)`` with its tables built at every call (the cache cleared
     first: what every call cost before tables were kept);
   - ``steady_state(engine)`` with the tables kept from the call before (the default);
   - ``steady_state(rotor.prepare(engine))``;
   - one compiled call with the prepared engine as an argument (``eqx.filter_jit``
     around ``steady_state(prepared, rpm).omega``), the whole ω(θ) on 2880 nodes;
   - one compiled call with the prepared engine closed over (``jax.jit(lambda rpm:
     steady_state(prepared, rpm).omega)``, compiled ahead of time: the tables are
     constants of the call and only the speed crosses into it), the whole ω(θ);
   - the same for δ alone;
   and δ of each (or ω, for the rows that return it) against the default
   ``steady_state(engine)``; then the default, the two whole-ω(θ) compiled calls and the
   δ-only one taken in turn, a thousand rounds: each one's median and the default's time
   over each other's, the median of the rounds' ratios (the machine's load cancels).
3. The plain route: ``jax.jit(jax.vmap(lambda J: steady_state(eqx.tree_at(…, engine, J),
   rpm).delta))`` over 10⁴ crankshaft inertias at once, per item.
4. Throughput: ``rotor.steady_sweep`` over speed × flywheel inertia for 1 … 10⁵ items
   (10⁶ with ``--full``) on every core, and 10⁵ on one thread: steady states per second
   after compiling, the chunk size and the process's peak resident memory after each
   size.
5. Speed-dependent friction (the docs' ``[friction]`` table with its speed-linear term b)
   against the same friction without b, taken in turn: the default steady state, the
   compiled call, ``steady_sweep`` of 10⁴ items and ``rotor flywheel`` (an engine file
   with the table, fresh processes, the compilation cache warm); ``--only-friction`` runs
   this part alone.

Compile time is kept apart (the first call); every time is the median of repeats after it,
at least as many as fill half a second for each call timed alone.
``--sync-dispatch`` runs it with JAX's asynchronous CPU dispatch off (each compiled program
runs in the thread that calls it instead of a worker thread the caller waits for).
Writes ``results/steady_limit.json`` and ``results/steady_limit.png``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import sys
import time
from pathlib import Path

import equinox as eqx
import jax
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from simulator_speed import NumpyEngine, versions  # noqa: E402
from torsion_modes import time_it  # noqa: E402

import rotor  # noqa: E402
from rotor.dynamics import crank_train  # noqa: E402
from rotor.fileio import write_text_atomic  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"


def peak_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def bench_single(engine, repeats):
    rpm = float(engine.operating.rpm)
    default = rotor.steady_state(engine)
    delta0 = float(default.delta)
    ne = NumpyEngine(engine)
    omega0, m_load = float(default.omega[0]), float(default.load_torque_Nm)
    rk45 = time_it(lambda: ne.run(omega0, lambda w: m_load, 1, "RK45", 1e-8), max(3, repeats // 10))
    out = {"rpm": rpm, "delta_default": delta0, "scipy_rk45_one_cycle": rk45}

    def cold():
        crank_train.clear_table_cache()
        return float(rotor.steady_state(engine).delta)

    def warm():
        return float(rotor.steady_state(engine).delta)

    prepared = rotor.prepare(engine)

    def python_prepared():
        return float(rotor.steady_state(prepared).delta)

    rpm_a = jax.numpy.asarray(rpm)
    as_argument = eqx.filter_jit(lambda p, r: rotor.steady_state(p, r).omega)

    def compiled_argument():
        return as_argument(prepared, rpm_a).block_until_ready()

    # the prepared engine closed over: its tables are constants of the compiled call, and
    # only the speed crosses into it (compiled ahead of time: no tracing cache to look up)
    t0 = time.perf_counter()
    omega_closed = jax.jit(lambda r: rotor.steady_state(prepared, r).omega).lower(rpm_a).compile()
    t1 = time.perf_counter()
    delta_closed = jax.jit(lambda r: rotor.steady_state(prepared, r).delta).lower(rpm_a).compile()
    out["compile_s"] = {"closed over, whole omega(theta)": t1 - t0, "closed over, delta only": time.perf_counter() - t1}

    def compiled_closed():
        return omega_closed(rpm_a).block_until_ready()

    def compiled_delta():
        return delta_closed(rpm_a).block_until_ready()

    rows = {
        "steady_state(engine), tables built every call": (cold, max(3, repeats // 10)),
        "steady_state(engine), tables kept": (warm, repeats),
        "steady_state(prepared)": (python_prepared, repeats),
        "compiled call, prepared engine as an argument, whole omega(theta)": (compiled_argument, repeats),
        "compiled call, prepared engine closed over, whole omega(theta)": (compiled_closed, repeats),
        "compiled call, prepared engine closed over, delta only": (compiled_delta, repeats),
    }
    omega0 = np.asarray(default.omega)

    def omega_gap(omega):  # the largest difference from the default steady state's ω, relative
        return float(np.max(np.abs(np.asarray(omega) - omega0)) / np.mean(omega0))

    checks = {
        "steady_state(engine), tables built every call": ("delta_minus_default", cold() - delta0),
        "steady_state(engine), tables kept": ("delta_minus_default", warm() - delta0),
        "steady_state(prepared)": ("delta_minus_default", python_prepared() - delta0),
        "compiled call, prepared engine as an argument, whole omega(theta)": (
            "omega_max_rel_diff",
            omega_gap(compiled_argument()),
        ),
        "compiled call, prepared engine closed over, whole omega(theta)": (
            "omega_max_rel_diff",
            omega_gap(compiled_closed()),
        ),
        "compiled call, prepared engine closed over, delta only": (
            "delta_minus_default",
            float(compiled_delta()) - delta0,
        ),
    }
    out["rotor"] = {}
    for name, (fn, n) in rows.items():
        t = time_it(fn, enough_repeats(fn, n))
        t["speedup_over_rk45_one_cycle"] = rk45["median_s"] / t["median_s"]
        t[checks[name][0]] = checks[name][1]
        out["rotor"][name] = t
    out["paired"] = paired(
        {
            "default": warm,
            "argument": compiled_argument,
            "closed": compiled_closed,
            "delta only": compiled_delta,
        },
        PAIRED_ROUNDS,
    )
    return out


PAIRED_ROUNDS = 1000
TIMED_S = 0.5  # at least this long in all for each call timed alone


def enough_repeats(fn, repeats):
    """At least ``repeats`` calls of ``fn`` and as many as fill :data:`TIMED_S`: the median of
    a few calls of tens of µs is the machine's moment rather than the call's (the estimate
    from one call after a first)."""
    fn()
    t0 = time.perf_counter()
    fn()
    return max(repeats, min(20000, int(TIMED_S / max(time.perf_counter() - t0, 1e-6))))


def paired(fns, rounds):
    """The calls of ``fns`` taken in turn, ``rounds`` times (after a warm-up round): the
    median time of each [s] and the median over the rounds of the default call's time over
    each other's (a round's calls see the same state of the machine, so that its load
    cancels in the ratio)."""
    for fn in fns.values():
        fn()
    times = {name: [] for name in fns}
    for _ in range(rounds):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    base = np.asarray(times["default"])
    return {
        "rounds": rounds,
        "median_s": {name: statistics.median(v) for name, v in times.items()},
        "default_over": {
            name: float(np.median(base / np.asarray(v))) for name, v in times.items() if name != "default"
        },
    }


def bench_batches(engine, sizes, repeats):
    prepared = rotor.prepare(engine)
    rpm0 = float(engine.operating.rpm)
    J0 = float(engine.crankshaft.inertia_kgm2)
    out = []
    plan = [(n, None) for n in sizes] + [(n, 1) for n in sizes if n == 10**5]
    for n, threads in plan:
        side = int(np.ceil(np.sqrt(n)))
        rpm = np.repeat(np.linspace(0.6 * rpm0, 1.6 * rpm0, side), side)[:n]
        J = np.tile(np.linspace(0.5 * J0, 3.0 * J0, side), side)[:n]
        runs = [
            rotor.steady_sweep(prepared, rpm=rpm, inertia_kgm2=J, threads=threads, progress=False)
            for _ in range(repeats if n <= 10**5 else 1)
        ]
        first = runs[0]
        run_s = statistics.median([r.wall_s - r.compile_s for r in runs])
        out.append(
            {
                "items": n,
                "threads": threads or os.cpu_count(),
                "chunk": first.chunk,
                "compile_s": first.compile_s,
                "run_s_after_compile": run_s,
                "steady_states_per_s": n / run_s,
                "converged": int(np.sum(first.converged)),
                "peak_rss_mb": peak_rss_mb(),
                "repeats": len(runs),
            }
        )
        print(
            f"  {n:>8} items on {threads or os.cpu_count()} threads: {run_s:8.3f} s after "
            f"{first.compile_s:.2f} s compiling, {n / run_s:10.0f} per s (chunks of {first.chunk}), "
            f"peak RSS {peak_rss_mb():.0f} MB",
            flush=True,
        )
    return out


def bench_plain_vmap(engine, items, repeats):
    """The route a user writes without ``steady_sweep``: ``jax.jit(jax.vmap(...))`` over the
    crankshaft inertia put into the engine by ``eqx.tree_at``, δ only, ``items`` at once."""
    rpm = float(engine.operating.rpm)
    J0 = float(engine.crankshaft.inertia_kgm2)

    def delta(J):
        return rotor.steady_state(eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, J), rpm=rpm).delta

    f = jax.jit(jax.vmap(delta))
    Js = jax.numpy.linspace(0.5 * J0, 3.0 * J0, items)
    t0 = time.perf_counter()
    first = np.asarray(f(Js))
    first_s = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f(Js).block_until_ready()
        times.append(time.perf_counter() - t0)
    run = statistics.median(times)
    one = float(rotor.steady_state(eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, Js[7]), rpm=rpm).delta)
    return {
        "items": items,
        "first_call_s": first_s,
        "median_s": run,
        "per_item_s": run / items,
        "repeats": repeats,
        "delta_item_7_minus_one_call": float(first[7]) - one,
    }


SPEED_FRICTION = {"fmep_pa": 0.8e5, "fmep_per_speed_pa_s_per_m": 2000.0}
"""The ``[friction]`` table of docs/how-to/write-an-engine-file.md: its speed-linear term
(b) is what the closed form takes by a fixed point."""


def _engine_file(preset, friction, folder):
    """A copy of the ``preset``'s engine file with ``friction`` (a dict, or None: none) as its
    ``[friction]`` table, in ``folder``: what ``rotor flywheel`` reads."""
    text = (Path(rotor.__file__).parent / "presets" / f"{preset}.toml").read_text()
    path = Path(folder) / f"{preset}-{'b' if friction and friction.get('fmep_per_speed_pa_s_per_m') else 'a'}.toml"
    if friction:
        text += "\n[friction]\n" + "".join(f"{k} = {v!r}\n" for k, v in friction.items())
    path.write_text(text)
    return path


def bench_speed_friction(preset, engine, repeats, items=10**4, flywheel_runs=3):
    """The engine with the docs' friction (speed-linear term b) against the same friction
    without b, in turn, each case the same calls: one ``steady_state(engine, friction=…)``
    (the default call; its method), one compiled call of the prepared engine closed over,
    ``steady_sweep`` of ``items`` speeds × inertias, and ``rotor flywheel`` (an engine file
    with the ``[friction]`` table, a fresh process each, the compilation cache warm: the
    medians of ``flywheel_runs`` after one to fill it)."""
    import subprocess
    import tempfile

    with_b = rotor.Friction(**SPEED_FRICTION)
    without_b = rotor.Friction(fmep_pa=SPEED_FRICTION["fmep_pa"])
    prepared = rotor.prepare(engine)
    rpm0, J0 = float(engine.operating.rpm), float(engine.crankshaft.inertia_kgm2)
    side = int(np.ceil(np.sqrt(items)))
    rpm = np.repeat(np.linspace(0.6 * rpm0, 1.6 * rpm0, side), side)[:items]
    J = np.tile(np.linspace(0.5 * J0, 3.0 * J0, side), side)[:items]
    rpm_a = jax.numpy.asarray(rpm0)
    calls, methods, sweeps = {}, {}, {}
    for name, fr in (("without b", without_b), ("with b", with_b)):
        methods[name] = rotor.steady_state(engine, friction=fr).method
        closed_over = jax.jit(lambda r, fr=fr: rotor.steady_state(prepared, r, friction=fr).delta)
        closed_over = closed_over.lower(rpm_a).compile()
        key = "default" if name == "without b" else f"steady_state(engine, friction), {name}"
        calls[key] = lambda fr=fr: float(rotor.steady_state(engine, friction=fr).delta)
        calls[f"compiled call, prepared engine closed over, delta, {name}"] = lambda f=closed_over: f(
            rpm_a
        ).block_until_ready()
        sweeps[name] = lambda fr=fr: rotor.steady_sweep(prepared, rpm=rpm, inertia_kgm2=J, friction=fr, progress=False)
    paired_calls = paired(calls, max(50, repeats))
    sweep_runs = {name: [] for name in sweeps}
    for fn in sweeps.values():
        fn()  # compile
    for _ in range(3):
        for name, fn in sweeps.items():
            r = fn()
            sweep_runs[name].append(r.wall_s - r.compile_s)
            assert r.converged.all(), name
    with tempfile.TemporaryDirectory() as folder:
        files = {"without b": _engine_file(preset, {"fmep_pa": SPEED_FRICTION["fmep_pa"]}, folder)}
        files["with b"] = _engine_file(preset, SPEED_FRICTION, folder)
        command = [str(Path(sys.executable).parent / "rotor"), "flywheel", "--delta", "0.01", "--rpm", "800,1250,2000"]
        flywheel = {name: [] for name in files}
        for path in files.values():  # the compilation cache filled for each
            subprocess.run([*command, str(path)], check=True, capture_output=True)
        for _ in range(flywheel_runs):
            for name, path in files.items():
                t0 = time.perf_counter()
                subprocess.run([*command, str(path)], check=True, capture_output=True)
                flywheel[name].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in sweep_runs.items()}
    fly = {k: statistics.median(v) for k, v in flywheel.items()}
    return {
        "friction": SPEED_FRICTION,
        "methods": methods,
        "paired": paired_calls,
        "steady_state_with_over_without": 1.0 / paired_calls["default_over"]["steady_state(engine, friction), with b"],
        "compiled_with_over_without": paired_calls["median_s"][
            "compiled call, prepared engine closed over, delta, with b"
        ]
        / paired_calls["median_s"]["compiled call, prepared engine closed over, delta, without b"],
        "sweep_items": items,
        "sweep_run_s": med,
        "sweep_with_over_without": med["with b"] / med["without b"],
        "flywheel_command": "rotor " + " ".join(command[1:]) + " ENGINE.toml",
        "flywheel_s": fly,
        "flywheel_with_over_without": fly["with b"] / fly["without b"],
        "load_average": os.getloadavg(),
    }


def plot(res, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 4.8))
    single = res["single"]
    names = ["scipy RK45, one cycle"] + list(single["rotor"])
    times = [single["scipy_rk45_one_cycle"]["median_s"]] + [v["median_s"] for v in single["rotor"].values()]
    a.barh(range(len(names)), np.asarray(times) * 1e6, color=["C1"] + ["C0"] * (len(names) - 1))
    a.set_yticks(range(len(names)), [n.replace(", ", ",\n", 1) for n in names], fontsize=7)
    a.set_xscale("log")
    a.set_xlabel("median time after compile [µs]")
    a.set_title(f"{res['engine']}: one steady state vs one RK45 cycle")
    for threads in sorted({r["threads"] for r in res["batches"]}):
        rows = [r for r in res["batches"] if r["threads"] == threads]
        b.loglog([r["items"] for r in rows], [r["steady_states_per_s"] for r in rows], "o-", label=f"{threads} threads")
    b.legend()
    b.set_xlabel("items in the sweep")
    b.set_ylabel("steady states per second (after compile)")
    b.set_title("rotor.steady_sweep, speed × flywheel inertia")
    b.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def print_speed_friction(f):
    pair = f["paired"]
    print(f"speed-dependent friction {f['friction']} against the same without b (methods {f['methods']}):")
    print("  ('default': steady_state(engine, friction) without b)")
    for name, t in pair["median_s"].items():
        print(f"  {name:<70} {t * 1e6:10.1f} µs")
    print(
        f"  with over without: steady_state {f['steady_state_with_over_without']:.2f}×, compiled call "
        f"{f['compiled_with_over_without']:.2f}×, steady_sweep of {f['sweep_items']} "
        f"{f['sweep_run_s']['with b']:.3f} s / {f['sweep_run_s']['without b']:.3f} s = {f['sweep_with_over_without']:.2f}×, "
        f"rotor flywheel {f['flywheel_s']['with b']:.2f} s / {f['flywheel_s']['without b']:.2f} s = "
        f"{f['flywheel_with_over_without']:.2f}× (load average {f['load_average'][0]:.1f})"
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engine", default="4chn15")
    ap.add_argument("--quick", action="store_true", help="fewer repeats, batches up to 10⁴")
    ap.add_argument("--full", action="store_true", help="batches up to 10⁶ items")
    ap.add_argument(
        "--sync-dispatch",
        action="store_true",
        help="run JAX's programs in the calling thread (jax_cpu_enable_async_dispatch off)",
    )
    ap.add_argument(
        "--only-friction", action="store_true", help="only the speed-dependent friction case (writes its own JSON)"
    )
    args = ap.parse_args()
    if args.sync_dispatch:  # before JAX's CPU backend starts
        jax.config.update("jax_cpu_enable_async_dispatch", False)
    repeats = 21 if args.quick else 101
    sizes = [1, 10, 100, 1000, 10**4] + ([] if args.quick else [10**5]) + ([10**6] if args.full else [])
    engine = rotor.load_engine(args.engine)
    res = {
        "engine": args.engine,
        "quick": args.quick,
        "async_dispatch": jax.config.values["jax_cpu_enable_async_dispatch"],
        "versions": versions(),
        "notes": __doc__,
    }
    if args.only_friction:
        res["speed_friction"] = bench_speed_friction(args.engine, engine, repeats)
        print_speed_friction(res["speed_friction"])
        RESULTS.mkdir(parents=True, exist_ok=True)
        write_text_atomic(RESULTS / "steady_limit_friction.json", json.dumps(res, indent=2, ensure_ascii=False))
        print(f"wrote {RESULTS / 'steady_limit_friction.json'}")
        return
    res["single"] = bench_single(engine, repeats)
    rk = res["single"]["scipy_rk45_one_cycle"]["median_s"]
    print(f"{args.engine} at {res['single']['rpm']:g} rpm; one cycle of scipy RK45 (rtol 1e-8): {rk * 1e3:.2f} ms")
    for name, t in res["single"]["rotor"].items():
        print(
            f"  {name:<66} {t['median_s'] * 1e6:10.1f} µs  {t['speedup_over_rk45_one_cycle']:8.0f}×  "
            + (
                f"δ − default {t['delta_minus_default']:+.1e}"
                if "delta_minus_default" in t
                else f"max |ω − default|/ω̄ {t['omega_max_rel_diff']:.1e}"
            )
            + f"  (first call {t['first_call_s']:.2f} s)"
        )
    pair = res["single"]["paired"]
    print(
        f"  in turn, {pair['rounds']} rounds: "
        + ", ".join(f"{k} {v * 1e6:.1f} µs" for k, v in pair["median_s"].items())
        + "; the default call over each (median of the rounds' ratios): "
        + ", ".join(f"{k} {v:.2f}×" for k, v in pair["default_over"].items())
    )
    print(
        "  compiling the closed-over calls ahead of time: "
        + ", ".join(f"{k} {v:.2f} s" for k, v in res["single"]["compile_s"].items())
    )
    plain = res["plain_jit_vmap"] = bench_plain_vmap(engine, 10**4, 3)
    print(
        f"  jax.jit(jax.vmap(steady_state over eqx.tree_at inertia)).delta, {plain['items']} items: "
        f"{plain['per_item_s'] * 1e3:.3f} ms an item (first call {plain['first_call_s']:.1f} s; "
        f"item 7 − its own call {plain['delta_item_7_minus_one_call']:+.1e})"
    )
    print("throughput of rotor.steady_sweep (speed × inertia grid):")
    res["batches"] = bench_batches(engine, sizes, 3)
    res["speed_friction"] = bench_speed_friction(args.engine, engine, repeats)
    print_speed_friction(res["speed_friction"])
    RESULTS.mkdir(parents=True, exist_ok=True)
    write_text_atomic(RESULTS / "steady_limit.json", json.dumps(res, indent=2, ensure_ascii=False))
    plot(res, RESULTS / "steady_limit.png")
    print(f"wrote {RESULTS / 'steady_limit.json'} and {RESULTS / 'steady_limit.png'}")


if __name__ == "__main__":
    main()
