"""The whole matrix of simulated trigger captures read with nothing but the signal: every
catalogue pattern × either polarity × inverted × timing jitter × edges next to a gap
displaced by 0.3 of a pitch × a glitch (:func:`rotor.logs.synthetic.pattern_capture`), each
read by :func:`rotor.logs.recording.read_wheel` with ``wheel="auto"``: read as itself, refused,
or read as another wheel (which must never happen). The suite reads a quarter of it
(``tests/logs/test_reading_matrix.py``).

Writes ``benchmarks/results/reading_matrix.json``. Run: ``.venv/bin/python benchmarks/reading_matrix.py``.
"""

from __future__ import annotations

import itertools
import json
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from simulator_speed import versions  # noqa: E402

DEFECTS = list(itertools.product((False, True), (0.0, 0.5), (0.0, 0.3), (False, True)))


def main() -> int:
    from rotor.errors import LogError
    from rotor.logs.catalogue import CATALOGUE
    from rotor.logs.recording import PatternReading, read_wheel
    from rotor.logs.synthetic import pattern_capture

    rows = []
    t0 = time.perf_counter()
    for name, p in CATALOGUE.items():
        for i, (inv, jit, dis, gl) in enumerate(DEFECTS):
            log = pattern_capture(p, invert=inv, jitter_deg=jit, displace=dis, glitch=gl, seed=i)
            try:
                r = read_wheel(log, None)
                got = r.pattern.name if isinstance(r, PatternReading) else r.wheel.spec
                outcome = "itself" if got == name else "another"
            except LogError as e:
                got, outcome = str(e)[:200], "refused"
            rows.append(
                {
                    "pattern": name,
                    "evenly_spaced": p.evenly_spaced,
                    "inverted": inv,
                    "jitter_deg": jit,
                    "displace_pitch": dis,
                    "glitch": gl,
                    "outcome": outcome,
                    "read_as_or_why": got,
                }
            )
    wall = time.perf_counter() - t0
    structured = [r for r in rows if not r["evenly_spaced"]]
    summary = {
        "cells": len(rows),
        "read_as_itself": sum(r["outcome"] == "itself" for r in rows),
        "refused": sum(r["outcome"] == "refused" for r in rows),
        "read_as_another_wheel": sum(r["outcome"] == "another" for r in rows),
        "patterns_timing_can_tell": len({r["pattern"] for r in structured}),
        "their_cells_read_as_themselves": sum(r["outcome"] == "itself" for r in structured),
        "their_cells": len(structured),
        "wall_s": round(wall, 1),
    }
    out = HERE / "results" / "reading_matrix.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps({"versions": versions(), "summary": summary, "rows": rows}, indent=1) + "\n")
    print(json.dumps(summary, indent=1))
    for r in rows:
        if r["outcome"] == "another":
            print("READ AS ANOTHER:", r)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
