"""IMEP from crank speed alone on the real tue-4gb10 recordings, against their own pressure.

    nice -n 19 .venv/bin/python benchmarks/diagnose_real.py [--data ../shared/data] \
        [--out benchmarks/results/diagnose_real.json] [--calibration-only]

For each recording as the calibration one (``full_load`` first: the one whose numbers the
``tue-single`` preset carries), :func:`rotor.calibrate` on it (pressure channel, the data
README's sensor gain 51.95 bar/V; the offset is fitted), then :func:`rotor.diagnose` of all
three from the encoder column alone (``columns="time,-,encoder_v"``, TDC and tooth errors
from the calibration), and the identified IMEP of each cycle compared with the IMEP of the
same cycle from that recording's own pressure channel (``rotor.measured_imep``, ∮p·dV with
the same gain). Also each variant that explains the choices: ``scaling="none"`` (the
combustion part of the file's cycle scaled alone, as identify does), ``load_per="cycle"``,
and the energy-balance inertia without the identification refinement.

Writes ``benchmarks/results/diagnose_real.json`` (per calibration recording and variant:
per recording the mean, rms and max of identified − measured IMEP [bar] and [% of the
measured mean]; the calibrations) and ``rotor/presets/tue-single.calibration.json`` (the
full-load calibration that the ``tue-single`` preset ships: ``rotor diagnose --engine
tue-single`` uses it when no ``--calibration`` is given). ``--calibration-only`` writes
just that file.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np

import rotor

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT / ".." / "shared" / "data"
OUT = ROOT / "benchmarks" / "results" / "diagnose_real.json"
CAL_OUT = ROOT / "rotor" / "presets" / "tue-single.calibration.json"
GAIN = 1e5 / (5 * 0.00385)  # Pa per volt, the data README (the bench's own scripts)
RECORDINGS = ("full_load", "half_load", "No_load")


def compare(engine, folder, cal, name, **kw):
    t0 = time.perf_counter()
    ident = rotor.diagnose(engine, folder / f"{name}.txt", cal, columns="time,-,encoder_v", **kw)
    wall = time.perf_counter() - t0
    pressure = rotor.analyze_log(
        folder / f"{name}.txt",
        "60-2",
        columns="time,pressure_v,encoder_v",
        tdc_deg=cal.tdc_after_gap_deg,
        tooth_errors=cal.tooth_errors,
    )
    if not np.allclose(pressure.t_start_s, ident.t_start_s, atol=1e-9):
        raise RuntimeError(f"{name}: the speed-only cycles are not the pressure's")
    meas = rotor.measured_imep(engine, pressure, cal.pressure_gain_pa)
    ident_imep = ident.imep_pa[:, 0]
    err = ident_imep - meas
    m = float(np.mean(meas))
    return {
        "cycles": int(ident.cycles),
        "measured_imep_bar": float(m / 1e5),
        "identified_imep_bar": float(np.mean(ident_imep) / 1e5),
        "error_mean_bar": float(np.mean(err) / 1e5),
        "error_rms_bar": float(np.sqrt(np.mean(err**2)) / 1e5),
        "error_max_bar": float(np.max(np.abs(err)) / 1e5),
        "error_mean_pct": float(100 * np.mean(err) / m),
        "error_rms_pct": float(100 * np.sqrt(np.mean(err**2)) / m),
        "cycle_to_cycle_correlation": float(np.corrcoef(ident_imep, meas)[0, 1]) if ident.cycles > 2 else None,
        "measured_std_bar": float(np.std(meas) / 1e5),
        "misfires": ident.misfires(),
        "charge_scale": float(ident.charge_scale),
        "identifications": int(ident.charge_iterations),
        "r2": float(ident.fit_r2),
        "wall_s": wall,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--calibration-only", action="store_true", help=f"write {CAL_OUT.name} only")
    args = ap.parse_args(argv)
    folder = args.data / "tue-4gb10"
    if not folder.is_dir():
        raise SystemExit(f"no data at {folder}")
    engine = rotor.load_engine("tue-single")
    results = {"gain_pa_per_v": GAIN, "calibrations": {}, "runs": {}}
    for cal_name in RECORDINGS:
        t0 = time.perf_counter()
        cal = rotor.calibrate(
            engine, folder / f"{cal_name}.txt", wheel="60-2", columns="time,pressure_v,encoder_v", pressure_gain=GAIN
        )
        cal_wall = time.perf_counter() - t0
        if cal_name == "full_load":
            here = "tue-4gb10/full_load.txt"  # not this machine's path
            te = None if cal.tooth_errors is None else dataclasses.replace(cal.tooth_errors, source=here)
            shipped = dataclasses.replace(cal, source=here, tooth_errors=te)
            shipped.save(CAL_OUT)
            print(f"wrote {CAL_OUT}", flush=True)
            if args.calibration_only:
                return
        d = cal.to_json_dict()
        d.pop("tooth_errors")
        d["wall_s"] = cal_wall
        results["calibrations"][cal_name] = d
        variants = {
            "default (charge scaling, load per block)": (cal, {}),
            "scaling none": (cal, {"scaling": "none"}),
            "load per cycle": (cal, {"load_per": "cycle"}),
        }
        if cal_name == "full_load":
            ebal = dataclasses.replace(cal, inertia_kgm2=cal.fit["energy_balance_inertia_kgm2"])
            variants["energy-balance inertia (no refinement)"] = (ebal, {})
        runs = {}
        for vname, (c, kw) in variants.items():
            runs[vname] = {name: compare(engine, folder, c, name, **kw) for name in RECORDINGS}
            print(
                f"calibrated on {cal_name:9s} {vname:42s} "
                + "  ".join(
                    f"{n}: {r['error_mean_bar']:+.3f} bar ({r['error_mean_pct']:+.1f} %), rms {r['error_rms_bar']:.3f}"
                    for n, r in runs[vname].items()
                ),
                flush=True,
            )
        results["runs"][cal_name] = runs
    args.out.write_text(json.dumps(results, indent=1) + "\n")
    print(f"wrote {args.out} and {CAL_OUT}")


if __name__ == "__main__":
    main()
