"""Every recording of ``../shared/data`` read two ways: as a user reads it with nothing but
the file (``rotor.analyze_log(FILE)``: read, or refused with the message), and with the
pattern and channel its README documents, by the edge-list decoder
(:func:`rotor.logs.patterns.decode_edges`): the speed per pattern turn against the speed
range the README gives (±2 %).

Writes ``benchmarks/published/real_recordings.json`` (``--out`` to change). Skips, with a
line saying so, where ``../shared/data`` is absent. Run: ``.venv/bin/python benchmarks/real_recordings.py``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from simulator_speed import versions  # noqa: E402

DATA = HERE.parent.parent / "shared" / "data"

# file, columns that name the documented channel, pattern, polarity read, README's speed range [rpm]
DOCUMENTED = [
    ("ecu-triggers/4b11-running.csv", "time,encoder_d,-", "36-2-1", "rising", 1399, 1486),
    ("ecu-triggers/4b11-running-doubled-edge.csv", "time,encoder_d,-", "36-2-1", "rising", 1399, 1486),
    ("ecu-triggers/6g75-withsparkplugs-cranking.csv", "time,encoder_d,-", "36-2-1-1", "falling", 135, 167),
    ("ecu-triggers/6g75-without-spark-crank.csv", "time,encoder_d,-", "36-2-1-1", "falling", 128, 165),
    ("ecu-triggers/3000gt.csv", "time,encoder_d", "mitsubishi-6g72-cam", "both", 164, 194),
    ("ecu-triggers/4g63-cranking.csv", "time,-,encoder_d", "mitsubishi-4g63-cam", "both", 133, 218),
    ("ecu-triggers/cranking_na_3.csv", "time,-,encoder_d,-,-", "mazda-na-cas-1", "both", 225, 1100),
    ("ecu-triggers/nb2_rev-d-1.csv", "time,encoder_d,-,-,-", "mazda-nb-crank", "rising", 240, 250),
    ("ecu-triggers/nb2_rev-d-2.csv", "time,-,encoder_d,-,-", "mazda-nb-cam", "rising", 235, 235),
    ("ecu-triggers/cas_nissan_24_plus_1.csv", "time,encoder_d,-", "12-tooth", "rising", 806, 1063),
    ("ecu-triggers/chrysler-phaser.csv", "time,encoder_d", "chrysler-phaser-cam", "rising", 787, 821),
    ("ecu-triggers/neonsrt4.csv", "time,-,encoder_d", "36-2-2", "falling", 147, 225),
    ("ecu-triggers/noisy-trigger-2.csv", "time,encoder_d", "36-2", "rising", 215, 420),
    ("ecu-triggers/arctic-cat.csv", "time,encoder_d", "arctic-cat", "falling", 528, 2129),
    (
        "ecu-triggers/BQS-1.csv",
        "time,encoder_d",
        "bosch-quick-start-cam",
        "rising",
        235,
        444,
    ),  # teeth low: their ends rise
    ("ecu-triggers/hr12-vvt-in-16s.csv", "time,encoder_d", "nissan-hr-cam-in", "falling", 196, 202),
]


# the other pattern a README documents for a file of two sensors (crank and cam)
ALSO_DOCUMENTED = {
    "ecu-triggers/nb2_rev-d-1.csv": ("mazda-nb-cam",),
    "ecu-triggers/nb2_rev-d-2.csv": ("mazda-nb-crank",),
}


def as_a_user(path: Path) -> dict:
    import rotor

    t0 = time.perf_counter()
    try:
        a = rotor.analyze_log(path)
        wheel = a.pattern.pattern.name if a.pattern is not None else a.track.wheel.spec
        return {
            "read": True,
            "wheel": wheel,
            "channel": a.pattern.channel if a.pattern is not None else None,
            "cycles": a.cycles,
            "median_cycle_rpm": float(np.median(a.mean_rpm)),
            "delta_median": float(np.median(a.delta)),
            "s": time.perf_counter() - t0,
        }
    except Exception as e:  # the refusal's message is the result
        return {"read": False, "refused": f"{type(e).__name__}: {e}"[:300], "s": time.perf_counter() - t0}


def documented(path: Path, columns: str, pattern: str | None, polarity: str, lo, hi) -> dict:
    from rotor.logs.catalogue import find_pattern
    from rotor.logs.patterns import channel_edges, decode_edges
    from rotor.logs.reader import read_log

    if pattern is None:
        return {"decoded": False, "why": "no published geometry in the catalogue for this pattern"}
    p = find_pattern(pattern)
    log = read_log(path, columns)
    try:
        times, kinds = channel_edges(log["time"], log["encoder_d"], polarity)
        fit = decode_edges(
            times, p, "both" if polarity == "both" else p.read, kinds=kinds if polarity == "both" else None
        )
    except Exception as e:
        return {"pattern": pattern, "polarity": polarity, "decoded": False, "why": str(e)[:300]}
    _, rpm = fit.rpm_per_turn()
    out = {
        "pattern": pattern,
        "polarity": polarity,
        "decoded": True,
        "kept_fraction": round(fit.kept, 4),
        "turns": round(fit.turns, 2),
        "rms_log_ratio": round(fit.rms, 4),
        "rpm_median": float(np.median(rpm)) if rpm.size else None,
        "rpm_min": float(rpm.min()) if rpm.size else None,
        "rpm_max": float(rpm.max()) if rpm.size else None,
        "readme_rpm": [lo, hi],
    }
    if lo is not None and rpm.size:
        out["median_within_readme_range_2pct"] = bool(0.98 * lo <= np.median(rpm) <= 1.02 * hi)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(HERE / "published" / "real_recordings.json"))
    args = ap.parse_args()
    if not DATA.is_dir():
        print(f"real_recordings: no data at {DATA}; nothing measured")
        return 0
    rows = []
    for rel, columns, pattern, polarity, lo, hi in DOCUMENTED:
        path = DATA / rel
        row = {
            "file": rel,
            "as_a_user": as_a_user(path),
            "documented": documented(path, columns, pattern, polarity, lo, hi),
        }
        rows.append(row)
        u, d = row["as_a_user"], row["documented"]
        print(
            f"{rel:48s} user: {u.get('wheel', 'refused'):22s} documented: "
            + (
                f"{d['pattern']} {d['rpm_median']:.0f} rpm (README {lo}–{hi})"
                if d.get("decoded")
                else f"not decoded ({d.get('why', '')[:60]})"
            )
        )
    for name in ("No_load", "half_load", "full_load"):
        path = DATA / "tue-4gb10" / f"{name}.txt"
        rows.append({"file": f"tue-4gb10/{name}.txt", "as_a_user": as_a_user(path)})
        print(f"tue-4gb10/{name}.txt user: {'read' if rows[-1]['as_a_user']['read'] else 'refused'}")
    for r in rows:
        u, d = r["as_a_user"], r.get("documented", {})
        if u["read"] and d.get("pattern"):
            u["as_documented"] = u["wheel"] in (d["pattern"], *ALSO_DOCUMENTED.get(r["file"], ()))
            lo, hi = d.get("readme_rpm", [None, None])
            if lo is not None:
                u["within_readme_range_2pct"] = bool(0.98 * lo <= u["median_cycle_rpm"] <= 1.02 * hi)
    summary = {
        "files": len(rows),
        "read_as_a_user": sum(r["as_a_user"]["read"] for r in rows),
        "read_as_a_user_as_documented": sum(bool(r["as_a_user"].get("as_documented")) for r in rows),
        "read_as_a_user_within_range": sum(bool(r["as_a_user"].get("within_readme_range_2pct")) for r in rows),
        "decoded_as_documented": sum(bool(r.get("documented", {}).get("decoded")) for r in rows),
        "within_readme_range": sum(bool(r.get("documented", {}).get("median_within_readme_range_2pct")) for r in rows),
    }
    print(summary)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps({"versions": versions(), "summary": summary, "rows": rows}, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
