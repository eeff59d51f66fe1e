"""What the streaming misfire monitor says about real captures.

    nice -n 19 .venv/bin/python benchmarks/misfire_real.py      # about a minute

Four parts, each skipped where its folder under ``../shared/data`` is absent (a clone of
the project has no ``shared/``); the data are read from there, never copied:

1. **Mitsubishi 4B11 at idle** (``ecu-triggers/4b11-running.csv``: a logic-analyser capture
   of the crank's 36-2-1 wheel, about 1440 rpm, 80 cycles). The capture states no TDC: it
   is taken where the mean speed over the firing interval is lowest (the end of
   compression), and the verdicts are also given for every TDC from 0 to 165° after the
   gap in 15° steps. Each call is judged against the capture's own speed: the step in the
   cycle-mean speed across the called cycle against the usual cycle-to-cycle change, and
   the speed over the cycle (30° bins) against the median cycle.
2. **Mitsubishi 6G75 cranked with and without compression** (``ecu-triggers/6g75-*.csv``,
   36-2-1-1 wheel, 130–170 rpm): the per-firing swing (the speed's rise from TDC to half
   the firing interval after), index and energy change e, and the ratio of their typical
   magnitude (median |·|) with compression to without; TDC where the
   speed over the 120° firing interval is lowest with compression (the compression's end).
   Both edges are tried; what the monitor refuses is given with its own words.
3. **tue-4gb10** (the single-cylinder bench, analog 60-2 wheel, no, half and full load):
   TDC and the firing revolution from the recording's own pressure channel
   (:func:`rotor.analyze_log`), tooth edges by :func:`rotor.find_edges`; the calls.
4. **Yanmar L100V motored cycles inserted into its fired sequence**: a simulated
   single-cylinder recording (``benchmarks/misfire_detection.py``'s simulation: 60-2 wheel
   with ±0.1° tooth errors, 20 ns timer noise, 1800 rpm) whose per-cycle work follows the
   net IMEP of the 60 real fired cycles in their recorded order (twice over, 120 cycles),
   with the net IMEP of real motored cycles (negative: pumping and friction of the
   real engine) in place of the fired one at known cycles; the same sequence without them
   for the false calls.

The monitor is fed one wheel revolution of edges at a time, as a logger would hand them
over; everything is through its public API (:class:`rotor.diagnostics.monitor.MisfireMonitor`),
and the 4B11 once more through ``rotor monitor`` to show the command gives the same calls.
Writes ``benchmarks/results/misfire_real.json`` and ``benchmarks/results/misfire_real.png``.
"""

from __future__ import annotations

import json
import math
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import rotor
from rotor.diagnostics.monitor import DEFAULT_THRESHOLD, MisfireMonitor
from rotor.logs.digital import digital_edges
from rotor.logs.pattern import locate_teeth

sys.path.insert(0, str(Path(__file__).resolve().parent))
from misfire_detection import (  # noqa: E402  (the simulation and the Yanmar reader, reused)
    FULL_IMEP_PA,
    TDC_DEG,
    VD_M3,
    YANMAR_VD_M3,
    simulate,
    yanmar_net_imep,
    yanmar_variation,
)

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
RESULTS = ROOT / "benchmarks" / "results"
TRIGGERS = DATA / "ecu-triggers"
TUE = DATA / "tue-4gb10"
B11_ORDER = [1, 3, 4, 2]
G75_ORDER = [1, 2, 3, 4, 5, 6]  # the 6G7x V6: cylinders fire in their numbered order
YANMAR_CYCLES = 120
YANMAR_INSERTED = (15, 30, 31, 47, 62, 63, 80, 96, 110)  # cycles given a motored cycle's IMEP
YANMAR_DRAW = 31  # the simulation's random draws (tooth errors apart: those are the wheel's)


# ---------------------------------------------------------------------- helpers
def capture_edges(path, edge):
    """Crank edge times [s] of a logic-analyser export (channel 0), glitches removed."""
    log = rotor.read_log(path)
    e = digital_edges(log["time"], log["encoder_d"], edge=edge)
    return e.times, int(e.glitches)


