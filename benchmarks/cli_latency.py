"""Wall time of `rotor` commands, each in a fresh process, with a cold and a warm
compilation cache.

The commands that need no JAX (``--help``, ``COMMAND --help``, ``presets``) and the ones
that compile one small kernel each (``info 4chn15``, ``table 4chn15``) have a target of 1.5 s; every
command that computes (``steady``, ``simulate`` with the default and the angle method,
``loads``, ``balance``, ``flywheel``, ``plot``, ``modes``, ``campbell``, ``torsion``,
``report``, and ``analyze``, ``diagnose``, ``calibrate`` of a tue-4gb10 recording) is
measured for its first call and its warm call, and so for what the persistent
compilation cache (rotor/cache.py) saves it. "cold": each run gets a new, empty cache
folder (``ROTOR_COMPILATION_CACHE``: a user's very first run); "warm": every run shares a
folder that one untimed run filled first (every later run); "kept": warm, and the output
of the same call kept by an untimed run (rotor/cli/kept.py: ``table`` and ``info`` then
print it without importing JAX); "warm, tables built": warm, but the engines' tables are
built in every process instead of read from their folder (``ROTOR_TABLE_CACHE=off``: the
baseline of what keeping them saves). "cold" and "warm" compute every time. The repeats go round the
commands in turn, so that the load of a shared machine falls on all of them alike; the
median of each is reported, with every time. Three reference processes put the figures in
proportion: ``python -c pass``, ``python -c 'import jax'`` and ``python -c 'import jax,
equinox'`` (JAX's and equinox's imports are the floor of every command that computes).
Each run's CPU time (user + system) is recorded beside its wall time.

    .venv/bin/python benchmarks/cli_latency.py            # 7 repeats, every command (about an hour)
    .venv/bin/python benchmarks/cli_latency.py --quick    # 3 repeats, light commands only
    .venv/bin/python benchmarks/cli_latency.py --repeats 5 --no-cold --only steady --only modes
    .venv/bin/python benchmarks/cli_latency.py --new-engine --repeats 3   # a second engine file, warm

``--new-engine``: ``steady``, ``flywheel``, ``report`` and ``diagnose`` on a preset (engine A,
warm) and on another engine file of the same shape (engine B, first call in a fresh
process, the cache filled by A), in turn, and a first ``jax.grad`` of δ in a fresh process
for B against A's second; B over A (target 1.5×). Engine B of ``diagnose`` has no shipped
calibration (A, the tue-single preset, has one).

Writes benchmarks/results/cli_latency.json (cli_latency_quick.json with --quick).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
TARGET_S = 1.5
NO_JAX = {  # need no JAX: the cache plays no part, one case each
    "--help": ["--help"],
    "table --help": ["table", "--help"],
    "steady --help": ["steady", "--help"],
    "presets": ["presets"],
}
LIGHT = {  # one small compiled kernel each
    "info 4chn15": ["info", "4chn15"],
    "table 4chn15": ["table", "4chn15"],
}
TUE = ROOT.parent / "shared" / "data" / "tue-4gb10" / "full_load.txt"
TUE_ARGS = ["--wheel", "60-2", "--columns", "time,pressure_v,encoder_v"]
COMPILED = {  # every command that computes; {tmp}: a scratch folder of the run's own
    "steady 4chn15": ["steady", "4chn15"],
    "simulate 4chn15 --cycles 20": ["simulate", "4chn15", "--cycles", "20", "--quiet"],
    "simulate 4chn15 --cycles 100 --method angle": [
        *("simulate", "4chn15", "--cycles", "100", "--method", "angle", "--quiet")
    ],
    "loads 4chn15": ["loads", "4chn15"],
    "balance 4chn15": ["balance", "4chn15"],
    "flywheel 4chn15 --delta 0.01": ["flywheel", "4chn15", "--delta", "0.01"],
    "plot 4chn15": ["plot", "4chn15", "--plot", "{tmp}/plot"],
    "modes mwm6": ["modes", "mwm6"],
    "campbell mwm6": ["campbell", "mwm6"],
    "torsion mwm6": ["torsion", "mwm6"],
    "report 4chn15": ["report", "4chn15", "--out", "{tmp}/report"],
    "analyze tue-4gb10": ["analyze", str(TUE), *TUE_ARGS],
    "diagnose tue-4gb10": ["diagnose", str(TUE), "--engine", "tue-single", *TUE_ARGS, "--pressure-gain", "1"],
    "calibrate tue-4gb10": ["calibrate", str(TUE), "--engine", "tue-single", *TUE_ARGS],
}
"""The commands of the full run: the first call ("cold", an empty compilation cache) and the
warm call (a fresh process, the cache filled by an earlier one) of each; the ones on the
tue-4gb10 recording are left out where ../shared/data is missing."""
REFERENCES = {
    "python -c pass": "pass",
    "import jax": "import jax",
    "import jax, equinox": "import jax, equinox",
    # the same, ended as the rotor command ends (no teardown of the modules): what the
    # interpreter's teardown costs, which the floor above pays and a rotor command does not
    "import jax, equinox; os._exit(0)": "import jax, equinox, os; os._exit(0)",
    "import rotor": "import rotor",
}


PHASES = r"""
import json, sys, time
t = [time.perf_counter()]
def lap():
    t.append(time.perf_counter())
    return t[-1] - t[-2]
