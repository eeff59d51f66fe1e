"""Where a warm call of a `rotor` command spends its time.

A warm call is a fresh process whose compilation cache was filled by an earlier call of the
same command (``benchmarks/cli_latency.py`` times it whole). Here each command runs in a
fresh process that imports the command line, then runs it there as the ``rotor`` command does
(``rotor.cli.app.main()`` with ``sys.argv``) with JAX's monitoring events recorded, and
splits its wall time into:

- ``import_s``: importing ``rotor.cli.app`` (and JAX, equinox and what the command needs
  at import);
- ``tracing_s``: JAX tracing Python functions into programs (``jaxpr_trace_duration``);
- ``lowering_s``: turning them into XLA's input (``jaxpr_to_mlir_module_duration``), which
  the persistent cache needs for its key;
- ``compile_or_load_s``: XLA compiling a program or reading it back from the persistent cache
  (JAX's ``backend_compile_duration`` covers both; ``from_cache`` of them were read back);
- ``kept_read_s``: reading the kernels' kept programs from disk (:mod:`rotor.programs`;
  ``kept_slowest``: the three slowest kernels); a kernel whose program is not on disk is
  compiled there, and that time is also in the three columns above (a warm call has none);
- ``rest_s``: the rest of the call: running the programs, rotor's own Python, writing the
  output;
- ``again_s``: the same command run a second time in the same process (its modules
  imported, its programs loaded, nothing traced): the command's own work, a floor of its own.

The programs traced most are listed per command (``top``). Medians of ``--repeats`` fresh
processes after one untimed call that fills a new cache folder.

    .venv/bin/python benchmarks/warm_call_profile.py                 # 3 repeats, every command
    .venv/bin/python benchmarks/warm_call_profile.py --only steady   # commands that start so

Writes benchmarks/results/warm_call_profile.json.
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

from cli_latency import COMPILED, TUE

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"

CHILD = r"""
import collections, contextlib, io, json, os, sys, time
t0 = time.perf_counter()
from rotor.cli.app import main
import jax
t_import = time.perf_counter() - t0
events = collections.defaultdict(float)
names = collections.defaultdict(float)
hits = [0]
def on_duration(event, duration_secs, fun_name="?", **_):
    if event.startswith("/jax/core/compile/"):
        kind = event.rsplit("/", 1)[-1]
        events[kind] += duration_secs
        if kind == "jaxpr_trace_duration":
            names[fun_name] += duration_secs
def on_event(event, **_):
    if event == "/jax/compilation_cache/cache_hits":
        hits[0] += 1
jax.monitoring.register_event_duration_secs_listener(on_duration)
jax.monitoring.register_event_listener(on_event)
from rotor import programs
find = programs._Kept._program
kept = collections.defaultdict(float)
def timed_find(self, folder, key):  # a kept program read from disk (or compiled where it is not there)
    t = time.perf_counter()
    try:
        return find(self, folder, key)
    finally:
        kept[self.name.rsplit(".", 1)[-1]] += time.perf_counter() - t
programs._Kept._program = timed_find
sys.argv = ["rotor", *json.loads(sys.argv[1])]  # main() as the command runs it (argv None)
t1 = time.perf_counter()
with contextlib.redirect_stdout(io.StringIO()):
    rc = main()
t_call = time.perf_counter() - t1
kept_first = dict(kept)
t2 = time.perf_counter()
with contextlib.redirect_stdout(io.StringIO()):
    main()
t_again = time.perf_counter() - t2
top = sorted(names.items(), key=lambda kv: -kv[1])[:8]
print(json.dumps({"rc": rc, "import_s": t_import, "call_s": t_call, "again_s": t_again, "events": dict(events),
                  "from_cache": hits[0], "top": top, "kept": kept_first}))
"""


def run(argv: list[str], env: dict) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", CHILD, json.dumps(argv)], env=env, capture_output=True, text=True, check=False
    )
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    if out.returncode != 0 or not lines:
        raise SystemExit(f"{' '.join(argv)}: exit {out.returncode}: {out.stderr.strip()[-400:]}")
    return json.loads(lines[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--only", action="append", default=[], help="commands whose name starts so (repeatable)")
    args = ap.parse_args()
    commands = {k: v for k, v in COMPILED.items() if not args.only or any(k.startswith(o) for o in args.only)}
    if not TUE.exists():
        commands = {k: v for k, v in commands.items() if "tue-4gb10" not in k}
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        env = {
            **os.environ,
            "ROTOR_COMPILATION_CACHE": str(Path(scratch) / "cache"),
            "ROTOR_TABLE_CACHE": str(Path(scratch) / "tables"),
            "ROTOR_OUTPUT_CACHE": "off",
            "PYTHONPATH": str(ROOT / "benchmarks"),
        }
        for name, argv in commands.items():
            argv = [a.replace("{tmp}", scratch) for a in argv]
            run(argv, env)  # fills the cache
            runs = [run(argv, env) for _ in range(args.repeats)]

            def med(f):
                return statistics.median(f(r) for r in runs)

            row = {
                "command": name,
                "import_s": med(lambda r: r["import_s"]),
                "call_s": med(lambda r: r["call_s"]),
                "again_s": med(lambda r: r["again_s"]),
                "tracing_s": med(lambda r: r["events"].get("jaxpr_trace_duration", 0.0)),
                "lowering_s": med(lambda r: r["events"].get("jaxpr_to_mlir_module_duration", 0.0)),
                "compile_or_load_s": med(lambda r: r["events"].get("backend_compile_duration", 0.0)),
                "from_cache": med(lambda r: r["from_cache"]),
                "kept_programs": med(lambda r: len(r["kept"])),
                "kept_read_s": med(lambda r: sum(r["kept"].values())),
                "kept_slowest": sorted(runs[-1]["kept"].items(), key=lambda kv: -kv[1])[:3],
                "top": runs[-1]["top"],
            }
            row["rest_s"] = (
                row["call_s"] - row["tracing_s"] - row["lowering_s"] - row["compile_or_load_s"] - row["kept_read_s"]
            )
            rows.append(row)
            print(
                f"{name:46s} import {row['import_s']:.2f} s, call {row['call_s']:.2f} s: tracing "
                f"{row['tracing_s']:.2f}, lowering {row['lowering_s']:.2f}, compiling or loading "
                f"{row['compile_or_load_s']:.2f}, kept programs read {row['kept_read_s']:.2f} "
                f"({row['kept_programs']:.0f} kernels; slowest "
                + ", ".join(f"{k} {v:.2f}" for k, v in row["kept_slowest"])
                + f"), rest {row['rest_s']:.2f} ({row['from_cache']:.0f} programs from the cache); "
                f"again in the process {row['again_s']:.2f} s",
                flush=True,
            )
    import jax

    RESULTS.mkdir(parents=True, exist_ok=True)
    out = RESULTS / "warm_call_profile.json"
    out.write_text(
        json.dumps(
            {
                "repeats": args.repeats,
                "python": platform.python_version(),
                "jax": jax.__version__,
                "machine": f"{platform.machine()}, {os.cpu_count()} CPUs",
                "rows": rows,
            },
            indent=1,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
