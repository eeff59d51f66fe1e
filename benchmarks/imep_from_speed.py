"""Where speed-based IMEP works: calibrated on some recordings with their pressure, read on others from speed alone.

    nice -n 19 .venv/bin/python benchmarks/imep_from_speed.py [--data ../shared/data] \
        [--out benchmarks/published/imep_from_speed.json]

**The tue-4gb10 matrix** (the three real recordings of the single-cylinder bench: no,
half and full load at about 3000 rpm): for every set of calibration recordings (each one
alone, each two, all three) :func:`rotor.calibrate` on them with their pressure channel
(the data README's sensor gain 51.95 bar/V, the offset fitted), then :func:`rotor.diagnose`
of every recording from the encoder column alone (``columns="time,-,encoder_v"``, TDC and
tooth errors the calibration's, the TDC checked against the speed). Per cell: the mean
identified IMEP against the mean IMEP of that recording's own pressure channel
(:func:`rotor.measured_imep`, the same gain) [% and bar], the per-cycle rms error, the TDC
used against the pressure's TDC of that recording [deg], the check's verdict, its
bias-corrected speed TDC against the pressure's [deg] and its σ, and whether the
diagnosis says the recording lies inside what the calibration covers (``supported``).

**The simulated grid** (reduced): tue-single, 4chn15 and mwm6 (1, 4 and 6 cylinders) at
0.5, 0.75 and 1 times their operating speed, loads 0.15 (idle) to 1 of the file's
combustion, rigid crankshaft, the speed straight from :func:`rotor.simulate` (no wheel),
each cycle's combustion the load times one of the Yanmar L100V's 60 measured fired
cycles' IMEP ratio (real cycle-to-cycle variation, CoV about 1.6 %), identified with the
engine file itself (its own cycle: a calibration right at full load). The simulated
pressure is the file's own shape scaled, so this measures only the identification's
inversion of its own model (it comes out exact), not the error of a cycle shape unlike the
file's: that is what the real matrix measures.

The done-when figures are counted at the end: calibrated on one recording, the others
within 10 % and TDC within 2°; calibrated on two, the third within 5 %.

Writes ``benchmarks/published/imep_from_speed.json`` (with rotor's, NumPy's and JAX's
versions and each cell's wall time; calibrations' wall time kept apart).
"""

from __future__ import annotations

import argparse
import itertools
import json
import platform
import time
from pathlib import Path

import jax
import numpy as np

import rotor

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT / ".." / "shared" / "data"
OUT = ROOT / "benchmarks" / "published" / "imep_from_speed.json"
GAIN = 1e5 / (5 * 0.00385)  # Pa per volt, the data README (the bench's own scripts)
RECORDINGS = ("full_load", "half_load", "No_load")


def _wrap(x: float) -> float:
    return (x + 180.0) % 360.0 - 180.0


def pressure_truth(folder, name):
    """The recording's own pressure: its analysis at the pressure's TDC and that TDC [deg]."""
    a = rotor.analyze_log(
        folder / f"{name}.txt",
        "60-2",
        columns="time,pressure_v,encoder_v",
        compression_ratio=8.5,
        rod_ratio=27.5 / 84.2,
    )
    return a, float(np.rad2deg(a.tdc_rad))


def read_cell(engine, folder, cal, name, truth):
    """One recording read from speed alone with ``cal``, against its pressure."""
    t0 = time.perf_counter()
    d = rotor.diagnose(engine, folder / f"{name}.txt", cal, columns="time,-,encoder_v")
    wall = time.perf_counter() - t0
    pressure, tdc_true = truth
    meas = rotor.measured_imep(engine, pressure, GAIN)  # at the recording's own pressure TDC
    ident = d.imep_pa[:, 0]
    # the cycles paired by their start times (the speed's cut at the TDC used, the pressure's at its own)
    j = np.searchsorted(pressure.t_start_s, d.t_start_s - 0.5 * np.median(np.diff(pressure.t_start_s)))
    pair = j < meas.size
    err = ident[pair] - meas[j[pair]]
    m = float(np.mean(meas))
    chk = d.tdc_check
    speed_tdc = None if chk is None or chk.fit.tdc_after_gap_deg is None else chk.fit.tdc_after_gap_deg - chk.bias_deg
    return {
        "measured_imep_bar": m / 1e5,
        "identified_imep_bar": float(np.mean(ident)) / 1e5,
        "error_mean_pct": 100.0 * (float(np.mean(ident)) - m) / m,
        "error_rms_pct": 100.0 * float(np.sqrt(np.mean(err**2))) / m,
        "tdc_used_deg": float(np.rad2deg(d.analysis.tdc_rad)),
        "tdc_pressure_deg": tdc_true,
        "tdc_used_error_deg": _wrap(float(np.rad2deg(d.analysis.tdc_rad)) - tdc_true),
        "tdc_check": None if chk is None else chk.verdict.name.lower(),
        "tdc_check_bias_deg": None if chk is None else chk.bias_deg,
        "tdc_check_sigma_deg": None if chk is None else chk.std_deg,
        "tdc_speed_less_bias_error_deg": None if speed_tdc is None else _wrap(float(speed_tdc) - tdc_true),
        "supported": not d.coverage,
        "unsupported_reason": d.coverage or None,
        "r2": float(d.fit_r2),
        "wall_s": wall,
    }


