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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--out", type=Path, default=OUT)
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
        "tue-4gb10": tue_matrix(folder),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(rotor.results.json_safe(results), indent=1) + "\n")
    print(json.dumps(results["tue-4gb10"]["done_when"], indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