def run_monitor(times, wheel, per_rev, **kw):
    """Feed the edges one revolution at a time; (verdicts, result, notes as text)."""
    m = MisfireMonitor(wheel, **kw)
    out, notes = [], []
    for i in range(0, times.size, per_rev):
        out += m.feed(times[i : i + per_rev])
        notes += m.pop_notes()
    out += m.close()
    notes += m.pop_notes()
    return out, m.result(), [f"{n.kind.value}: {n.text}" for n in notes]


def wheel_angles(times, wheel):
    """The angle [rad] of each edge from tooth 0 (the first tooth after the wheel's
    reference gap, as the monitor counts), through the monitor's own reader."""
    tr = locate_teeth(times, wheel, repair=True)
    w = tr.wheel
    ang = 2 * np.pi * np.asarray(w.positions) / w.teeth
    return tr.t, 2 * np.pi * tr.rev + ang[tr.tooth]


def speed_on_grid(t, phi, step_deg):
    """Mean speed [rpm] over each ``step_deg`` of crank angle, and the grid's start angles."""
    grid = np.arange(phi[0], phi[-1], np.deg2rad(step_deg))
    tg = np.interp(grid, phi, t)
    return np.deg2rad(step_deg) / np.diff(tg) * 30 / np.pi, grid[:-1], tg


def tdc_from_lowest_speed(times, wheel, interval_deg):
    """Cylinder 1's TDC after the gap [deg], modulo the firing interval: where the speed,
    relative to its running mean over a revolution and averaged over the capture, is lowest
    over the firing interval (5° bins, smoothed over 30°). Also the profile."""
    t, phi = wheel_angles(times, wheel)
    rpm, start, _ = speed_on_grid(t, phi, 5.0)
    rel = rpm / np.convolve(rpm, np.ones(72) / 72, mode="same")
    keep = slice(36, rel.size - 36)  # a whole revolution on both sides of the running mean
    fold = np.mod(np.rad2deg(start[keep]) + 2.5, interval_deg)
    bins = np.arange(0.0, interval_deg, 5.0)
    prof = np.array([rel[keep][(fold >= b) & (fold < b + 5)].mean() for b in bins])
    smooth = np.array([np.mean(np.take(prof, range(i - 3, i + 4), mode="wrap")) for i in range(prof.size)])
    return float(bins[int(np.argmin(smooth))]), bins, prof


def verdict_rows(verdicts):
    return [
        {
            "cycle": v.cycle,
            "cylinder": v.cylinder,
            "misfire": v.misfire,
            "index": round(float(v.index), 3),
            "energy": float(v.energy),
            "decided_at_s": round(float(v.decided_at_s), 6),
        }
        for v in verdicts
    ]


def summary_of(result):
    d = result.to_json_dict()
    return {k: d[k] for k in ("firings_judged", "misfire_count", "misfires", "not_judged", "cylinders", "note_counts")}