out = {}
from rotor.cli.app import build_parser
from rotor.cache import enable_compilation_cache
args = build_parser().parse_args(sys.argv[1:])
enable_compilation_cache(min_compile_time_s=0.0)  # as the command does
out["cli: parser"] = lap()
import jax
out["import jax"] = lap()
import equinox
out["import equinox"] = lap()
from rotor.engine.file import load_engine
from rotor.engine.summary import engine_summary
from rotor.engine.table import crank_table
out["import rotor.engine"] = lap()
engine = load_engine(args.engine)
out["load_engine"] = lap()
if args.command == "table":
    text = crank_table(engine).to_text()
else:
    text = engine_summary(engine).summary()
out[f"compute ({args.command}, compiled call from the cache)"] = lap()
if args.command == "table":
    crank_table(engine).to_text()
else:
    engine_summary(engine).summary()
out["the same again in the process (compiled, no tracing)"] = lap()
print(json.dumps(out))
"""


def phases(command: str, cache: str, repeats: int) -> dict:
    """Median seconds of each phase of ``rotor COMMAND 4chn15`` timed inside the process
    (warm cache), and the process's wall time for comparison."""
    runs = []
    env = dict(os.environ, ROTOR_COMPILATION_CACHE=cache, ROTOR_TABLE_CACHE=cache + "-tables", ROTOR_OUTPUT_CACHE="off")
    argv = [sys.executable, "-c", PHASES, command, "4chn15"]
    subprocess.run(argv, env=env, check=True, capture_output=True)  # fills the cache
    for _ in range(repeats):
        start = time.perf_counter()
        out = subprocess.run(argv, env=env, check=True, capture_output=True, text=True)
        runs.append({"process": time.perf_counter() - start, **json.loads(out.stdout.strip().splitlines()[-1])})
    return {k: statistics.median(r[k] for r in runs) for k in runs[0]}


def rotor_exe() -> list[str]:
    """The ``rotor`` script next to this Python (the installed entry point), else ``python -m rotor.cli``."""
    exe = Path(sys.executable).with_name("rotor")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rotor.cli"]


