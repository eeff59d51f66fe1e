"""What the progress bar costs: ``rotor simulate`` in a pseudo-terminal against ``--quiet``.

The bar is drawn only when stderr is a terminal, so the run with the bar is started under
``script -qc "…" /dev/null`` (a pseudo-terminal); the quiet run is the same command with
``--quiet``. Each is a whole fresh process (import, compile, run), timed ``--repeats``
times, alternating; the figure is the median. The bar hears from inside the one compiled
run (a host callback), so it should cost next to nothing: the target is within 10 %.

    .venv/bin/python benchmarks/progress_overhead.py                 # 4chn15, 3000 cycles, 5 repeats
    .venv/bin/python benchmarks/progress_overhead.py --method grid --cycles 300

Writes benchmarks/results/progress_overhead.json.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
TARGET = 0.10


def _time(command: str, terminal: bool) -> float:
    argv = ["script", "-qc", command, "/dev/null"] if terminal else ["bash", "-c", command]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    start = time.perf_counter()
    subprocess.run(argv, check=True, env=env, stdin=subprocess.DEVNULL, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engine", default="4chn15")
    ap.add_argument("--cycles", type=int, default=3000)
    ap.add_argument("--load", default="propeller:1100,1250")
    ap.add_argument("--method", default="auto")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    base = (
        f"{shlex.quote(sys.executable)} -m rotor.cli simulate {shlex.quote(args.engine)} --cycles {args.cycles} "
        f"--load {shlex.quote(args.load)} --method {shlex.quote(args.method)}"
    )
    bar, quiet = [], []
    for _ in range(args.repeats):
        bar.append(_time(base, terminal=True))
        quiet.append(_time(base + " --quiet", terminal=True))
    out = {
        "command": base,
        "repeats": args.repeats,
        "bar_s": bar,
        "quiet_s": quiet,
        "bar_median_s": statistics.median(bar),
        "quiet_median_s": statistics.median(quiet),
    }
    out["overhead"] = out["bar_median_s"] / out["quiet_median_s"] - 1
    out["within_target"] = out["overhead"] <= TARGET
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "progress_overhead.json").write_text(json.dumps(out, indent=2) + "\n")
    print(
        f"{base}\n  with the bar (pseudo-terminal) {out['bar_median_s']:.2f} s, --quiet {out['quiet_median_s']:.2f} s "
        f"(median of {args.repeats}): overhead {100 * out['overhead']:+.1f} % (target ≤ {100 * TARGET:.0f} %)"
    )


if __name__ == "__main__":
    main()
