"""The ``rotor`` command line: a thin layer over the library.

ENGINE is an engine file (TOML) or a preset name everywhere. Bad input exits with
code 2 and a one-line message on stderr; no traceback.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

from ..errors import SolverError

__all__ = ["main"]

EXIT_USAGE = 2
EXIT_SOLVER = 1


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, as for bad input
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def _positive_float(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (v > 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r} must be a positive number")
    return v


def _engine_arg(p):
    p.add_argument("engine", metavar="ENGINE", help="engine file (.toml) or preset name (see `rotor presets`)")
    p.add_argument("--rpm", type=_positive_float, help="crank speed [rev/min] (default: the file's [operating] rpm)")


def _nonnegative_float(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (v >= 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r} must be zero or positive")
    return v


_speed = _nonnegative_float  # a speed may be zero (from rest)


def _number_list(text, check, what):
    out = []
    for item in filter(None, (t.strip() for t in text.split(","))):
        try:
            out.append(check(item))
        except argparse.ArgumentTypeError as e:
            raise argparse.ArgumentTypeError(f"{text!r}: {e}; expected {what}") from None
    if not out:
        raise argparse.ArgumentTypeError(f"{text!r}: expected {what}")
    return out


def _speed_list(text):
    return _number_list(text, _positive_float, "speeds in rpm separated by commas, e.g. 800,1250,2000")


def _delta_list(text):
    return _number_list(text, _positive_float, "targets separated by commas, e.g. 0.01 or 0.03,0.01,0.005")


def _scale_list(text):
    return _number_list(text, _speed, "scales ≥ 0 separated by commas, e.g. 0.3,1,1")


def _whole(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be 1 or more")
    return v


def _dynamics_args(p):
    from ..dynamics.loads import LOAD_HELP

    p.add_argument("--load", default="none", metavar="SPEC", help=LOAD_HELP + " (default none)")
    p.add_argument(
        "--fidelity",
        choices=("variable", "series", "coefficients", "constant"),
        default="variable",
        help="inertia model: exact I(θ) (default), seed 003 coefficients, or constant + textbook torque",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="DIR", help="write plots to DIR")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _build_parser():
    parser = _Parser(prog="rotor", description="Rotational dynamics of piston engines.")
    parser.add_argument("--version", action="version", version=f"rotor {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="COMMAND")

    p = sub.add_parser("table", help="one-cylinder kinematic and dynamic table over the cycle (seed 004)")
    _engine_arg(p)
    p.add_argument("--step", type=_positive_float, default=10.0, help="angle step [deg] (default 10)")
    p.add_argument("--format", choices=("text", "csv"), default="text")
    p.add_argument(
        "--kinematics",
        choices=("series", "exact"),
        default="series",
        help="piston kinematics: the textbook lambda series (default, as in seed 004) or exact",
    )
    p.add_argument("--cylinder", type=int, default=1, help="cylinder number (default 1)")
    p.add_argument("--output", "-o", metavar="FILE", help="write to FILE instead of standard output")

    p = sub.add_parser("info", help="summary of an engine: geometry, IMEP, power, torque range, inertia")
    _engine_arg(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")

    p = sub.add_parser("plot", help="plots of kinematics, forces, total torque and inertia to a folder")
    _engine_arg(p)
    p.add_argument("--out", default="out", metavar="DIR", help="output folder (default out/)")

    p = sub.add_parser("steady", help="periodic steady state over one cycle: δ, speed and torque orders")
    _engine_arg(p)
    _dynamics_args(p)
    p.add_argument("--method", choices=("auto", "closed", "shooting"), default="auto")

    p = sub.add_parser("simulate", help="transient run over many cycles (load steps, misfires, stall, start)")
    p.add_argument("engine", metavar="ENGINE", help="engine file (.toml) or preset name (see `rotor presets`)")
    p.add_argument("--rpm", type=_speed, help="start speed [rev/min], 0 = from rest (default: [operating] rpm)")
    p.add_argument("--cycles", type=_whole, default=10, help="number of cycles (default 10)")
    _dynamics_args(p)
    p.add_argument("--method", choices=("auto", "closed", "grid", "angle", "time"), default="auto")
    p.add_argument("--rtol", type=_positive_float, help="relative tolerance of the adaptive solvers (default 1e-9)")
    p.add_argument("--steps-per-cycle", type=_whole, help="RK4 steps per cycle of --method grid (default 2 per degree)")
    p.add_argument(
        "--misfire",
        metavar="CYCLE:CYL,...",
        default="",
        help="misfiring firings, e.g. 3:1,7:2 (cycle from 0, cylinder from 1)",
    )
    p.add_argument("--governor", type=_positive_float, metavar="RPM", help="PI speed governor set to RPM")

    p = sub.add_parser("analyze", help="logged crank speed: per-cycle mean speed, δ and orders from a wheel signal")
    p.add_argument("log", metavar="LOG", help="CSV/TSV log: tooth times, a sampled wheel signal, or time and rpm")
    p.add_argument(
        "--wheel", metavar="N-M", help="trigger wheel, e.g. 60-2, 36-1, 36-2 (N alone: with an index_v column)"
    )
    p.add_argument(
        "--columns",
        metavar="NAMES",
        help="column names in file order: time, encoder_v, pressure_v, cam_v, index_v, tooth_time_s, rpm, "
        "- (skip), e.g. time,pressure_v,encoder_v",
    )
    p.add_argument("--strokes", type=int, choices=(2, 4), default=4)
    p.add_argument(
        "--cylinders",
        type=_whole,
        default=1,
        metavar="N",
        help="cylinders of the (evenly firing) engine, default 1: a tooth-error estimate from the log "
        "leaves the multiples of the firing order to the engine",
    )
    p.add_argument(
        "--tdc-deg",
        type=float,
        metavar="DEG",
        help="angle from the gap to TDC of cylinder 1 [deg] (default: from the pressure channel, else 0)",
    )
    p.add_argument(
        "--firing",
        default="auto",
        choices=("auto", "pressure", "cam", "speed", "0", "1"),
        help="which revolution fires (4-stroke; default auto: pressure, cam, else speed)",
    )
    p.add_argument(
        "--compression-ratio",
        type=_positive_float,
        metavar="R",
        help="for TDC from the pressure by a polytropic fit (with --rod-ratio)",
    )
    p.add_argument("--rod-ratio", type=_positive_float, metavar="LAMBDA", help="crank radius / rod length")
    p.add_argument(
        "--tooth-errors",
        default="estimate",
        metavar="estimate|none|FILE",
        help="tooth-spacing correction: estimate from this log (default), none, or a JSON file",
    )
    p.add_argument(
        "--engine-orders",
        default="auto",
        metavar="auto|none|K,K",
        help="orders of the per-revolution pattern left to the engine when estimating (default auto)",
    )
    p.add_argument(
        "--engine",
        metavar="ENGINE",
        help="engine file or preset on the wheel: its inertia ripple is taken "
        "out of the tooth-error estimate (needs --tdc-deg), so its own fuel-cut coast-down calibrates the "
        "wheel",
    )
    p.add_argument("--save-tooth-errors", metavar="FILE", help="write the tooth errors applied as JSON")
    p.add_argument("--max-order", type=_positive_float, help="highest order reported and used for δ (default teeth/4)")
    p.add_argument(
        "--points-per-cycle",
        type=_whole,
        metavar="P",
        help="points of the uniform angle grid per cycle (default 2 per tooth pitch, more if --max-order needs them)",
    )
    p.add_argument(
        "--no-denoise",
        action="store_true",
        help="δ from all orders up to --max-order, not weighted by their signal-to-noise ratio",
    )
    p.add_argument("--edge", choices=("rising", "falling"), default="rising", help="edges of an analog wheel signal")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="DIR", help="write the combined plot to DIR")

    p = sub.add_parser("diagnose", help="per-cylinder IMEP, load and misfires of a recording from its crank speed")
    p.add_argument(
        "log",
        metavar="LOG",
        help="CSV/TSV log: a sampled wheel signal or tooth times (a pressure channel "
        "is optional: used for --save-calibration and compared with when a calibration is given)",
    )
    p.add_argument("--engine", required=True, metavar="ENGINE", help="engine file (.toml) or preset name")
    p.add_argument("--wheel", metavar="N-M", help="trigger wheel, e.g. 60-2 (default: the calibration's)")
    p.add_argument(
        "--columns",
        metavar="NAMES",
        help="column names in file order, as for analyze; - skips a column (time,-,encoder_v: speed only)",
    )
    p.add_argument(
        "--calibration",
        metavar="FILE",
        help="a saved calibration (inertia, TDC, tooth errors, pressure "
        "scale) to use (default: the preset's own where it ships one, e.g. tue-single; a calibration of "
        "another engine is refused)",
    )
    p.add_argument(
        "--no-calibration", action="store_true", help="not even the preset's own calibration: the engine file as it is"
    )
    p.add_argument(
        "--save-calibration",
        metavar="FILE",
        help="calibrate from this log's pressure channel, write the "
        "calibration as JSON and use it (unless --calibration is given)",
    )
    p.add_argument(
        "--pressure-gain",
        type=_positive_float,
        metavar="PA_PER_UNIT",
        help="pressure sensor gain for --save-calibration [Pa per signal unit] (default: the gain "
        "that gives the log's mean IMEP the engine file's)",
    )
    p.add_argument(
        "--tdc-deg",
        type=float,
        metavar="DEG",
        help="angle from the gap to TDC of cylinder 1 [deg] "
        "(default: the calibration's, else from the pressure channel)",
    )
    p.add_argument(
        "--load-per",
        choices=("block", "cycle"),
        default="block",
        help="an unknown load torque per block of cycles (default: a steady load) or per cycle",
    )
    p.add_argument(
        "--scaling",
        choices=("charge", "none"),
        help="scale the engine file's whole cycle with the load (charge: SI) or only its combustion (none); "
        "default: the calibration's, else none",
    )
    p.add_argument(
        "--threshold",
        type=_positive_float,
        default=0.5,
        help="misfire threshold of the contribution index (default 0.5)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="DIR", help="write the diagnosis plot to DIR")

    p = sub.add_parser(
        "flywheel",
        help="the smallest flywheel keeping δ ≤ --delta at every operating point, "
        "against the textbook (seed 004 §3.2.12)",
    )
    p.add_argument("engine", metavar="ENGINE", help="engine file (.toml) or preset name (see `rotor presets`)")
    p.add_argument(
        "--delta",
        type=_delta_list,
        required=True,
        metavar="D,...",
        help="target irregularity δ = (ω_max − ω_min)/ω_mean, e.g. 0.01; one for all or one per --rpm "
        "(e.g. 0.03,0.01,0.005: looser at idle)",
    )
    p.add_argument(
        "--rpm",
        type=_speed_list,
        metavar="RPM,...",
        help="operating speeds [rev/min], e.g. 800,1250,2000 (default: the file's [operating] rpm)",
    )
    p.add_argument(
        "--imep-scale",
        type=_scale_list,
        default=[1.0],
        metavar="S,...",
        help="fuelling of each operating point (combustion scale, 1 = the engine file's), one for all or "
        "one per --rpm, e.g. 0.3,1,1 for idle to rated (default 1)",
    )
    p.add_argument(
        "--load",
        default="none",
        metavar="SPEC",
        help="load at every point: none (default: the load balances the engine), or a speed-dependent "
        "load such as propeller:TORQUE_NM,RPM (that torque at that speed, ∝ speed²; the fuelling is "
        "then scaled to carry it)",
    )
    p.add_argument(
        "--max-rpm",
        type=_positive_float,
        metavar="RPM",
        help="highest crank speed the flywheel must stand, for --max-rim-speed (default: the larger of the "
        "file's [operating] rpm and the highest speed at the points)",
    )
    p.add_argument(
        "--shaft-inertia",
        type=_nonnegative_float,
        default=0.0,
        metavar="KGM2",
        help="the crankshaft's own inertia without the flywheel [kg·m²] (default 0)",
    )
    p.add_argument("--max-diameter", type=_positive_float, metavar="M", help="outer diameter limit of the disc [m]")
    p.add_argument("--max-width", type=_positive_float, metavar="M", help="width limit of the disc [m]")
    p.add_argument("--max-rim-speed", type=_positive_float, metavar="M_S", help="rim speed limit [m/s]")
    p.add_argument(
        "--density",
        type=_positive_float,
        default=7200.0,
        metavar="KG_M3",
        help="flywheel material density [kg/m³] (default 7200, cast iron)",
    )
    p.add_argument("--bore", type=_nonnegative_float, default=0.0, metavar="M", help="bore of the disc [m] (default 0)")
    p.add_argument(
        "--fidelity",
        choices=("variable", "series", "coefficients", "constant"),
        default="variable",
        help="inertia model of the steady state (default variable: the exact I(θ))",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="DIR", help="write the design plot to DIR")

    sub.add_parser("presets", help="list the built-in engines")

    p = sub.add_parser("demo", help="summary, steady state, a load step and plots of the default preset (4chn15)")
    p.add_argument("--engine", default="4chn15", metavar="ENGINE")
    p.add_argument("--out", default="out", metavar="DIR", help="output folder (default out/)")
    return parser


def _version():
    from .. import __version__

    return __version__


def _cmd_table(args):
    import rotor

    from ..fileio import write_text_atomic

    engine = rotor.load_engine(args.engine)
    table = rotor.crank_table(
        engine, rpm=args.rpm, step_deg=args.step, kinematics=args.kinematics, cylinder=args.cylinder
    )
    text = table.to_csv() if args.format == "csv" else table.to_text()
    if args.output:
        write_text_atomic(args.output, text)
    else:
        sys.stdout.write(text)


def _cmd_info(args):
    import rotor

    from ..engine.summary import format_summary

    engine = rotor.load_engine(args.engine)
    summary = rotor.engine_summary(engine, rpm=args.rpm)
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        sys.stdout.write(format_summary(summary))


def _write_plots(engine, rpm, out):
    import matplotlib

    matplotlib.use("Agg")
    import rotor

    from ..plotting import plot_inertia, plot_torque, save_figure

    os.makedirs(out, exist_ok=True)
    table = rotor.crank_table(engine, rpm=rpm, step_deg=2.0, kinematics="exact")
    written = []
    for name, draw in (
        ("kinematics.png", lambda: table.plot("kinematics")),
        ("forces.png", lambda: table.plot("forces")),
        ("torque.png", lambda: plot_torque(engine, rpm)),
        ("inertia.png", lambda: plot_inertia(engine)),
    ):
        path = os.path.join(out, name)
        save_figure(draw(), path)
        written.append(path)
    return written


def _cmd_plot(args):
    import rotor

    engine = rotor.load_engine(args.engine)
    for path in _write_plots(engine, args.rpm, args.out):
        print(f"wrote {path}")


def _format_result(res) -> str:
    s = res.summary()
    lines = [
        f"{s['engine']}: {s['kind']} run, method {s['method']}, {s['fidelity']} inertia",
        f"  mean speed      {s['mean_rpm']:10.2f} rpm   (min {s['min_rpm']:.2f}, max {s['max_rpm']:.2f})",
    ]
    if s["delta"] is not None:
        lines.append(f"  irregularity δ  {s['delta']:10.5f}      (1/δ = {1 / s['delta']:.1f})")
    if "textbook_delta" in s:
        lines.append(
            f"  textbook δ      {s['textbook_delta']:10.5f}      (seed 004: L_excess / (J·ω²), "
            f"L_excess = {s['excess_work_J']:.1f} J)"
        )
    if "load_torque_Nm" in s:
        lines.append(f"  load torque     {s['load_torque_Nm']:10.2f} N·m (balances the mean engine torque)")
    if "fuel_scale" in s:
        lines.append(f"  fuel scale      {s['fuel_scale']:10.4f}      (carries the load)")
    if s["stalled"]:
        lines.append(f"  STALLED at t = {s['stall_time_s']:.4f} s, crank angle {s['stall_angle_deg']:.1f}°")
    if res.info.get("incomplete"):
        lines.append(f"  note: {res.info['incomplete']}")
    if s["orders"]:
        lines.append("  order  speed amplitude [rad/s]  torque amplitude [N·m]")
        for o in s["orders"]:
            lines.append(f"  {o['order']:5.1f}  {o['speed_amplitude_rad_s']:24.5f}  {o['torque_amplitude_Nm']:22.2f}")
    lines.append(f"  wall time {s['wall_s']:.3f} s")
    return "\n".join(lines) + "\n"


def _plot_result(res, out, prefix):
    import matplotlib

    matplotlib.use("Agg")
    from ..plotting import save_figure

    os.makedirs(out, exist_ok=True)
    written = []
    kinds = ("cycle", "time", "torque", "orders") if res.uniform_cycles else ("time",)
    for kind in kinds:
        if res.kind == "steady" and kind == "time":
            continue
        path = os.path.join(out, f"{prefix}_{kind}.png")
        save_figure(res.plot(kind=kind), path)
        written.append(path)
    return written


def _report(res, args, prefix):
    if args.json:
        print(json.dumps(res.summary(), indent=2))
    else:
        sys.stdout.write(_format_result(res))
    if args.plot:
        paths = _plot_result(res, args.plot, prefix)
        if not args.json:
            for p in paths:
                print(f"wrote {p}")


def _cmd_steady(args):
    import rotor

    engine = rotor.load_engine(args.engine)
    res = rotor.steady_state(
        engine, rpm=args.rpm, load=rotor.parse_load(args.load), fidelity=args.fidelity, method=args.method
    )
    _report(res, args, "steady")


def _parse_misfires(text):
    from ..errors import EngineError

    pairs = []
    for item in filter(None, (t.strip() for t in text.split(","))):
        try:
            k, c = item.split(":")
            pairs.append((int(k), int(c)))
        except ValueError:
            raise EngineError(f"--misfire {text!r}: expected CYCLE:CYLINDER pairs such as 3:1,7:2") from None
    return pairs


def _cmd_simulate(args):
    import rotor

    engine = rotor.load_engine(args.engine)
    pairs = _parse_misfires(args.misfire)
    combustion = rotor.combustion_pattern(args.cycles, engine.cylinders, misfires=pairs) if pairs else None
    governor = rotor.Governor(args.governor) if args.governor else None
    progress = False if (args.json or args.quiet) else None
    res = rotor.simulate(
        engine,
        rpm=args.rpm,
        cycles=args.cycles,
        load=rotor.parse_load(args.load),
        method=args.method,
        fidelity=args.fidelity,
        rtol=args.rtol,
        combustion=combustion,
        steps_per_cycle=args.steps_per_cycle,
        governor=governor,
        progress=progress,
    )
    _report(res, args, "simulate")


def _plot_log(make_figure, args, kind):
    """Write ``make_figure()`` to DIR/<log stem>_<kind>.png (``--plot DIR``); the path."""
    import matplotlib

    matplotlib.use("Agg")
    from ..plotting import save_figure

    os.makedirs(args.plot, exist_ok=True)
    stem = os.path.splitext(os.path.basename(args.log))[0]
    path = os.path.join(args.plot, f"{stem}_{kind}.png")
    save_figure(make_figure(), path)
    return path


def _cmd_analyze(args):
    from ..engine.file import load_engine
    from ..errors import LogError
    from ..logs.analysis import analyze_log

    if args.engine_orders == "auto":
        eo = "auto"
    elif args.engine_orders == "none":
        eo = ()
    else:
        try:
            eo = tuple(int(k) for k in args.engine_orders.split(","))
        except ValueError:
            raise LogError(
                f"--engine-orders {args.engine_orders!r}: auto, none, or whole orders such as 1,2,3"
            ) from None
    te = {"estimate": "estimate", "none": None}.get(args.tooth_errors, args.tooth_errors)
    firing = int(args.firing) if args.firing in ("0", "1") else args.firing
    if (args.compression_ratio is None) != (args.rod_ratio is None):
        raise LogError("--compression-ratio and --rod-ratio go together")
    res = analyze_log(
        args.log,
        args.wheel,
        columns=args.columns,
        strokes=args.strokes,
        cylinders=args.cylinders,
        tdc_deg=args.tdc_deg,
        firing=firing,
        tooth_errors=te,
        engine_orders=eo,
        max_order=args.max_order,
        points_per_cycle=args.points_per_cycle,
        edge=args.edge,
        compression_ratio=args.compression_ratio,
        rod_ratio=args.rod_ratio,
        denoise=not args.no_denoise,
        engine=load_engine(args.engine) if args.engine else None,
    )
    written = []
    if args.save_tooth_errors:
        if res.tooth_errors is None:
            raise LogError("--save-tooth-errors: no tooth errors were applied (--tooth-errors none, or a speed log)")
        res.tooth_errors.save(args.save_tooth_errors)
        written.append(args.save_tooth_errors)
    if args.plot:
        written.append(_plot_log(res.plot, args, "analysis"))
    if args.json:
        print(json.dumps(res.to_json_dict(), indent=1, allow_nan=False))  # never NaN: not JSON
    else:
        sys.stdout.write(res.summary())
        for p in written:
            print(f"wrote {p}")


def _cmd_flywheel(args):
    import rotor

    from ..design.flywheel import OperatingPoint, design_flywheel

    engine = rotor.load_engine(args.engine)
    rpms = args.rpm if args.rpm else [float(engine.operating.rpm)]

    def per_point(values, option):
        if len(values) not in (1, len(rpms)):
            raise rotor.EngineError(
                f"{option} gives {len(values)} values for {len(rpms)} speeds: give one for all or one per --rpm"
            )
        return values * len(rpms) if len(values) == 1 else values

    scales, deltas = per_point(args.imep_scale, "--imep-scale"), per_point(args.delta, "--delta")
    load = rotor.parse_load(args.load)
    points = [OperatingPoint(r, s, load, d) for r, s, d in zip(rpms, scales, deltas)]
    design = design_flywheel(
        engine,
        None,
        points,
        shaft_inertia_kgm2=args.shaft_inertia,
        density_kg_m3=args.density,
        bore_m=args.bore,
        max_outer_diameter_m=args.max_diameter,
        max_width_m=args.max_width,
        max_rim_speed_m_s=args.max_rim_speed,
        max_rpm=args.max_rpm,
        fidelity=args.fidelity,
    )
    written = []
    if args.plot:
        from ..plotting import plot_flywheel_design, save_figure

        os.makedirs(args.plot, exist_ok=True)
        path = os.path.join(args.plot, "flywheel.png")
        save_figure(plot_flywheel_design(design, engine), path)
        written.append(path)
    if args.json:
        d = design.to_dict()
        d["plots"] = written
        print(json.dumps(d, indent=2))
        return
    print(design.report())
    for p in written:
        print(f"wrote {p}")


def _cmd_diagnose(args):
    import numpy as np

    import rotor

    from ..diagnostics.calibration import Calibration, calibrate, diagnose, measured_imep

    engine = rotor.load_engine(args.engine)
    cal = Calibration.load(args.calibration) if args.calibration else None
    cal_source = f"file {args.calibration}" if args.calibration else None
    if cal is not None:
        cal.check_engine(engine, where=f"--calibration {args.calibration}")
    written = []
    if args.save_calibration:
        folder = os.path.dirname(os.path.abspath(args.save_calibration))
        if not os.path.isdir(folder):
            raise rotor.EngineError(f"--save-calibration {args.save_calibration}: no folder {folder}")
        new = calibrate(engine, args.log, wheel=args.wheel, columns=args.columns, pressure_gain=args.pressure_gain)
        new.save(args.save_calibration)
        written.append(args.save_calibration)
        if cal is None:
            cal, cal_source = new, f"saved from this log to {args.save_calibration}"
    try:
        use = cal if cal is not None or args.no_calibration else "preset"  # the preset's own, if it ships one
        ident = diagnose(
            engine,
            args.log,
            use,
            wheel=args.wheel,
            columns=args.columns,
            tdc_deg=args.tdc_deg,
            load_per=args.load_per,
            scaling=args.scaling,
            threshold=args.threshold,
        )
    except ArithmeticError as e:  # a one-line error, not a traceback
        raise rotor.EngineError(f"{args.log}: the diagnosis failed ({e})") from None
    if cal is None and ident.info.get("calibration") is not None:  # the preset's own
        cal = Calibration.from_json_dict(ident.info["calibration"])
        cal_source = ident.info.get("calibration_source")
    analysis = ident.info.get("analysis")
    measured = None
    if cal is not None and analysis is not None and analysis.pressure is not None and engine.cylinders == 1:
        measured = measured_imep(engine, analysis, cal.pressure_gain_pa)
    if args.plot:
        written.append(_plot_log(ident.plot, args, "diagnosis"))
    if args.json:

        def num(x):
            x = float(x)
            return x if np.isfinite(x) else None

        t0 = ident.t_start_s
        cycles = []
        for k in range(ident.cycles):
            row = {
                "t_start_s": None if t0 is None else num(t0[k]),
                "mean_rpm": num(ident.mean_omega[k] * 30 / np.pi),
                "imep_pa": [num(v) for v in ident.imep_pa[k]],
                "imep_std_pa": [num(v) for v in ident.imep_std_pa[k]],
                "misfire": [bool(v) for v in ident.misfire[k]],
                "contribution": [num(v) for v in ident.contribution[k]],
                "load_torque_Nm": num(ident.load_torque_Nm[k]),
            }
            if measured is not None:
                row["measured_imep_pa"] = [num(measured[k])]
            cycles.append(row)
        out = {
            "engine": ident.engine_name,
            "source": analysis.source if analysis is not None else args.log,
            "cylinders": ident.cylinders,
            "cycles": cycles,
            "misfires": ident.misfires(),
            "calibration": None if cal is None else {**cal.to_json_dict(), "loaded_from": cal_source},
            "calibration_source": cal_source,
            "ambiguous_pairs": [list(p) for p in ident.ambiguous_pairs],
            "scaling": ident.info.get("scaling"),
            "charge_scale": num(ident.info.get("charge_scale", 1.0)),
            "tdc_after_gap_deg": None if analysis is None else num(np.rad2deg(analysis.tdc_rad)),
            "tdc_method": None if analysis is None else analysis.tdc_method,
            "firing_method": None if analysis is None else analysis.firing_method,
            "rms_residual_rad_s": num(ident.rms_residual),
            "r2": num(ident.fit_r2),
            "threshold": ident.threshold,
            "notes": list(ident.notes) + (list(analysis.notes) if analysis else []),
            "written": written,
        }
        print(json.dumps(out, indent=1, allow_nan=False))
    else:
        if cal is not None:
            sys.stdout.write(cal.summary())
            print(f"  calibration: {cal_source}")
        sys.stdout.write(ident.summary())
        if measured is not None:
            err = ident.imep_pa[:, 0] - measured
            print(
                f"  IMEP from the pressure channel {np.mean(measured) / 1e5:.3f} bar; identified − measured: mean "
                f"{np.mean(err) / 1e5:+.3f} bar, rms {np.sqrt(np.mean(err**2)) / 1e5:.3f} bar"
            )
        for p in written:
            print(f"wrote {p}")


def _cmd_presets(args):
    import rotor

    for name in rotor.preset_names():
        print(f"{name:12s} {rotor.load_engine(name).name}")


def _cmd_demo(args):
    import rotor

    from ..engine.summary import format_summary

    engine = rotor.load_engine(args.engine)
    sys.stdout.write(format_summary(rotor.engine_summary(engine)))
    print()
    steady = rotor.steady_state(engine)
    sys.stdout.write(_format_result(steady))
    print()
    # a transient: the load steps up by 20 % half a second in, a PI governor holds the speed
    load = float(steady.info["load_torque_Nm"])
    step = rotor.LoadStep(rotor.ConstantLoad(load), rotor.ConstantLoad(1.2 * load), time_s=0.5)
    rpm0 = float(steady.omega[0]) * 30 / 3.141592653589793
    trans = rotor.simulate(engine, rpm=rpm0, cycles=40, load=step, governor=rotor.Governor(float(steady.mean_rpm)))
    print(f"load step {load:.0f} -> {1.2 * load:.0f} N·m at t = 0.5 s, PI governor:")
    sys.stdout.write(_format_result(trans))
    print()
    # the flywheel for δ ≤ 0.01 at rated speed and ≤ 0.03 at a part-load idle, against the textbook
    from ..design.flywheel import OperatingPoint
    from ..plotting import plot_flywheel_design, save_figure

    rpm = float(engine.operating.rpm)
    design = rotor.design_flywheel(engine, 0.01, [OperatingPoint(0.5 * rpm, 0.3, None, 0.03), rpm])
    print(design.report())
    print()
    os.makedirs(args.out, exist_ok=True)
    fly = os.path.join(args.out, "flywheel.png")
    save_figure(plot_flywheel_design(design, engine), fly)
    for path in (
        _write_plots(engine, None, args.out)
        + _plot_result(steady, args.out, "steady")
        + _plot_result(trans, args.out, "load_step")
        + [fly]
    ):
        print(f"wrote {path}")


_COMMANDS = {
    "table": _cmd_table,
    "info": _cmd_info,
    "plot": _cmd_plot,
    "steady": _cmd_steady,
    "simulate": _cmd_simulate,
    "analyze": _cmd_analyze,
    "diagnose": _cmd_diagnose,
    "flywheel": _cmd_flywheel,
    "presets": _cmd_presets,
    "demo": _cmd_demo,
}


def _analyze_argv(argv):
    """``analyze`` / ``diagnose --columns -,encoder_v,time``: argparse takes a value that starts with '-'
    for an option; joined as ``--columns=-,encoder_v,time`` it is a value."""
    if "analyze" not in argv and "diagnose" not in argv:
        return argv
    out = list(argv)
    for i in range(len(out) - 1):
        if out[i] == "--columns" and out[i + 1].startswith("-") and out[i + 1] not in ("-h", "--help"):
            out[i : i + 2] = [f"--columns={out[i + 1]}", None]
    return [a for a in out if a is not None]


def main(argv=None) -> int:
    """Entry point of the ``rotor`` command."""
    parser = _build_parser()
    args = parser.parse_args(_analyze_argv(sys.argv[1:] if argv is None else list(argv)))
    try:
        _COMMANDS[args.command](args)
    except BrokenPipeError:  # e.g. `rotor table ... | head`
        return 0
    except SolverError as e:  # valid input, no answer: not a usage error
        print(f"rotor: {str(e).replace(chr(10), ' ')}", file=sys.stderr)
        return EXIT_SOLVER
    except (ValueError, OSError) as e:  # EngineError is a ValueError
        msg = str(e).replace("\n", " ")
        if isinstance(e, OSError) and e.filename:
            msg = f"{e.filename}: {e.strerror}"
        print(f"rotor: error: {msg}", file=sys.stderr)
        return EXIT_USAGE
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