# ---------------------------------------------------------------------- 1. 4B11
def part_4b11():
    path = TRIGGERS / "4b11-running.csv"
    wheel, per_rev = "36-2-1", 33
    times, glitches = capture_edges(path, "falling")
    tdc, bins, prof = tdc_from_lowest_speed(times, wheel, 180.0)
    kw = {"cylinders": 4, "firing_order": B11_ORDER}
    verdicts, result, notes = run_monitor(times, wheel, per_rev, tdc_deg=tdc, **kw)
    scan = []
    for x in range(0, 180, 15):
        v, r, _ = run_monitor(times, wheel, per_rev, tdc_deg=float(x), **kw)
        scan.append(
            {
                "tdc_after_gap_deg": x,
                "firings_judged": int(r.judged.sum()),
                "calls": [list(p) for p in r.misfire_list],
                "lowest_index": round(float(min(u.index for u in v)), 2),
                "index_iqr": round(float(np.subtract(*np.percentile([u.index for u in v], [75, 25]))), 2),
            }
        )
    rising = capture_edges(path, "rising")[0]
    vr, rr, _ = run_monitor(rising, wheel, per_rev, tdc_deg=tdc, **kw)
    # the capture's own speed: cycle means (two revolutions from tooth 0) and 30° bins
    t, phi = wheel_angles(times, wheel)
    rpm30, start30, tg30 = speed_on_grid(t, phi, 30.0)
    per = 24
    ncyc = rpm30.size // per
    cyc = rpm30[: ncyc * per].reshape(ncyc, per)
    cyc_t0 = tg30[: ncyc * per : per]
    cycle_mean = cyc.mean(axis=1)
    step_sd = float(np.std(np.diff(cycle_mean), ddof=1))
    dev = cyc - np.median(cyc, axis=0)
    judged_calls = []
    for k, c in result.misfire_list:
        v = next(u for u in verdicts if u.cycle == k and u.cylinder == c)
        i = int(np.searchsorted(cyc_t0, v.decided_at_s)) - 1  # the capture cycle the firing lies in
        i = min(max(i, 4), ncyc - 5)
        before, after = cycle_mean[i - 4 : i].mean(), cycle_mean[i + 1 : i + 5].mean()
        judged_calls.append(
            {
                "cycle": k,
                "cylinder": c,
                "index": round(float(v.index), 2),
                "decided_at_s": round(float(v.decided_at_s), 4),
                "cycle_mean_rpm_4_before": round(float(before), 1),
                "cycle_mean_rpm_4_after": round(float(after), 1),
                "step_rpm": round(float(after - before), 1),
                "step_over_usual_cycle_to_cycle_change": round(float((after - before) / step_sd), 1),
                "later_cycle_mean_rpm_to_the_end": round(float(cycle_mean[i + 1 :].mean()), 1),
                "speed_minus_median_cycle_rpm_30deg_bins": {
                    f"{cyc_t0[j]:.3f} s": [round(float(x), 1) for x in dev[j]] for j in range(i - 2, i + 3)
                },
            }
        )
    # the loss in words: where in the called cycle the speed fell
    cli = cli_check(times, tdc)
    return {
        "capture": "logic-analyser capture of a Mitsubishi 4B11's crank wheel (36-2-1) at idle, falling edges",
        "edges": int(times.size),
        "glitches_removed": glitches,
        "mean_rpm": round(float(np.mean(cycle_mean)), 1),
        "cycles_in_capture": int(ncyc),
        "tdc_after_gap_deg": tdc,
        "tdc_rule": "the lowest mean speed over the 180° firing interval (5° bins, smoothed over 30°); the capture "
        "states no TDC, and which revolution holds cylinder 1's firing is not known (parity 0 taken): the "
        "cylinder numbers may be 1<->4 and 3<->2 swapped",
        "speed_profile_over_firing_interval": {
            "deg_after_gap": bins.tolist(),
            "speed_over_running_mean": [round(float(x), 5) for x in prof],
        },
        "summary": summary_of(result),
        "notes": notes,
        "cycle_mean_rpm": [round(float(x), 1) for x in cycle_mean],
        "usual_cycle_to_cycle_change_rpm": round(step_sd, 2),
        "calls": judged_calls,
        "tdc_scan": scan,
        "rising_edges": {"firings_judged": int(rr.judged.sum()), "calls": [list(p) for p in rr.misfire_list]},
        "cli": cli,
        "verdicts": verdict_rows(verdicts),
    }


def cli_check(times, tdc):
    """The same edges through ``rotor monitor`` (a file with the TDC in its header)."""
    exe = Path(sys.executable).with_name("rotor")
    if not exe.is_file():
        return {"skipped": "no rotor command next to this Python"}
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "edges.csv"
        log.write_text(f"# tdc_after_gap_deg: {tdc}\ntooth_time_s\n" + "\n".join(f"{x:.9f}" for x in times) + "\n")
        argv = ["monitor", "EDGES", "--cylinders", "4", "--firing-order", "1,3,4,2", "--wheel", "36-2-1", "--json"]
        run = subprocess.run(
            [str(exe), *[str(log) if a == "EDGES" else a for a in argv]], capture_output=True, text=True, timeout=300
        )
    if run.returncode != 0:
        return {"command": "rotor " + " ".join(argv), "error": run.stderr.strip()[-500:]}
    last = json.loads(run.stdout.strip().splitlines()[-1])["summary"]
    return {
        "command": "rotor " + " ".join(argv),
        "firings_judged": last["firings_judged"],
        "misfires": last["misfires"],
    }


