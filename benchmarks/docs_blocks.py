"""What the documentation tests cost: every page's blocks run as tests/project/test_readme.py
runs them (in page order, in one process, a folder per page), each Python block and each
shell command timed, wall and CPU (user + system) seconds.

The Python blocks are the baseline, measured in the same run: the shell commands are what
running the pages' commands adds to the suite. The compilation cache is the suite's
(build/test-jax-cache, as a test run leaves it) unless ``--cold``, which gives the run an
empty folder of its own: a fresh clone's first run, the worst case (the suite runs the
pages late, after the tests that compile the same kernels).

    .venv/bin/python benchmarks/docs_blocks.py            # the suite's cache (a few minutes)
    .venv/bin/python benchmarks/docs_blocks.py --cold     # an empty cache

Writes benchmarks/results/docs_blocks.json (docs_blocks_cold.json with --cold).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cold", action="store_true", help="an empty compilation cache")
    args = parser.parse_args()
    if args.cold:
        os.environ["ROTOR_COMPILATION_CACHE"] = tempfile.mkdtemp(prefix="docs-blocks-cache-")
        os.environ["ROTOR_TABLE_CACHE"] = tempfile.mkdtemp(prefix="docs-blocks-tables-")
    sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "project")]
    import conftest  # noqa: F401  (the suite's environment: XLA's level, the caches, no kept outputs)
    import matplotlib.pyplot as plt
    import test_readme as pages

    rows = []
    for path in pages.PAGES:
        name = path.relative_to(ROOT).as_posix()
        folder = Path(tempfile.mkdtemp(prefix=path.stem))
        os.chdir(folder)
        ns: dict = {"__name__": "__docs__", pages.OUTPUTS: {}}
        for block in pages.blocks(path.read_text(encoding="utf-8"), name):
            steps = (
                [(line, command) for line, command in pages.shell_commands(block.source, block.line)]
                if block.kind == "sh"
                else [(block.line, None)]
            )
            for line, command in steps:
                wall, cpu = time.perf_counter(), time.process_time()
                if command is None:
                    pages.run_block(block, path, ns)
                else:
                    rc, _, err = pages.run_once(command)
                    assert rc == 0, f"{name}:{line}: {command}: {err.strip()[-300:]}"
                rows.append(
                    {
                        "page": name,
                        "line": line,
                        "kind": block.kind,
                        "command": command,
                        "wall_s": time.perf_counter() - wall,
                        "cpu_s": time.process_time() - cpu,
                    }
                )
                plt.close("all")
        os.chdir(ROOT)

    def total(kind: str, key: str) -> float:
        return round(sum(r[key] for r in rows if r["kind"] == kind), 2)

    import jax

    out = {
        "cache": "empty" if args.cold else "the suite's (build/test-jax-cache)",
        "python_blocks": {
            "count": sum(r["kind"] == "python" for r in rows),
            "wall_s": total("python", "wall_s"),
            "cpu_s": total("python", "cpu_s"),
        },
        "shell_commands": {
            "count": sum(r["kind"] == "sh" for r in rows),
            "wall_s": total("sh", "wall_s"),
            "cpu_s": total("sh", "cpu_s"),
        },
        "rows": sorted(rows, key=lambda r: -r["wall_s"]),
        "versions": {"python": platform.python_version(), "jax": jax.__version__},
        "machine": {"cpus": os.cpu_count(), "load_1min": os.getloadavg()[0]},
    }
    target = ROOT / "benchmarks" / "results" / ("docs_blocks_cold.json" if args.cold else "docs_blocks.json")
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    print(f"python blocks: {out['python_blocks']}\nshell commands: {out['shell_commands']}\nwrote {target}")
    for r in out["rows"][:10]:
        print(f"{r['wall_s']:7.1f} s  {r['page']}:{r['line']}  {r['command'] or 'python block'}")


if __name__ == "__main__":
    main()
