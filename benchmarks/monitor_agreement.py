"""How often the streaming misfire monitor agrees with the whole-record diagnosis.

    nice -n 19 .venv/bin/python benchmarks/monitor_agreement.py --quick   # 2 records, under 2 minutes
    nice -n 19 .venv/bin/python benchmarks/monitor_agreement.py           # the matrix twice, about 5 minutes

A detector that sees only the past (:class:`rotor.diagnostics.monitor.MisfireMonitor`,
``rotor monitor``: each firing's energy change against running per-cylinder baselines,
decided about half a cycle after it) cannot always equal one that sees the whole record
(:func:`rotor.diagnose`, ``rotor diagnose``: the engine model fitted to the speed of every
cycle, a misfire where a firing's combustion scale is below half of the median around
it). The requirement measured here: on the simulated matrix their verdicts agree on at
least 99 % of the firings, and every difference is listed.

**The matrix.** Presets with several cylinders that ship with rotor (``4chn15``, ``mwm6``,
``v8``), three speeds each within its range, full fuelling and half, wheels 60-2 and
36-1, and per condition one fault-free record and records with single misfires at known
(cycle, cylinder) (1 to 3 a record, drawn anywhere in the record, no two within a cycle of
each other). Each record is what ``rotor simulate ENGINE --rpm RPM --cycles N --misfire
… --record FILE --wheel SPEC`` writes, made here in Python: :func:`rotor.simulate` from
the start speed under a propeller load (torque ∝ speed², so that the speed recovers after
a misfire) that balances the engine at that speed and fuelling
(:func:`rotor.steady_state`), each firing's combustion scale the fuelling times
1 + 2 % normal cycle-to-cycle variation (:func:`rotor.combustion_pattern` ``cov``), written
by :func:`rotor.diagnostics.record.record_run` (a perfect wheel, 20 ns of timer noise,
cylinder 1's TDC 29.4° after the gap, stated in the log's header).

**Two lead-ins.** ``record_run`` starts the log with a copy of the run's first cycle (so
that a reader's first whole cycle is the run's cycle 1) and ends it with a copy of its
last revolution. The matrix is run with that lead-in (``copy``) and again with the same
misfires and variation on runs two cycles longer, written from the run's start by
:func:`rotor.diagnostics.synthetic.simulated_tooth_times` with the same header
(``simulated``: every cycle of the log simulated, the first the lead-in, the record's
cycle k the run's k + 1), as a bench would record it (``--lead-in``; default both).

**The two detectors**, each as a user would run it on the log file:

- ``diagnose``: ``rotor.diagnose(engine, log, wheel=SPEC)`` (the engine given, the TDC
  from the log's header); its ``misfire`` flags, ``contribution`` index (1 a normal
  firing, a misfire below 0.5), ``identified`` and ``cycle_flags``.
- ``monitor``: ``MisfireMonitor(SPEC, tdc_deg=…, firing_parity=…, engine=engine)`` (the
  header's phase, the engine's firing angles; the verdict is the model-free index, the
  engine adds each firing's model IMEP), fed the log's tooth times one revolution of edges
  at a time, then closed.

**Compared** per firing (cycle, cylinder) of the simulated run: misfire yes/no of each.
A firing the monitor gives no verdict on, or that the diagnosis does not cover (its cycle
flagged as not supported, the firing not ``identified`` because the record's end cuts
it, or a diagnosis whose verdict is not ``FITS``), is counted apart, not as agreement.
Reported: the firings compared, the agreement rate with its 95 % Wilson interval, each
detector's detection of the inserted misfires and its false calls (on the compared
firings, and on all it judged), and every disagreement: the record, cycle, cylinder, the
truth, the monitor's index and misfire flag, the diagnosis's contribution, combustion
scale and flag, how many firings (in firing order) it lies from the nearest inserted
misfire and that misfire's monitor index, and its kind (a neighbour of a misfire flagged,
a false call in the monitor's first cycles, a misfire missed, …), counted per kind.

Writes ``benchmarks/results/monitor_agreement.json`` (``_quick.json`` for ``--quick``)
with the versions (rotor, jax, numpy, python) and the command.
"""

from __future__ import annotations

import argparse
import collections
import json
import math
import pathlib
import platform
import shlex
import sys
import tempfile
import time
import warnings

import jax
import numpy as np