def tue_matrix(folder):
    engine = rotor.load_engine("tue-single")
    truths = {n: pressure_truth(folder, n) for n in RECORDINGS}
    cells, cals = [], {}
    for k in (1, 2, 3):
        for on in itertools.combinations(RECORDINGS, k):
            t0 = time.perf_counter()
            cal = rotor.calibrate(
                engine,
                [folder / f"{n}.txt" for n in on],
                wheel="60-2",
                columns="time,pressure_v,encoder_v",
                pressure_gain=GAIN,
            )
            key = "+".join(on)
            cals[key] = {
                "wall_s": time.perf_counter() - t0,
                "inertia_kgm2": cal.inertia_kgm2,
                "tdc_after_gap_deg": cal.tdc_after_gap_deg,
                "tdc_bias": None if cal.tdc_bias is None else cal.tdc_bias.to_json_dict(),
                "coverage": cal.coverage(),
            }
            for name in RECORDINGS:
                cell = {"calibrated_on": list(on), "read": name, "held_out": name not in on}
                cell.update(read_cell(engine, folder, cal, name, truths[name]))
                cells.append(cell)
                print(
                    f"calibrated on {key:30s} read {name:9s}: IMEP {cell['identified_imep_bar']:.3f} against "
                    f"{cell['measured_imep_bar']:.3f} bar ({cell['error_mean_pct']:+.1f} %), TDC used "
                    f"{cell['tdc_used_error_deg']:+.2f}°, check {cell['tdc_check']} (speed less bias "
                    f"{cell['tdc_speed_less_bias_error_deg']:+.2f}° ± {cell['tdc_check_sigma_deg']:.2f}°)"
                    + ("" if cell["supported"] else "  [outside the calibration's coverage]"),
                    flush=True,
                )
    held = [c for c in cells if c["held_out"]]
    one = [c for c in held if len(c["calibrated_on"]) == 1]
    two = [c for c in held if len(c["calibrated_on"]) == 2]
    done = {
        "one_calibration_within_10_pct": sum(abs(c["error_mean_pct"]) <= 10.0 for c in one),
        "one_calibration_tdc_within_2_deg": sum(abs(c["tdc_used_error_deg"]) <= 2.0 for c in one),
        "one_calibration_cells": len(one),
        "two_calibrations_within_5_pct": sum(abs(c["error_mean_pct"]) <= 5.0 for c in two),
        "two_calibrations_cells": len(two),
        "held_out_unsupported_beyond_10_pct": sum(
            (not c["supported"]) for c in held if abs(c["error_mean_pct"]) > 10.0
        ),
        "held_out_beyond_10_pct": sum(abs(c["error_mean_pct"]) > 10.0 for c in held),
    }
    return {"cells": cells, "calibrations": cals, "done_when": done}


YANMAR_COLUMNS = slice(1, 61)  # the 60 fired cycles' pressure [bar]; column 0 the crank angle [deg]
GRID_ENGINES = ("tue-single", "4chn15", "mwm6")  # 1, 4 and 6 cylinders
GRID_SPEEDS = (0.5, 0.75, 1.0)  # of each engine's operating speed
GRID_LOADS = (0.15, 0.25, 0.5, 1.0)  # combustion scale of the engine file's full load (0.15: idle)
GRID_CYCLES = 24


def yanmar_variation(folder):
    """Each of the Yanmar L100V's 60 fired cycles' net IMEP over their mean [-] (∮p·dV with its
    bore, stroke, rod and compression ratio from the data README)."""
    data = np.loadtxt(folder / "fired-18Nm.txt")
    theta = np.deg2rad(data[:, 0])
    bore, stroke, rod, eps = 0.086, 0.075, 0.118, 21.2
    r = stroke / 2
    lam = r / rod
    vh = np.pi / 4 * bore**2 * stroke
    v = vh / (eps - 1) + np.pi / 4 * bore**2 * r * (
        1 - np.cos(theta) + (1 - np.sqrt(1 - (lam * np.sin(theta)) ** 2)) / lam
    )
    p = data[:, YANMAR_COLUMNS] * 1e5
    dv = np.gradient(v)
    imep = np.sum(p * dv[:, None], axis=0) / vh
    return imep / np.mean(imep)