# ---------------------------------------------------------------------- 2. 6G75
def part_6g75():
    wheel, per_rev = "36-2-1-1", 32
    files = {
        "with_compression": TRIGGERS / "6g75-withsparkplugs-cranking.csv",
        "without_compression": TRIGGERS / "6g75-without-spark-crank.csv",
    }
    edges = {k: capture_edges(p, "falling")[0] for k, p in files.items()}
    tdc, bins, prof = tdc_from_lowest_speed(edges["with_compression"], wheel, 120.0)
    out = {
        "capture": "logic-analyser captures of a Mitsubishi 6G75 V6's crank wheel (36-2-1-1), cranked by the "
        "starter with the spark plugs in (compression) and out",
        "tdc_after_gap_deg": tdc,
        "tdc_rule": "the lowest mean speed over the 120° firing interval with compression (5° bins, smoothed over "
        "30°), used for both captures",
        "speed_profile_with_compression": {
            "deg_after_gap": bins.tolist(),
            "speed_over_running_mean": [round(float(x), 4) for x in prof],
        },
    }
    typical = {}
    for k in files:
        for edge in ("falling", "rising"):
            t = edges[k] if edge == "falling" else capture_edges(files[k], "rising")[0]
            v, r, notes = run_monitor(t, wheel, per_rev, tdc_deg=tdc, cylinders=6, firing_order=G75_ORDER)
            idx = np.array([u.index for u in v])
            e = np.array([u.energy for u in v])
            sw = np.array([u.swing for u in v])
            row = {
                "edges": int(t.size),
                "firings_judged": int(r.judged.sum()),
                "calls": [list(p) for p in r.misfire_list],
                "notes": notes,
            }
            if v:
                # the starter's cranking apart from the coast-down after it lets go: firings
                # whose cycle ends before the speed over 120° stays below 85 % of its median
                tw, ph = wheel_angles(t, wheel)
                rpm120, _, tg = speed_on_grid(tw, ph, 120.0)
                low = rpm120 < 0.85 * np.median(rpm120)
                stay = np.flatnonzero(~low)
                release = float(tg[stay[-1] + 1]) if stay.size and stay[-1] + 1 < tg.size else math.inf
                crank = np.array([u.cycle_end_s <= release for u in v])
                row.update(
                    {
                        "median_abs_index": float(np.median(np.abs(idx))),
                        "median_abs_energy": float(np.median(np.abs(e))),
                        "median_abs_swing": float(np.median(np.abs(sw))),
                        "median_abs_swing_cranking": float(np.median(np.abs(sw[crank]))),
                        "min_swing_cranking": float(np.min(sw[crank])),
                        "max_abs_swing_cranking": float(np.max(np.abs(sw[crank]))),
                        "coast_down_from_s": release if math.isfinite(release) else None,
                        "firings_cranking": int(crank.sum()),
                        "median_abs_index_cranking": float(np.median(np.abs(idx[crank]))),
                        "rms_index_cranking": float(np.sqrt(np.mean(idx[crank] ** 2))),
                        "median_abs_energy_cranking": float(np.median(np.abs(e[crank]))),
                        "calls_in_coast_down": [[u.cycle, u.cylinder] for u, c in zip(v, crank) if u.misfire and not c],
                        "index": [round(float(x), 3) for x in idx],
                        "energy": [round(float(x), 5) for x in e],
                        "swing": [round(float(x), 5) for x in sw],
                        "cycle_cylinder": [[u.cycle, u.cylinder] for u in v],
                    }
                )
                if edge == "falling":
                    typical[k] = row
            out[f"{k}_{edge}"] = row
    if len(typical) == 2:
        w, wo = typical["with_compression"], typical["without_compression"]
        out["ratio_median_abs_index"] = w["median_abs_index"] / wo["median_abs_index"]
        out["ratio_median_abs_energy"] = w["median_abs_energy"] / wo["median_abs_energy"]
        out["ratio_median_abs_energy_cranking"] = w["median_abs_energy_cranking"] / wo["median_abs_energy_cranking"]
        out["ratio_median_abs_swing"] = w["median_abs_swing"] / wo["median_abs_swing"]
        out["ratio_median_abs_swing_cranking"] = w["median_abs_swing_cranking"] / wo["median_abs_swing_cranking"]
        # every cranking firing with compression against the largest without
        out["ratio_min_swing_with_to_max_abs_without_cranking"] = w["min_swing_cranking"] / wo["max_abs_swing_cranking"]
        # without compression most of the cranking firings' indices are exactly 0: the first
        # firings of a short capture are judged against medians that hold their own value
        out["zero_indices_without_compression"] = int(
            sum(1 for x, u in zip(wo["index"], wo["cycle_cylinder"]) if x == 0.0)
        )
        out["ratio_rms_index_cranking"] = w["rms_index_cranking"] / wo["rms_index_cranking"]
    return out


