"""Does a second process find every program of a command in the compilation cache?

Each command of ``benchmarks/cli_latency.py``'s full run, twice, in fresh processes that
share a new, empty compilation cache (the engines' tables built in each, rotor's kept
programs off, so that JAX's own cache serves every program): the programs the second
process asked XLA for and how many of them it read back. A program holding a host callback
is never stored, so the second process compiles it again: ``hits < requests`` names such a
command. Not a timing: ``cli_latency.py`` measures what the cache saves.

    .venv/bin/python benchmarks/cache_hits.py [--only NAME ...]   # about a minute

Writes ``benchmarks/results/cache_hits.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

from cli_latency import COMPILED, RESULTS, TUE, versions

from rotor.fileio import write_text_atomic

COUNT = """
import json, sys
import jax.monitoring
counts = {"requests": 0, "hits": 0}
def seen(event, **_):
    if event == "/jax/compilation_cache/compile_requests_use_cache":
        counts["requests"] += 1
    elif event == "/jax/compilation_cache/cache_hits":
        counts["hits"] += 1
jax.monitoring.register_event_listener(seen)
from rotor.cli.app import main
sys.argv[0] = "rotor"
code = main()
print(json.dumps(counts), file=sys.stderr)
sys.exit(code)
"""


def twice(argv: list[str]) -> list[dict]:
    """The program counts of the first and the second process running ``rotor argv``."""
    with tempfile.TemporaryDirectory() as d:
        env = dict(
            os.environ,
            ROTOR_COMPILATION_CACHE=f"{d}/cache",
            ROTOR_TABLE_CACHE="off",
            ROTOR_PROGRAM_CACHE="off",
            ROTOR_OUTPUT_CACHE="off",
        )
        counts = []
        for i in range(2):
            args = [a.replace("{tmp}", f"{d}/run{i}") for a in argv]
            out = subprocess.run([sys.executable, "-c", COUNT, *args], env=env, capture_output=True, text=True, cwd=d)
            if out.returncode:
                raise RuntimeError(f"rotor {' '.join(args)}: exit {out.returncode}: {out.stderr.strip()[-500:]}")
            counts.append(json.loads(out.stderr.strip().splitlines()[-1]))
        return counts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", action="append", default=[], help="only the commands whose name holds this text")
    args = ap.parse_args()
    rows = {}
    for name, argv in COMPILED.items():
        if "tue-4gb10" in name and not TUE.exists():
            continue
        if args.only and not any(o in name for o in args.only):
            continue
        first, second = twice(argv)
        rows[name] = {"first": first, "second": second, "all_read_back": second["hits"] == second["requests"]}
        print(f"{name:48s} second process: {second['hits']} of {second['requests']} programs read back", flush=True)
    out = {"measured": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "commands": rows, "versions": versions()}
    RESULTS.mkdir(parents=True, exist_ok=True)
    write_text_atomic(RESULTS / "cache_hits.json", json.dumps(out, indent=1))
    missed = [n for n, r in rows.items() if not r["all_read_back"]]
    print("every program read back" if not missed else f"compiled again in the second process: {', '.join(missed)}")


if __name__ == "__main__":
    main()