import rotor
from rotor.diagnostics.monitor import MisfireMonitor
from rotor.diagnostics.record import record_run
from rotor.diagnostics.stated import stated_phase
from rotor.diagnostics.synthetic import DEFAULT_GAP_DEG, simulated_tooth_times
from rotor.logs.wheel import parse_wheel
from rotor.results import json_safe

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"

ENGINES = {  # preset: start speeds [rpm] within its range
    "4chn15": (800.0, 1250.0, 1800.0),
    "mwm6": (1200.0, 1700.0, 2200.0),
    "v8": (1500.0, 3000.0, 4500.0),
}
FUELLING = (1.0, 0.5)  # combustion scale of every firing: full and half
WHEELS = ("60-2", "36-1")
CYCLES = 40
MISFIRE_RECORDS = 4  # records with misfires per condition (and one fault-free)
COV = 0.02  # cycle-to-cycle variation of each firing's combustion scale
Z95 = 1.959963984540054
WARM_CYCLES = 4  # the monitor's first cycles: its baselines hold 3 firings a cylinder when it starts judging


def wilson(k: int, n: int) -> list[float] | None:
    """The 95 % Wilson score interval of k successes in n."""
    if n == 0:
        return None
    p = k / n
    d = 1 + Z95**2 / n
    c = (p + Z95**2 / (2 * n)) / d
    h = Z95 * math.sqrt(p * (1 - p) / n + Z95**2 / (4 * n * n)) / d
    return [max(0.0, c - h), min(1.0, c + h)]


def draw_misfires(rng: np.random.Generator, cycles: int, n: int) -> list[tuple[int, int]]:
    """1 to 3 single misfires (cycle, cylinder), no two within a cycle of each other."""
    want = int(rng.integers(1, 4))
    pairs: list[tuple[int, int]] = []
    for _ in range(200):
        if len(pairs) == want:
            break
        k = int(rng.integers(1, cycles + 1))
        if all(abs(k - k2) > 1 for k2, _ in pairs):
            pairs.append((k, int(rng.integers(1, n + 1))))
    return sorted(pairs)


def write_log(
    path: pathlib.Path, engine, rpm: float, load, fuel: float, wheel: str, cycles: int, pairs: list, lead: str, draws
) -> None:
    """Simulate a record of ``cycles`` cycles with the misfires ``pairs`` and write its log.

    ``lead="copy"``: :func:`record_run`, as ``rotor simulate --record`` writes it (a lead-in
    cycle that is a copy of the run's first cycle, a lead-out that is a copy of the first
    revolution of its last cycle). ``lead="simulated"``: a run of two cycles more, its first cycle the lead-in
    and its last revolution after the record the lead-out, every cycle simulated (the
    header states the same phase); the record's cycle k is the run's cycle k + 1."""
    n = int(engine.cylinders)
    extra = 0 if lead == "copy" else 2
    shift = 0 if lead == "copy" else 1
    pattern = rotor.combustion_pattern(
        cycles + extra,
        n,
        imep_scale=fuel,
        misfires=[(k + shift, c) for k, c in pairs],
        cov=COV,
        seed=int(draws.integers(2**31)),
    )
    run = rotor.simulate(engine, rpm=rpm, cycles=cycles + extra, load=load, combustion=pattern, progress=False)
    noise = int(draws.integers(2**31))
    if lead == "copy":
        record_run(path, run, wheel=wheel, misfires=pairs, seed=noise)
        return
    cyc = 360.0 * int(engine.strokes) / 2
    simulated_tooth_times(
        path,
        run,
        wheel=wheel,
        tooth_error_deg=0.0,
        start_deg=0.0,
        end_deg=(cycles + 1) * cyc + 360.0,
        seed=noise,
    )
    times = np.loadtxt(path)
    with open(path, "w") as f:
        f.write(f"# tdc_after_gap_deg: {-DEFAULT_GAP_DEG}\n# firing_parity: 0\ntooth_time_s\n")
        np.savetxt(f, times, fmt="%.10f")