# ---------------------------------------------------------------------- 3. tue-4gb10
def part_tue():
    out = {}
    cols = "time,pressure_v,encoder_v"
    for name in ("No_load", "half_load", "full_load"):
        path = TUE / f"{name}.txt"
        a = rotor.analyze_log(path, "60-2", columns=cols, compression_ratio=8.5, rod_ratio=27.5 / 84.2)
        tdc, parity = float(np.rad2deg(a.tdc_rad)), int(a.firing_parity)
        log = rotor.read_log(path, columns=cols)
        times = rotor.find_edges(log["time"], log["encoder_v"]).times
        v, r, notes = run_monitor(times, "60-2", 58, tdc_deg=tdc, cylinders=1, firing_parity=parity)
        v_other = run_monitor(times, "60-2", 58, tdc_deg=tdc, cylinders=1, firing_parity=1 - parity)[0]
        out[name] = {
            "tdc_after_gap_deg": round(tdc, 2),
            "firing_parity": parity,
            "mean_rpm": round(float(a.mean_rpm.mean()), 1),
            "edges": int(times.size),
            "firings_judged": int(r.judged.sum()),
            "calls": [list(p) for p in r.misfire_list],
            "index": [round(float(u.index), 2) for u in v],
            "lowest_index": round(float(min(u.index for u in v)), 2) if v else None,
            "median_energy": float(np.median([u.energy for u in v])) if v else None,
            "median_energy_other_revolution": float(np.median([u.energy for u in v_other])) if v_other else None,
            "notes": notes,
        }
    return out


# ---------------------------------------------------------------------- 4. Yanmar
def part_yanmar():
    fired = yanmar_net_imep("fired-18Nm.txt")
    motored = yanmar_net_imep("motored.txt")
    variation = yanmar_variation()
    inserted = {k: i for i, k in enumerate(YANMAR_INSERTED)}  # cycle -> motored cycle used

    def work_of_with(insert):
        def work_of(fk, fj):
            imep = fired[np.mod(np.asarray(fk) - 1, fired.size)].copy()
            if insert:
                for k, i in inserted.items():
                    imep[np.asarray(fk) == k] = motored[i]
            return imep * YANMAR_VD_M3

        return work_of

    load = float(fired.mean() * YANMAR_VD_M3 / (FULL_IMEP_PA * VD_M3))
    out = {
        "recording": "simulated single cylinder (benchmarks/misfire_detection.py's simulation: 0.4 kg·m², 60-2 wheel "
        "with ±0.1° tooth errors, 20 ns timer noise, 1800 rpm, load ∝ ω²), per-cycle work = net IMEP × 0.435 l "
        "of the Yanmar L100V's 60 fired cycles in their recorded order, twice over",
        "fired_imep_bar_mean": float(fired.mean() / 1e5),
        "fired_imep_cov": float(fired.std(ddof=1) / fired.mean()),
        "motored_imep_bar": [round(float(x / 1e5), 3) for x in motored[: len(inserted)]],
        "inserted_cycles": list(YANMAR_INSERTED),
        "cycles": YANMAR_CYCLES,
    }
    for label, insert in (("with_motored_cycles", True), ("fired_only", False)):
        t = simulate(
            1, 1800.0, load, YANMAR_CYCLES, "60-2", variation, False, YANMAR_DRAW, work_of=work_of_with(insert)
        )[0]
        v, r, notes = run_monitor(t, "60-2", 58, tdc_deg=TDC_DEG, cylinders=1)
        calls = sorted(k for k, _ in r.misfire_list)
        idx = {u.cycle: u.index for u in v}
        want = set(YANMAR_INSERTED) if insert else set()
        normal = [x for k, x in idx.items() if k not in want]
        out[label] = {
            "firings_judged": int(r.judged.sum()),
            "first_cycle_judged": min(idx) if idx else None,
            "calls": calls,
            "found": sorted(want & set(calls)),
            "missed": sorted(want - set(calls)),
            "false_calls": sorted(set(calls) - want),
            "index_of_inserted": {str(k): round(float(idx[k]), 1) for k in sorted(want) if k in idx},
            "lowest_index_of_fired_cycles": round(float(min(normal)), 2),
            "index_iqr_of_fired_cycles": round(float(np.subtract(*np.percentile(normal, [75, 25]))), 2),
            "notes": notes,
            "cycle_index": [[u.cycle, round(float(u.index), 2)] for u in v],
        }
    return out