def simulated_grid(folder):
    """The reduced grid: rigid crankshaft, speed straight from the simulation (no wheel), each
    cycle's combustion the load times one of the Yanmar's cycles (drawn at random), the engine
    file's own inertia and cycle (a calibration that is right at full load); identified with
    load_per="block". Per cell the bias of the mean IMEP and the per-cycle rms error [%]."""
    rng = np.random.default_rng(0)
    ratio = yanmar_variation(folder)
    cells = []
    for name in GRID_ENGINES:
        engine = rotor.load_engine(name)
        for fs in GRID_SPEEDS:
            rpm = fs * float(engine.operating.rpm)
            for load in GRID_LOADS:
                comb = load * rng.choice(ratio, size=(GRID_CYCLES, engine.cylinders))
                try:
                    torque = float(rotor.steady_state(engine, rpm, imep_scale=load).load_torque_Nm)
                    res = rotor.simulate(
                        engine, rpm, GRID_CYCLES, rotor.ConstantLoad(torque), combustion=comb, progress=False
                    )
                    t0 = time.perf_counter()
                    ident = rotor.identify(engine, res, load_per="block")
                    wall = time.perf_counter() - t0
                except rotor.EngineError as e:
                    cells.append({"engine": name, "rpm": rpm, "load": load, "error": str(e)[:200]})
                    continue
                truth = np.asarray(res.imep_pa)[: ident.cycles]
                got = ident.imep_pa[: truth.shape[0]]
                ok = ident.identified[: truth.shape[0]]
                err = (got - truth)[ok]
                ref = float(np.mean(truth[ok]))
                cell = {
                    "engine": name,
                    "cylinders": int(engine.cylinders),
                    "rpm": rpm,
                    "load": load,
                    "imep_true_bar": ref / 1e5,
                    "bias_pct": 100.0 * float(np.mean(err)) / ref,
                    "rms_pct": 100.0 * float(np.sqrt(np.mean(err**2))) / ref,
                    "r2": float(ident.fit_r2),
                    "wall_s": wall,
                }
                cells.append(cell)
                print(
                    f"{name:10s} {rpm:6.0f} rpm load {load:4.2f}: IMEP {ref / 1e5:6.2f} bar, bias "
                    f"{cell['bias_pct']:+6.2f} %, per cycle rms {cell['rms_pct']:5.2f} %",
                    flush=True,
                )
    return {
        "cycles": GRID_CYCLES,
        "cycle_to_cycle_cov_pct": 100.0 * float(np.std(ratio, ddof=1)),
        "what": (
            "the engine file's own cycle shape, scaled per cycle: this measures the identification's inversion "
            "of its own model (with the Yanmar's cycle-to-cycle variation), not the error of a cycle shape "
            "unlike the file's, which the tue-4gb10 matrix measures"
        ),
        "crankshaft": "rigid",
        "wheel": "none (the simulated speed)",
        "cells": cells,
    }


def plot(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    tue = results["tue-4gb10"]["cells"]
    for k, marker in ((1, "o"), (2, "s")):
        held = [c for c in tue if c["held_out"] and len(c["calibrated_on"]) == k]
        a.scatter(
            [c["measured_imep_bar"] for c in held],
            [c["error_mean_pct"] for c in held],
            marker=marker,
            label=f"calibrated on {k} recording{'s' if k > 1 else ''}",
        )
    for lim in (-10, 10):
        a.axhline(lim, color="0.6", lw=0.8, ls="--")
    a.set(xlabel="measured IMEP [bar]", ylabel="speed-based IMEP error [%]", title="tue-4gb10, held-out recordings")
    a.legend()
    grid = [c for c in results.get("simulated", {}).get("cells", []) if "bias_pct" in c]
    for name in GRID_ENGINES:
        cs = [c for c in grid if c["engine"] == name]
        b.scatter([c["load"] for c in cs], [c["rms_pct"] for c in cs], label=f"{name} per-cycle rms")
    for lim in (5, 10):
        b.axhline(lim, color="0.6", lw=0.8, ls="--")
    b.set(
        xlabel="load (combustion scale)",
        ylabel="IMEP error [%]",
        title="simulated with the file's own cycle (an inversion check)",
    )
    b.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--parts", default="tue,grid", help="which parts: tue (the real matrix), grid (simulated)")
    args = ap.parse_args(argv)
    folder = args.data / "tue-4gb10"
    if not folder.is_dir():
        raise SystemExit(f"no data at {folder}")
    results = {
        "versions": {
            "rotor": getattr(rotor, "__version__", "?"),
            "numpy": np.__version__,
            "jax": jax.__version__,
            "python": platform.python_version(),
        },
        "gain_pa_per_v": GAIN,
    }
    if "tue" in args.parts:
        results["tue-4gb10"] = tue_matrix(folder)
    if "grid" in args.parts:
        results["simulated"] = simulated_grid(args.data / "yanmar-l100v")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(rotor.results.json_safe(results), indent=1) + "\n")
    if "tue-4gb10" in results:
        print(json.dumps(results["tue-4gb10"]["done_when"], indent=1))
        plot(results, args.out.with_suffix(".png"))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