def run_monitor(path: pathlib.Path, wheel: str, engine) -> tuple[dict, dict]:
    """The monitor's verdicts on the log ``path`` fed a revolution of edges at a time:
    {(cycle, cylinder): Verdict}, and what else it said."""
    tdc, parity = stated_phase(path)
    times = np.asarray(rotor.read_log(path)["tooth_time_s"], dtype=np.float64)
    m = MisfireMonitor(wheel, tdc_deg=tdc, firing_parity=parity, engine=engine)
    rev = parse_wheel(wheel).edges_per_rev
    out = []
    for i in range(0, times.size, rev):
        out += m.feed(times[i : i + rev])
    out += m.close()
    res = m.result()
    verdicts = {}
    for v in out:
        verdicts[(v.cycle, v.cylinder)] = v
    info = {
        "verdicts": len(out),
        "not_judged": res.not_judged,
        "note_counts": {str(k): int(c) for k, c in res.note_counts.items()},
    }
    return verdicts, info


def run_diagnose(path: pathlib.Path, wheel: str, engine):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = rotor.diagnose(engine, path, wheel=wheel)
    return d, [str(w.message) for w in caught if issubclass(w.category, UserWarning)]


def firing_slots(engine) -> dict:
    """{cylinder: its place in the cycle's firing sequence} (firing angles within a cycle,
    sorted, as the monitor and :func:`rotor.combustion_pattern` count them)."""
    cycle = 2 * math.pi * int(engine.strokes) / 2
    fire = np.mod(np.asarray(engine.firing_angles_rad, dtype=np.float64), cycle)
    return {int(c) + 1: i for i, c in enumerate(np.argsort(fire, kind="stable"))}


def kind_of(x: dict, cycles: int) -> str:
    """What kind of difference a disagreement is (for the summary)."""
    off = x["firings_from_nearest_inserted_misfire"]
    if x["inserted_misfire"]:
        return (
            "monitor misses an inserted misfire" if not x["monitor_misfire"] else "diagnose misses an inserted misfire"
        )
    if x["diagnose_misfire"]:
        return "diagnose false call"
    if off == -1:
        return "monitor flags the firing just before an inserted misfire"
    if off == 1:
        return "monitor flags the firing just after an inserted misfire"
    if x["cycle"] <= WARM_CYCLES:
        return f"monitor false call in the record's first {WARM_CYCLES} cycles"
    if x["cycle"] == cycles:
        return "monitor false call in the record's last cycle"
    return "monitor false call, other"


def compare_record(
    name: str, truth: set, cycles: int, n: int, verdicts: dict, d, counts: dict, slot: dict
) -> list[dict]:
    """Per firing of the run: count into ``counts``; return the disagreements."""
    inserted = sorted((k - 1) * n + slot[c] for k, c in truth)
    index_of = {(k - 1) * n + slot[c]: verdicts[(k, c)].index for k, c in truth if (k, c) in verdicts}
    fits = d.verdict == rotor.diagnostics.diagnosis.DiagnosisVerdict.FITS
    flags = list(d.cycle_flags) if d.cycle_flags else [""] * d.cycles
    diffs = []
    for k in range(1, cycles + 1):
        for c in range(1, n + 1):
            counts["firings"] += 1
            true_mis = (k, c) in truth
            v = verdicts.get((k, c))
            row = k - 1
            if not fits:
                d_ok, why = False, f"diagnosis verdict {d.verdict.name}"
            elif row >= d.cycles:
                d_ok, why = False, "cycle not in the diagnosis"
            elif flags[row]:
                d_ok, why = False, f"cycle not supported: {flags[row]}"
            elif not bool(d.identified[row, c - 1]):
                d_ok, why = False, "firing not identified (cut by the record's end)"
            else:
                d_ok, why = True, ""
            if v is None:
                counts["monitor_no_verdict"] += 1
                counts["monitor_no_verdict_misfires"] += true_mis
            else:
                counts["monitor_judged"] += 1
                counts["monitor_false_all"] += v.misfire and not true_mis
                counts["monitor_found_all"] += v.misfire and true_mis
                counts["monitor_judged_misfires"] += true_mis
            if not d_ok:
                counts["diagnose_not_covered"] += 1
                counts["diagnose_not_covered_misfires"] += true_mis
                counts["diagnose_not_covered_why"][why] = counts["diagnose_not_covered_why"].get(why, 0) + 1
            else:
                dm = bool(d.misfire[row, c - 1])
                counts["diagnose_covered"] += 1
                counts["diagnose_false_all"] += dm and not true_mis
                counts["diagnose_found_all"] += dm and true_mis
                counts["diagnose_covered_misfires"] += true_mis
            if v is None or not d_ok:
                if v is None and not d_ok:
                    counts["neither"] += 1
                elif v is not None and fits and row < d.cycles:  # the diagnosis flags it but gives a verdict
                    counts["flagged_both_judged"] += 1
                    counts["flagged_agree"] += bool(v.misfire) == bool(d.misfire[row, c - 1])
                continue
            counts["compared"] += 1
            dm = bool(d.misfire[row, c - 1])
            mm = bool(v.misfire)
            counts["inserted"] += true_mis
            counts["monitor_found"] += mm and true_mis
            counts["diagnose_found"] += dm and true_mis
            counts["monitor_false"] += mm and not true_mis
            counts["diagnose_false"] += dm and not true_mis
            if mm == dm:
                counts["agree"] += 1
                continue
            g = (k - 1) * n + slot[c]
            near = min(inserted, key=lambda x: abs(x - g)) if inserted else None
            diffs.append(
                {
                    "record": name,
                    "cycle": k,
                    "cylinder": c,
                    "inserted_misfire": true_mis,
                    "firings_from_nearest_inserted_misfire": None if near is None else g - near,
                    "nearest_inserted_misfire_monitor_index": (
                        None if near is None or near not in index_of else round(float(index_of[near]), 3)
                    ),
                    "monitor_misfire": mm,
                    "monitor_index": round(float(v.index), 3),
                    "monitor_imep_bar": round(float(v.imep_pa) / 1e5, 3) if math.isfinite(v.imep_pa) else None,
                    "diagnose_misfire": dm,
                    "diagnose_contribution": round(float(d.contribution[row, c - 1]), 4),
                    "diagnose_scale": round(float(d.scale[row, c - 1]), 4),
                    "diagnose_imep_bar": round(float(d.imep_pa[row, c - 1]) / 1e5, 3),
                    "right": "monitor" if mm == true_mis else ("diagnose" if dm == true_mis else "neither"),
                }
            )
            diffs[-1]["kind"] = kind_of(diffs[-1], cycles)
    return diffs