# ---------------------------------------------------------------------- figure
def figure(res, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(11, 7.5))
    b = res.get("4b11")
    if isinstance(b, dict):
        a = ax[0, 0]
        v = b["verdicts"]
        x = [u["decided_at_s"] for u in v]
        a.plot(x, [u["index"] for u in v], ".", ms=3, color="tab:blue", label="index per firing")
        m = [u for u in v if u["misfire"]]
        a.plot([u["decided_at_s"] for u in m], [u["index"] for u in m], "rv", label="misfire call")
        a.axhline(-DEFAULT_THRESHOLD, color="tab:red", lw=0.8, ls="--")
        a2 = a.twinx()
        cm = b["cycle_mean_rpm"]
        t0, t1 = v[0]["decided_at_s"], v[-1]["decided_at_s"]
        a2.plot(np.linspace(t0, t1, len(cm)), cm, color="0.4", lw=1)
        a2.set_ylabel("cycle mean speed [rpm]", fontsize=8)
        a.set_title(f"4B11 at idle, TDC {b['tdc_after_gap_deg']:.0f}° after the gap", fontsize=9)
        a.set_xlabel("time [s]")
        a.set_ylabel("index")
        a.legend(fontsize=7, loc="lower left")
    g = res.get("6g75")
    if isinstance(g, dict):
        a = ax[0, 1]
        for k, col in (("with_compression", "tab:red"), ("without_compression", "tab:blue")):
            r = g.get(f"{k}_falling", {})
            if "swing" in r:
                a.plot(np.arange(1, len(r["swing"]) + 1), r["swing"], "o-", ms=3, color=col, label=k.replace("_", " "))
        a.set_yscale("symlog", linthresh=1e-2)
        a.set_title("6G75 cranking: each firing's swing, TDC to 60° after", fontsize=9)
        a.set_xlabel("firing")
        a.set_ylabel("swing = (ω²(TDC+60°) − ω²(TDC))/ω²")
        a.legend(fontsize=7)
    tu = res.get("tue-4gb10")
    if isinstance(tu, dict):
        a = ax[1, 0]
        for name, r in tu.items():
            a.plot(np.arange(1, len(r["index"]) + 1), r["index"], "o-", ms=3, label=name)
        a.axhline(-DEFAULT_THRESHOLD, color="tab:red", lw=0.8, ls="--")
        a.set_title("tue-4gb10 bench (one cylinder, fired): index per cycle", fontsize=9)
        a.set_xlabel("cycle judged")
        a.set_ylabel("index")
        a.legend(fontsize=7)
    y = res.get("yanmar")
    if isinstance(y, dict):
        a = ax[1, 1]
        ci = np.array(y["with_motored_cycles"]["cycle_index"])
        a.plot(ci[:, 0], ci[:, 1], ".-", ms=3, lw=0.6, color="tab:blue", label="index per cycle")
        ins = [k for k in y["inserted_cycles"] if k in set(ci[:, 0].astype(int))]
        a.plot(ins, [ci[ci[:, 0] == k, 1][0] for k in ins], "kx", label="motored cycle inserted")
        calls = y["with_motored_cycles"]["calls"]
        a.plot(calls, [ci[ci[:, 0] == k, 1][0] for k in calls], "rv", mfc="none", ms=8, label="misfire call")
        a.axhline(-DEFAULT_THRESHOLD, color="tab:red", lw=0.8, ls="--")
        a.set_title("Yanmar L100V fired sequence with real motored cycles (simulated speed)", fontsize=9)
        a.set_xlabel("cycle")
        a.set_ylabel("index")
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------- main
def main():
    t0 = time.perf_counter()
    res = {}
    parts = (
        ("4b11", TRIGGERS / "4b11-running.csv", part_4b11),
        ("6g75", TRIGGERS / "6g75-without-spark-crank.csv", part_6g75),
        ("tue-4gb10", TUE / "full_load.txt", part_tue),
        ("yanmar", DATA / "yanmar-l100v" / "motored.txt", part_yanmar),
    )
    for key, need, fn in parts:
        if not need.is_file():
            res[key] = f"skipped: {need.relative_to(ROOT.parent)} absent"
            print(res[key], flush=True)
            continue
        s = time.perf_counter()
        res[key] = fn()
        print(f"{key}: {time.perf_counter() - s:.1f} s", flush=True)
        report(key, res[key])
    res.update(
        {
            "seconds": time.perf_counter() - t0,
            "threshold": DEFAULT_THRESHOLD,
            "rotor": rotor.__version__,
            "numpy": np.__version__,
            "python": platform.python_version(),
        }
    )
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / "misfire_real.json"
    path.write_text(json.dumps(res, indent=1, allow_nan=False) + "\n")
    figure(res, path.with_suffix(".png"))
    print(f"wrote {path.relative_to(ROOT)} and {path.with_suffix('.png').relative_to(ROOT)} ({res['seconds']:.0f} s)")


