"""The whole matrix of simulated trigger captures read with nothing but the signal: every
catalogue pattern × either polarity × inverted × timing jitter × edges next to a gap
displaced by 0.3 of a pitch × a glitch (:func:`rotor.logs.synthetic.pattern_capture`), each
read by :func:`rotor.logs.recording.read_wheel` with ``wheel="auto"``: read as itself, refused,
or read as another wheel (which must never happen). The suite reads a quarter of it
(``tests/logs/test_reading_matrix.py``). And analog bench signals of three missing-tooth wheels
with the defects a real sensor shows near the gap (:func:`rotor.logs.synthetic.bench_capture`:
a faint tooth after the gap in every revolution or in half of them, the teeth after it late or
early by 0.3 of a pitch, the tooth before it merged with the gap on one polarity, a level in the
gap, negated), read with the wheel found and with it named (the suite: a third of the 60-2 ones,
``tests/logs/test_bench_signatures.py``).

Writes ``benchmarks/published/reading_matrix.json``. Run: ``.venv/bin/python benchmarks/reading_matrix.py``.
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
BENCH = list(
    itertools.product(
        ((1.0, 1.0), (0.35, 1.0), (0.35, 0.5)),
        ((0.0, 0.0), (0.3, 0.1), (-0.3, 0.0)),
        (0.45, 1.5),
        (0.0, 0.1),
        (False, True),
    )
)  # (faint, share of revolutions), late, wide, gap level, negated


def bench_rows() -> list[dict]:
    from rotor.errors import LogError
    from rotor.logs.recording import read_wheel
    from rotor.logs.synthetic import bench_capture

    rows = []
    for wheel in ("60-2", "36-1", "36-2"):
        for i, ((faint, share), late, wide, gap, neg) in enumerate(BENCH):
            if faint == 1.0 and share != 1.0:
                continue
            log = bench_capture(
                wheel,
                rpm=2500,
                faint=faint,
                faint_share=share,
                late_pitch=late,
                wide_pitch=wide,
                gap_level=gap,
                invert=neg,
                seed=i,
            )
            row = {
                "wheel": wheel,
                "faint": faint,
                "faint_share": share,
                "late_pitch": list(late),
                "wide_pitch": wide,
                "gap_level": gap,
                "negated": neg,
            }
            for how, given in (("found", None), ("named", wheel)):
                try:
                    got = read_wheel(log, given).wheel.spec
                    row[how] = "itself" if got == wheel else "another"
                    row[f"{how}_as"] = got
                except LogError as e:
                    row[how], row[f"{how}_as"] = "refused", str(e)[:200]
            rows.append(row)
    return rows


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
    t1 = time.perf_counter()
    bench = bench_rows()
    summary["bench"] = {
        "cells": len(bench),
        **{
            f"{how}_{outcome}": sum(r[how] == outcome for r in bench)
            for how in ("found", "named")
            for outcome in ("itself", "refused", "another")
        },
        "wall_s": round(time.perf_counter() - t1, 1),
    }
    out = HERE / "published" / "reading_matrix.json"
    out.write_text(
        json.dumps({"versions": versions(), "summary": summary, "rows": rows, "bench_rows": bench}, indent=1) + "\n"
    )
    print(json.dumps(summary, indent=1))
    for r in rows:
        if r["outcome"] == "another":
            print("READ AS ANOTHER:", r)
    for r in bench:
        if "another" in (r["found"], r["named"]):
            print("BENCH READ AS ANOTHER:", r)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
