"""A 1000-cycle transient against the numba RK4 at equal error and equal output.

The scene, the error and the baselines are those of ``work_precision.py`` (imported, not
copied): each preset started at 0.95 × its operating speed under ``PropellerLoad(T,
operating rpm)``; error ω = max|ω − ω_ref| / mean ω_ref over the 1° crank angles of the
last cycle that a run saves, each run against a reference of its own physics (rotor:
``closed`` at grid_deg 0.0625; numba: its RK4 at 11,520 steps per cycle).

**Equal error.** Each solver at the cheapest setting of its knob that reaches error ω ≤
``--target`` (default 1e-6): numba RK4 at 90, 180, 360, 720 steps per cycle; rotor
``closed`` (what ``method="auto"`` picks for this scene) at grid_deg 4, 2, 1, 0.5, 0.25;
rotor ``grid`` (RK4 in a ``lax.scan``) at 90 … 1440 steps per cycle.

**Equal output.** Two modes, both solvers saving the same samples:

- ``every cycle``: ω and t on the same crank-angle grid in every cycle, the coarser of
  numba's step and rotor's node spacing (numba saves every ``every``-th step; rotor
  ``step_deg`` = that spacing). rotor's samples also carry the engine and load torque,
  dω/dt and θ at each sample (its result arrays); numba's only ω and t.
- ``last cycle``: rotor ``keep_cycles=1`` (the last cycle's samples on that grid plus the
  per-cycle summary of every cycle: start and end time, mean, highest and lowest speed,
  δ); numba saving ω and t once per cycle (less than rotor's: a bound in numba's favour).
  Its error is that of the same setting in the first mode (the same arithmetic).

Times: medians of ``--repeats`` calls (wall and process time), rotor and numba calls
interleaved in one loop so that load from other jobs falls on both alike, after a first
call apart (compile). rotor is called with the plain :class:`rotor.Engine` (its table
cache in effect, as for any repeated call) and once more with a :func:`rotor.prepare`\\ d
engine.

    .venv/bin/python benchmarks/transient_limit.py                    # all presets, ~3 min
    .venv/bin/python benchmarks/transient_limit.py --presets v8 --repeats 5

Writes benchmarks/results/transient_limit.json and prints the ratio rotor/numba per
preset (the target: ≤ 2 on every preset).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import work_precision as wp  # noqa: E402  (sets ROTOR_COMPILATION_CACHE=off unless given)

import rotor  # noqa: E402
from rotor.fileio import write_text_atomic  # noqa: E402

CYCLES = 1000
NUMBA_SPC = [90, 180, 360, 720]
CLOSED_GRID = [4.0, 2.0, 1.0, 0.5, 0.25]
GRID_SPC = [90, 180, 360, 720, 1440]
TARGET_TIMES = 2.0  # the target: rotor within 2× the numba time


def timed(fn):
    w0, p0 = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - w0, time.process_time() - p0, out


def stats(samples):
    wall, cpu = zip(*samples)
    return {
        "median_s": statistics.median(wall),
        "median_cpu_s": statistics.median(cpu),
        "wall_s": list(wall),
        "cpu_s": list(cpu),
        "repeats": len(wall),
    }


class Preset:
    def __init__(self, name, target):
        self.b = b = wp.Bench(name, quick=True, cap=1e9, first=CYCLES)  # engine, load, numpy physics, numba
        self.name, self.target = name, target
        self.cycle_deg = float(np.rad2deg(b.ph.cycle))
        self.start = (CYCLES - 1) * b.ph.cycle
        t0 = time.perf_counter()
        self.ref_r = self.rotor_lc(self.sim(method="closed", grid_deg=0.0625))
        self.ref_n = wp.last_cycle(*self.numba(wp.REF_SPC, 1), self.start)
        self.ref_s = time.perf_counter() - t0
        self.prepared = {}

    # ---------------------------------------------------------------- the two solvers
    def sim(self, engine=None, **kw):
        b = self.b
        r = rotor.simulate(engine or b.engine, rpm=b.rpm0, cycles=CYCLES, load=b.load, **kw)
        return wp._block(r)

    def rotor_lc(self, r):
        return wp.last_cycle(r.theta, r.t, r.omega, self.start)

    def numba(self, spc, every):
        """(θ, t, ω) of the numba RK4 at ``spc`` steps per cycle, saved every ``every`` steps."""
        w, t = wp.nb_rk4(self.b.omega0, self.b.c, CYCLES, spc, every, self.b.ph.nb)
        return self.b.ph.cycle / spc * every * np.arange(w.size), t, w

    # ---------------------------------------------------------------- equal error
    def cheapest(self, settings, err_of):
        """The first (cheapest) setting whose error ω is ≤ the target, and every error seen."""
        seen = {}
        for s in settings:
            seen[s] = err_of(s)
            if seen[s]["omega_rel"] <= self.target:
                return s, seen
        return None, seen

    def numba_error(self, spc):
        return wp.error(wp.last_cycle(*self.numba(spc, 1), self.start), self.ref_n)

    def closed_error(self, g):
        return wp.error(self.rotor_lc(self.sim(method="closed", grid_deg=g, step_deg=max(g, 1.0))), self.ref_r)

    def grid_error(self, spc):
        step = max(self.cycle_deg / spc, 1.0)
        return wp.error(self.rotor_lc(self.sim(method="grid", steps_per_cycle=spc, step_deg=step)), self.ref_r)

    # ---------------------------------------------------------------- one comparison
    def compare(self, repeats, contenders, numba_spc, out_deg, keep_last):
        """Interleaved timing of the rotor ``contenders`` {label: kwargs} and the numba RK4,
        all saving every ``out_deg`` degrees (``keep_last``: rotor the last cycle only,
        numba once per cycle)."""
        n_every = numba_spc if keep_last else int(round(numba_spc * out_deg / self.cycle_deg))
        calls = {"numba": lambda: self.numba(numba_spc, n_every)}
        for label, kw in contenders.items():
            kw = dict(kw, step_deg=out_deg, **({"keep_cycles": 1} if keep_last else {}))
            calls[label] = lambda kw=kw: self.sim(**kw)
        first = {k: timed(f) for k, f in calls.items()}  # compile (and the tables' cache) apart
        samples = {k: [] for k in calls}
        for _ in range(repeats):
            for k, f in calls.items():
                samples[k].append(timed(f)[:2])
        res = {}
        for k in calls:
            res[k] = stats(samples[k])
            res[k]["first_call_s"] = first[k][0]
            out = first[k][2]
            if k == "numba":
                res[k]["saved_per_cycle"] = (numba_spc // n_every) if not keep_last else 1
                res[k]["saved"] = int(out[2].size)
            else:
                res[k]["method"] = out.method
                res[k]["saved"] = int(np.size(out.omega))
                res[k]["saved_per_cycle"] = int(out.points_per_cycle)
                res[k]["kept_cycles"] = int(out.uniform_cycles - out.first_kept_cycle)
                res[k]["error"] = wp.error(self.rotor_lc(out), self.ref_r)
        if not keep_last:
            res["numba"]["error"] = wp.error(wp.last_cycle(*first["numba"][2], self.start), self.ref_n)
        n = res["numba"]
        for k in contenders:
            res[k]["ratio_wall"] = res[k]["median_s"] / n["median_s"]
            res[k]["ratio_cpu"] = res[k]["median_cpu_s"] / n["median_cpu_s"]
        return res

    def run(self, repeats):
        ns, n_seen = self.cheapest(NUMBA_SPC, self.numba_error)
        g, c_seen = self.cheapest(CLOSED_GRID, self.closed_error)
        out = {
            "rpm_start": self.b.rpm0,
            "load": f"PropellerLoad({self.b.torque:.6g} N·m, {self.b.rpm:g} rpm)",
            "references_s": self.ref_s,
            "errors": {
                "numba RK4 (steps per cycle)": {str(k): v for k, v in n_seen.items()},
                "rotor closed (grid_deg)": {str(k): v for k, v in c_seen.items()},
            },
        }
        if ns is None or g is None:
            out["failed"] = "no setting reached the target"
            return out
        numba_step = self.cycle_deg / ns
        out_deg = max(numba_step, g)  # both powers of two times 1°: the coarser one divides into both
        P = int(round(self.cycle_deg / out_deg))
        # rotor grid: the cheapest RK4 step count reaching the target that saves on that grid
        gs, g_seen = self.cheapest([s for s in GRID_SPC if s % P == 0], self.grid_error)
        out["errors"]["rotor grid (steps per cycle)"] = {str(k): v for k, v in g_seen.items()}
        contenders = {"rotor auto": dict(method="auto", grid_deg=g)}
        if gs is not None:
            contenders["rotor grid"] = dict(method="grid", steps_per_cycle=gs, grid_deg=min(g, out_deg))
        self.prepared = rotor.prepare(self.b.engine, grid_deg=g)
        contenders["rotor auto, prepared engine"] = dict(method="auto", grid_deg=g, engine=self.prepared)
        out["settings"] = {
            "numba_steps_per_cycle": ns,
            "rotor_closed_grid_deg": g,
            "rotor_grid_steps_per_cycle": gs,
            "output_every_deg": out_deg,
            "output_per_cycle": P,
        }
        out["every_cycle"] = self.compare(repeats, contenders, ns, out_deg, keep_last=False)
        out["last_cycle"] = self.compare(repeats, contenders, ns, out_deg, keep_last=True)
        return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", default="4chn15,mwm6,v8,tue-single")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--target", type=float, default=1e-6, help="error ω both solvers must reach")
    ap.add_argument("--stem", default="transient_limit")
    args = ap.parse_args()
    wp.RESULTS.mkdir(parents=True, exist_ok=True)
    res = {
        "cycles": CYCLES,
        "target_error_omega": args.target,
        "target_ratio": TARGET_TIMES,
        "versions": wp.versions(),
        "notes": __doc__.split("\n\n", 1)[1].rsplit("\n\n", 2)[0],
        "presets": {},
    }
    wall = time.perf_counter()
    for name in args.presets.split(","):
        p = Preset(name, args.target)
        res["presets"][name] = r = p.run(args.repeats)
        print(f"\n{name}: {r.get('settings', r.get('failed'))}", flush=True)
        for mode in ("every_cycle", "last_cycle"):
            for k, v in r.get(mode, {}).items():
                err = v.get("error", {}).get("omega_rel")
                ratio = f"  ×{v['ratio_wall']:.2f} wall, ×{v['ratio_cpu']:.2f} cpu" if "ratio_wall" in v else ""
                print(
                    f"  {mode:11s} {k:28s} {v['median_s'] * 1e3:8.1f} ms (cpu {v['median_cpu_s'] * 1e3:7.1f}) "
                    f"error {err if err is None else format(err, '.1e')}  saved {v['saved']}{ratio}",
                    flush=True,
                )
        res["elapsed_s"] = time.perf_counter() - wall
        write_text_atomic(wp.RESULTS / f"{args.stem}.json", json.dumps(res, indent=1, ensure_ascii=False))
    print(f"\nrotor auto / numba RK4 at {CYCLES} cycles, error ω ≤ {args.target:g}, equal output (wall; cpu):")
    for name, r in res["presets"].items():
        if "every_cycle" in r:
            a, b = r["every_cycle"]["rotor auto"], r["last_cycle"]["rotor auto"]
            ok = max(a["ratio_wall"], b["ratio_wall"]) <= TARGET_TIMES
            print(
                f"  {name:11s} every cycle ×{a['ratio_wall']:.2f}; ×{a['ratio_cpu']:.2f}   last cycle "
                f"×{b['ratio_wall']:.2f}; ×{b['ratio_cpu']:.2f}   {'met' if ok else 'MISSED'}"
            )
    print(f"wrote {wp.RESULTS / (args.stem + '.json')} in {time.perf_counter() - wall:.0f} s")


if __name__ == "__main__":
    main()