def report(key, r):
    if key == "4b11":
        s = r["summary"]
        print(
            f"  {s['firings_judged']} firings judged at TDC {r['tdc_after_gap_deg']:.0f}° after the gap, calls "
            f"{s['misfires']}; per cylinder median index "
            + ", ".join(f"{c['median_index']:+.2f}" for c in s["cylinders"])
        )
        for c in r["calls"]:
            print(
                f"  call cycle {c['cycle']} cylinder {c['cylinder']} (index {c['index']}): cycle-mean speed "
                f"{c['cycle_mean_rpm_4_before']} -> {c['cycle_mean_rpm_4_after']} rpm, "
                f"{c['step_over_usual_cycle_to_cycle_change']}x the usual cycle-to-cycle change"
            )
        print("  TDC scan: " + "; ".join(f"{x['tdc_after_gap_deg']}° {x['calls']}" for x in r["tdc_scan"]))
        print(f"  rising edges: calls {r['rising_edges']['calls']}; rotor monitor: {r['cli']}")
    elif key == "6g75":
        for k in ("with_compression", "without_compression"):
            for edge in ("falling", "rising"):
                x = r[f"{k}_{edge}"]
                print(
                    f"  {k} {edge}: {x['firings_judged']} judged, calls {x['calls']}, "
                    f"median |index| {x.get('median_abs_index', float('nan')):.3g}, "
                    f"median |e| {x.get('median_abs_energy', float('nan')):.3g}; first note: "
                    f"{x['notes'][0][:160] if x['notes'] else '-'}"
                )
        if "ratio_median_abs_energy" in r:
            print(
                f"  ratio with/without compression: median |e| {r['ratio_median_abs_energy']:.1f}x, "
                f"median |index| {r['ratio_median_abs_index']:.2f}x; while the starter turns it (coast-down left "
                f"out): median |e| {r['ratio_median_abs_energy_cranking']:.1f}x, rms index "
                f"{r['ratio_rms_index_cranking']:.2f}x"
            )
            print(
                f"  swing with/without compression: median |swing| {r['ratio_median_abs_swing']:.1f}x, while the "
                f"starter turns it {r['ratio_median_abs_swing_cranking']:.1f}x; the smallest swing with compression "
                f"{r['ratio_min_swing_with_to_max_abs_without_cranking']:.1f}x the largest |swing| without"
            )
            wo = r["without_compression_falling"]
            print(
                f"  without compression: coast-down from {wo['coast_down_from_s']} s, calls in it "
                f"{wo['calls_in_coast_down']} of {wo['calls']}"
            )
    elif key == "tue-4gb10":
        for name, x in r.items():
            print(
                f"  {name}: TDC {x['tdc_after_gap_deg']}°, parity {x['firing_parity']}, {x['firings_judged']} judged, "
                f"calls {x['calls']}, lowest index {x['lowest_index']}, median e {x['median_energy']:.4f} "
                f"(other revolution {x['median_energy_other_revolution']:.4f})"
            )
    elif key == "yanmar":
        for label in ("with_motored_cycles", "fired_only"):
            x = r[label]
            print(
                f"  {label}: {x['firings_judged']} judged from cycle {x['first_cycle_judged']}, found {x['found']}, "
                f"missed {x['missed']}, false calls {x['false_calls']}, lowest fired index "
                f"{x['lowest_index_of_fired_cycles']}"
            )
        print(f"  index of the inserted cycles: {r['with_motored_cycles']['index_of_inserted']}")


if __name__ == "__main__":
    main()