def wall(argv: list[str], cache: str, outputs: str = "off", tables: bool = True) -> tuple[float, float]:
    """Seconds from start to exit of ``argv`` in a fresh process with the compilation cache
    ``cache`` and the kept outputs ``outputs`` (rotor/cli/kept.py; "off": computed every
    time), and the CPU seconds it used (user + system: less sensitive than the wall time
    to the other jobs of a shared machine, but counting every thread of the process). The
    engines' tables are kept in a folder beside ``cache`` (``tables=False``: not kept, built
    in every process)."""
    env = dict(
        os.environ,
        ROTOR_COMPILATION_CACHE=cache,
        ROTOR_TABLE_CACHE=cache + "-tables" if tables else "off",
        ROTOR_OUTPUT_CACHE=outputs,
    )
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    out = subprocess.run(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    took = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode:
        raise RuntimeError(f"{' '.join(argv)}: exit {out.returncode}: {out.stderr.strip()[-500:]}")
    return took, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def versions() -> dict:
    import equinox
    import jax
    import jaxlib
    import numpy

    return {m.__name__: m.__version__ for m in (jax, jaxlib, equinox, numpy)} | {
        "python": platform.python_version(),
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
    }


def loadavg() -> list[float] | None:
    try:
        return list(os.getloadavg())
    except OSError:
        return None


def summarize(runs: list[tuple[float, float]]) -> dict:
    times, cpu = [w for w, _ in runs], [c for _, c in runs]
    return {
        "median_s": statistics.median(times),
        "min_s": min(times),
        "cpu_median_s": statistics.median(cpu),
        "times_s": times,
        "cpu_s": cpu,
    }


NEW_ENGINE = {  # command -> (the preset it derives from, argv with {engine} and {tmp})
    "steady": ("4chn15", ["steady", "{engine}"]),
    "flywheel --delta 0.01": ("4chn15", ["flywheel", "{engine}", "--delta", "0.01"]),
    "report": ("4chn15", ["report", "{engine}", "--out", "{tmp}/report"]),
    "diagnose tue-4gb10": (
        "tue-single",
        ["diagnose", str(TUE), "--engine", "{engine}", *TUE_ARGS, "--pressure-gain", "1"],
    ),
}
"""``--new-engine``: each command on its preset (engine A, warm) and on another engine file
of the same shape (engine B: another name, bore, reciprocating mass and flywheel (not where a
torsion chain must sum to it); a new
file in every repeat, so that its tables and programs are never its own from before)."""

GRAD = r"""
import sys
import rotor
rotor.enable_compilation_cache()
import equinox as eqx, jax
engine = rotor.load_engine(sys.argv[1])
def delta(j):
    return rotor.steady_state(eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, j)).delta
print(float(jax.grad(delta)(float(engine.crankshaft.inertia_kgm2))))
"""
"""A first ``jax.grad`` of δ with respect to the flywheel inertia in a fresh process, as a
user writes it (the compilation cache on, as ``rotor.enable_compilation_cache()`` does)."""


def engine_b(preset: str, folder: Path, r: int) -> str:
    """A new engine file of ``preset``'s shape for repeat ``r``: its numbers changed a little
    in every repeat (another engine for the table folder and the compiled programs alike)."""
    import re

    text = (ROOT / "rotor" / "presets" / f"{preset}.toml").read_text()
    changes = [("bore_m", 0.97), ("reciprocating_kg", 0.92)]
    if "[torsion]" not in text:  # a torsion chain's inertias sum to the crankshaft's: left as they are
        changes.append(("inertia_kgm2", 0.75))
    for key, factor in changes:
        text, n = re.subn(
            rf"^{key} = ([0-9.eE+-]+)",
            lambda m: f"{key} = {float(m.group(1)) * (factor - 0.001 * r):.6g}",
            text,
            count=1,
            flags=re.M,
        )
        assert n == 1, (preset, key)
    text = re.sub(r"^name = .*$", f'name = "engine B {r}"', text, count=1, flags=re.M)
    path = folder / f"{preset}-b{r}.toml"
    path.write_text(text)
    return str(path)


def new_engine(rotor: list[str], repeats: int, only: list[str] | None) -> dict:
    """``--new-engine``: engine A (the preset) warm and engine B (:func:`engine_b`) first, in
    turn, in fresh processes sharing a compilation cache that engine A filled; and the
    ``jax.grad`` of δ (:data:`GRAD`) for engine A run a second time and engine B."""
    commands = {k: v for k, v in NEW_ENGINE.items() if (TUE.exists() or "tue-4gb10" not in k)}
    if only:
        commands = {k: v for k, v in commands.items() if any(o in k for o in only)}
    top = Path(tempfile.mkdtemp(prefix="rotor-new-engine-"))
    cache = str(top / "cache")
    times: dict[str, list[tuple[float, float]]] = {}
    try:
        cases = {
            f"rotor {k} [A, warm]": ([*rotor, *(a.replace("{tmp}", str(top)) for a in argv)], preset, False)
            for k, (preset, argv) in commands.items()
        }
        cases |= {
            f"rotor {k} [B, first]": ([*rotor, *(a.replace("{tmp}", str(top)) for a in argv)], preset, True)
            for k, (preset, argv) in commands.items()
        }
        cases["jax.grad of delta [A, second]"] = ([sys.executable, "-c", GRAD, "{engine}"], "4chn15", False)
        cases["jax.grad of delta [B, first]"] = ([sys.executable, "-c", GRAD, "{engine}"], "4chn15", True)
        times = {name: [] for name in cases}
        for argv, preset, is_b in cases.values():  # engine A fills the cache (untimed), twice
            if not is_b:
                for _ in range(2):
                    wall([a.replace("{engine}", preset) for a in argv], cache)
        for r in range(repeats):
            for name, (argv, preset, is_b) in cases.items():
                engine = engine_b(preset, top, r) if is_b else preset
                times[name].append(wall([a.replace("{engine}", engine) for a in argv], cache))
            print(f"repeat {r + 1}/{repeats} done", flush=True)
    finally:
        shutil.rmtree(top, ignore_errors=True)
    results = {name: summarize(t) for name, t in times.items()}
    ratios = {}
    for name in results:
        if name.endswith("[B, first]"):
            base = name.replace("[B, first]", "[A, warm]" if name.startswith("rotor") else "[A, second]")
            ratios[name.replace(" [B, first]", "")] = results[name]["median_s"] / results[base]["median_s"]
    return {"results": results, "b_over_a": ratios, "target": 1.5}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 repeats, the light commands only")
    ap.add_argument("--repeats", type=int, help="repeats of each command (default 7, 3 with --quick)")
    ap.add_argument("--only", action="append", metavar="NAME", help="only the commands whose name contains NAME")
    ap.add_argument("--no-cold", action="store_true", help="the warm calls only (the cold ones take minutes)")
    ap.add_argument(
        "--new-engine",
        action="store_true",
        help="a second engine file of the same shape against the first, warm (writes cli_latency_new_engine.json)",
    )
    args = ap.parse_args()
    repeats = args.repeats or (3 if args.quick else 7)
    rotor = rotor_exe()
    if args.new_engine:
        load_before = loadavg()
        res = new_engine(rotor, repeats, args.only)
        res |= {"versions": versions(), "repeats": repeats, "loadavg_before": load_before, "loadavg_after": loadavg()}
        for name, r in res["results"].items():
            print(f"{name:45s} {r['median_s']:6.2f}s (CPU {r['cpu_median_s']:6.2f}s)")
        for name, x in res["b_over_a"].items():
            print(
                f"  {name}: engine B first over engine A (warm; the grad: its second run) {x:.2f}× (target {res['target']}×)"
            )
        RESULTS.mkdir(parents=True, exist_ok=True)
        sys.path.insert(0, str(ROOT))
        from rotor.fileio import write_text_atomic

        write_text_atomic(RESULTS / "cli_latency_new_engine.json", json.dumps(res, indent=1))
        print(f"wrote {RESULTS / 'cli_latency_new_engine.json'}")
        return
    light = dict(LIGHT)
    compiled = {} if args.quick else {k: v for k, v in COMPILED.items() if TUE.exists() or "tue-4gb10" not in k}
    if args.only:
        light = {k: v for k, v in light.items() if any(o in k for o in args.only)}
        compiled = {k: v for k, v in compiled.items() if any(o in k for o in args.only)}
    cases: dict[str, tuple[list[str], str]] = {}  # name -> (argv, "cold" | "warm" | "off")
    for name, code in REFERENCES.items():
        cases[name] = ([sys.executable, "-c", code], "off")
    for name, argv in NO_JAX.items():
        cases[f"rotor {name}"] = ([*rotor, *argv], "warm")
    top = Path(tempfile.mkdtemp(prefix="rotor-cli-latency-"))
    for name, argv in {**light, **compiled}.items():
        kinds = (
            (() if args.no_cold else ("cold",)) + ("warm",) + (("kept",) if name in light else ("warm, tables built",))
        )
        for kind in kinds:
            cases[f"rotor {name} [{kind}]"] = ([*rotor, *(a.replace("{tmp}", str(top)) for a in argv)], kind)
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in cases}
    load_before = loadavg()
    try:
        warm, kept = str(top / "warm"), str(top / "outputs")
        for argv, kind in cases.values():  # fill the warm cache and the kept outputs (untimed)
            if kind in ("warm", "kept", "warm, tables built"):
                wall(argv, warm, kept if kind == "kept" else "off", tables=kind != "warm, tables built")
        for r in range(repeats):
            for name, (argv, kind) in cases.items():
                if kind == "cold":
                    cache = str(top / f"cold-{r}-{list(cases).index(name)}")
                elif kind in ("warm", "kept", "warm, tables built"):
                    cache = warm
                else:
                    cache = "off"
                times[name].append(
                    wall(argv, cache, kept if kind == "kept" else "off", tables=kind != "warm, tables built")
                )
                if kind == "cold":
                    shutil.rmtree(cache, ignore_errors=True)
            print(f"repeat {r + 1}/{repeats} done", flush=True)
        breakdown = {c: phases(c, str(top / f"phases-{c}"), repeats) for c in ("table", "info")}
    finally:
        shutil.rmtree(top, ignore_errors=True)
    out = {
        "versions": versions(),
        "target_s": TARGET_S,
        "repeats": repeats,
        "loadavg_before": load_before,
        "loadavg_after": loadavg(),
        "rotor": rotor,
        "no_jax_commands": list(NO_JAX),
        "light_commands": list(light),
        "compiled_commands": list(compiled),
        "results": {name: summarize(t) for name, t in times.items()},
        "phases_warm_median_s": breakdown,
    }
    width = max(len(n) for n in times)
    print(f"{'':{width}s} {'median':>7s} {'min':>7s} {'CPU':>7s}")
    for name, r in out["results"].items():
        print(f"{name:{width}s} {r['median_s']:6.2f}s {r['min_s']:6.2f}s {r['cpu_median_s']:6.2f}s")
    for command, parts in breakdown.items():
        print(f"rotor {command} 4chn15, warm cache, phases inside the process (medians):")
        for k, v in parts.items():
            print(f"  {k:55s} {v:6.3f}s")
    RESULTS.mkdir(parents=True, exist_ok=True)
    stem = "cli_latency_quick" if args.quick else "cli_latency"
    sys.path.insert(0, str(ROOT))
    from rotor.fileio import write_text_atomic

    write_text_atomic(RESULTS / f"{stem}.json", json.dumps(out, indent=1))
    print(f"wrote {RESULTS / (stem + '.json')}")


if __name__ == "__main__":
    main()