def new_counts() -> dict:
    keys = (
        "firings compared agree inserted monitor_found diagnose_found monitor_false diagnose_false "
        "monitor_no_verdict monitor_no_verdict_misfires monitor_judged monitor_judged_misfires monitor_found_all "
        "monitor_false_all diagnose_not_covered diagnose_not_covered_misfires diagnose_covered "
        "diagnose_covered_misfires diagnose_found_all diagnose_false_all neither flagged_both_judged flagged_agree"
    )
    c: dict = {k: 0 for k in keys.split()}
    c["diagnose_not_covered_why"] = {}
    return c


def add_counts(total: dict, c: dict) -> None:
    for k, v in c.items():
        if k.startswith("_"):
            continue
        if isinstance(v, dict):
            for w, x in v.items():
                total[k][w] = total[k].get(w, 0) + x
        else:
            total[k] += v


def summary(c: dict) -> dict:
    def rate(k, n):
        return {"count": k, "of": n, "rate": (k / n) if n else None, "ci95": wilson(k, n)}

    return {
        "firings": c["firings"],
        "compared": c["compared"],
        "agree": c["agree"],
        "agreement": rate(c["agree"], c["compared"]),
        "on_compared_firings": {
            "inserted_misfires": c["inserted"],
            "monitor_detection": rate(c["monitor_found"], c["inserted"]),
            "diagnose_detection": rate(c["diagnose_found"], c["inserted"]),
            "monitor_false_calls": c["monitor_false"],
            "diagnose_false_calls": c["diagnose_false"],
            "normal_firings": c["compared"] - c["inserted"],
        },
        "monitor_on_all_it_judged": {
            "judged": c["monitor_judged"],
            "no_verdict": c["monitor_no_verdict"],
            "no_verdict_inserted_misfires": c["monitor_no_verdict_misfires"],
            "detection": rate(c["monitor_found_all"], c["monitor_judged_misfires"]),
            "false_calls": c["monitor_false_all"],
        },
        "diagnose_on_all_it_covered": {
            "covered": c["diagnose_covered"],
            "not_covered": c["diagnose_not_covered"],
            "not_covered_inserted_misfires": c["diagnose_not_covered_misfires"],
            "not_covered_why": c["diagnose_not_covered_why"],
            "detection": rate(c["diagnose_found_all"], c["diagnose_covered_misfires"]),
            "false_calls": c["diagnose_false_all"],
        },
        "neither_judged": c["neither"],
        "diagnose_flagged_firings_both_judged": {
            "note": "firings in a cycle the diagnosis flags as not supported, where both still give a verdict "
            "(not in the agreement above)",
            "agreement": rate(c["flagged_agree"], c["flagged_both_judged"]),
        },
    }


def run_matrix(plan: dict, fuelling, wheels, cycles: int, misfire_records: int, with_clean: bool, lead: str) -> dict:
    """Every record of the matrix with the lead-in ``lead``: the counts, per engine, the
    disagreements and the records."""
    rng = np.random.default_rng(20261127)  # the same misfires and variation for either lead-in
    total = new_counts()
    per_engine: dict = {}
    records = []
    diffs: list[dict] = []
    print(f"lead-in: {lead}", flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "rec.csv"
        for name in plan:
            engine = rotor.load_engine(name)
            n = int(engine.cylinders)
            slot = firing_slots(engine)
            ec = new_counts()
            for rpm in plan[name]:
                for fuel in fuelling:
                    st = rotor.steady_state(engine, rpm=rpm, imep_scale=fuel)
                    torque = float(np.asarray(st.load_torque_Nm))
                    load = rotor.PropellerLoad(torque, rpm)
                    for wheel in wheels:
                        kinds = ([[]] if with_clean else []) + [
                            draw_misfires(rng, cycles, n) for _ in range(misfire_records)
                        ]
                        for pairs in kinds:
                            tag = f"{name} {rpm:.0f} rpm fuel {fuel:g} {wheel} " + (
                                "misfires " + ",".join(f"{k}:{c}" for k, c in pairs) if pairs else "fault-free"
                            )
                            ts = time.perf_counter()
                            write_log(path, engine, rpm, load, fuel, wheel, cycles, pairs, lead, rng)
                            t_sim = time.perf_counter() - ts
                            verdicts, minfo = run_monitor(path, wheel, engine)
                            t_mon = time.perf_counter() - ts - t_sim
                            d, dwarn = run_diagnose(path, wheel, engine)
                            t_diag = time.perf_counter() - ts - t_sim - t_mon
                            c = new_counts()
                            rd = compare_record(tag, set(pairs), cycles, n, verdicts, d, c, slot)
                            add_counts(ec, c)
                            add_counts(total, c)
                            diffs += rd
                            records.append(
                                {
                                    "record": tag,
                                    "engine": name,
                                    "rpm": rpm,
                                    "fuel_scale": fuel,
                                    "load_torque_Nm_at_rpm": round(torque, 2),
                                    "wheel": wheel,
                                    "cycles": cycles,
                                    "misfires_inserted": [list(p) for p in pairs],
                                    "monitor_misfires": sorted([list(k) for k, v in verdicts.items() if v.misfire]),
                                    "diagnose_misfires": [list(p) for p in d.identification.misfires()],
                                    "diagnose_verdict": d.verdict.name,
                                    "diagnose_fit_r2": round(float(d.fit_r2), 5),
                                    "diagnose_ambiguous_pairs": [list(p) for p in d.ambiguous_pairs],
                                    "diagnose_warnings": dwarn,
                                    "monitor": minfo,
                                    "compared": c["compared"],
                                    "agree": c["agree"],
                                    "disagreements": len(rd),
                                    "seconds": {
                                        "simulate_record": round(t_sim, 2),
                                        "monitor": round(t_mon, 3),
                                        "diagnose": round(t_diag, 2),
                                    },
                                }
                            )
                            print(
                                f"  {tag:58s} compared {c['compared']:4d} agree {c['agree']:4d}  "
                                f"monitor {records[-1]['monitor_misfires']} diagnose {records[-1]['diagnose_misfires']}"
                                f"  ({t_sim:.1f} + {t_mon:.2f} + {t_diag:.1f} s)",
                                flush=True,
                            )
            per_engine[name] = summary(ec)
    s = summary(total)
    a = s["agreement"]
    print(
        f"lead-in {lead}: {s['compared']} firings compared (of {s['firings']}): agreement {a['rate']:.4f} "
        f"(95 % {a['ci95'][0]:.4f}–{a['ci95'][1]:.4f}); {len(diffs)} disagreements"
    )
    oc = s["on_compared_firings"]
    print(
        f"  inserted misfires compared {oc['inserted_misfires']}: monitor found {oc['monitor_detection']['count']}, "
        f"diagnose {oc['diagnose_detection']['count']}; false calls monitor {oc['monitor_false_calls']}, "
        f"diagnose {oc['diagnose_false_calls']} (of {oc['normal_firings']} normal firings)"
    )
    print(
        f"  not compared: monitor no verdict {s['monitor_on_all_it_judged']['no_verdict']}, "
        f"diagnose not covering {s['diagnose_on_all_it_covered']['not_covered']} "
        f"{s['diagnose_on_all_it_covered']['not_covered_why']}"
    )
    kinds = dict(collections.Counter(x["kind"] for x in diffs).most_common())
    for kind, count in kinds.items():
        print(f"  {count:4d}  {kind}")
    for x in diffs:
        print(
            f"    {x['record']}: cycle {x['cycle']} cyl {x['cylinder']} inserted {x['inserted_misfire']} | monitor "
            f"{x['monitor_misfire']} index {x['monitor_index']:+.2f} | diagnose {x['diagnose_misfire']} contribution "
            f"{x['diagnose_contribution']:.3f} | {x['kind']}"
        )
    return {
        "lead_in": lead,
        "records": len(records),
        "meets_requirement": (total["agree"] >= 0.99 * total["compared"]) if total["compared"] else None,
        "summary": s,
        "per_engine": per_engine,
        "disagreement_kinds": kinds,
        "disagreement_kinds_per_engine": {
            e: dict(collections.Counter(x["kind"] for x in diffs if x["record"].split()[0] == e).most_common())
            for e in plan
        },
        "disagreements": diffs,
        "record_list": records,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one record of 4chn15 and one of v8 (under 2 minutes)")
    ap.add_argument("--engines", type=str, default=None, help="presets, comma separated (default 4chn15,mwm6,v8)")
    ap.add_argument("--cycles", type=int, default=CYCLES, help=f"cycles a record (default {CYCLES})")
    ap.add_argument(
        "--lead-in",
        choices=("copy", "simulated", "both"),
        default=None,
        help="the record's lead-in cycle: copy (as rotor simulate --record writes it), simulated, or both "
        "(default: both; --quick: copy)",
    )
    args = ap.parse_args()
    t0 = time.perf_counter()
    if args.quick:
        plan = {"4chn15": (800.0,), "v8": (1500.0,)}
        fuelling, wheels, misfire_records, with_clean = (1.0,), ("60-2",), 1, False
    else:
        plan = {e: ENGINES[e] for e in (args.engines.split(",") if args.engines else ENGINES)}
        fuelling, wheels, misfire_records, with_clean = FUELLING, WHEELS, MISFIRE_RECORDS, True
    lead = args.lead_in or ("copy" if args.quick else "both")
    leads = ("copy", "simulated") if lead == "both" else (lead,)
    runs = {x: run_matrix(plan, fuelling, wheels, args.cycles, misfire_records, with_clean, x) for x in leads}
    out = {
        "command": "nice -n 19 .venv/bin/python benchmarks/monitor_agreement.py"
        + ("" if len(sys.argv) < 2 else " " + shlex.join(sys.argv[1:])),
        "matrix": {
            "engines": {k: list(v) for k, v in plan.items()},
            "fuel_scales": list(fuelling),
            "wheels": list(wheels),
            "cycles_per_record": args.cycles,
            "records_per_condition": ("1 fault-free + " if with_clean else "") + f"{misfire_records} with misfires",
            "misfires": "1 to 3 single misfires a record, at random cycles and cylinders, no two within a cycle",
            "cycle_to_cycle_variation_cov": COV,
            "load": "propeller law balancing the engine at the start speed and fuelling (rotor.steady_state)",
            "wheel_errors": "none (a perfect wheel), 20 ns timer noise, TDC 29.4 deg after the gap",
            "lead_in": "copy: record_run's (rotor simulate --record), a copy of the first cycle; simulated: a run of "
            "two cycles more, its first cycle the lead-in",
        },
        "requirement": "agreement on at least 99 % of the firings compared",
        "results": runs,
        "seconds": round(time.perf_counter() - t0, 1),
        "versions": {
            "rotor": rotor.__version__,
            "jax": jax.__version__,
            "numpy": np.__version__,
            "python": platform.python_version(),
        },
        "machine": platform.machine(),
    }
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / ("monitor_agreement_quick.json" if args.quick else "monitor_agreement.json")
    path.write_text(json.dumps(json_safe(out), indent=1, allow_nan=False) + "\n")
    print(f"wrote {path.relative_to(ROOT)} ({out['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
