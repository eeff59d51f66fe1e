"""``rotor analyze``: a logged crank speed, cycle by cycle."""

from __future__ import annotations

import argparse
import os

from .args import add_edge, add_json, add_plot, positive_float, whole
from .output import plot_folder, print_json, print_text, print_written, save_plot

__all__ = ["add_parsers", "cmd_analyze", "log_plot"]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``analyze`` to the subcommands ``sub``."""
    p = sub.add_parser("analyze", help="logged crank speed: per-cycle mean speed, δ and orders from a wheel signal")
    p.add_argument("log", metavar="LOG", help="CSV/TSV log: tooth times, a sampled wheel signal, or time and rpm")
    p.add_argument(
        "--wheel",
        metavar="SPEC",
        help="trigger wheel: N-M (60-2, 36-1), N-g1-g2… (36-2-1, 36-2-2-2: N positions, the missing teeth of "
        "each gap; where they lie is found from the log), a wheel file (.toml), auto (found from the log), or "
        "N alone with an index_v column; angle 0 = the first tooth after gap 1",
    )
    p.add_argument(
        "--columns",
        metavar="NAMES",
        help="column names in file order: time, encoder_v, pressure_v, cam_v, index_v, encoder_d, cam_d "
        "(digital 0/1 channels, one row per transition), tooth_time_s, rpm, - (skip), e.g. "
        "time,pressure_v,encoder_v or time,encoder_d,-; a time in ms or µs: time_ms, time_us, tooth_time_ms, "
        "tooth_time_us; a logic analyser's Time[s], Channel 0, Channel 1 header reads as time,encoder_d,cam_d",
    )
    p.add_argument("--strokes", type=int, choices=(2, 4), default=4)
    p.add_argument(
        "--cylinders",
        type=whole,
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
        type=positive_float,
        metavar="R",
        help="for TDC from the pressure by a polytropic fit (with --rod-ratio)",
    )
    p.add_argument("--rod-ratio", type=positive_float, metavar="LAMBDA", help="crank radius / rod length")
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
    p.add_argument(
        "--max-order",
        type=positive_float,
        help="highest order reported and used for δ (default teeth/4; 0.5 or more for a four-stroke, 1 for a two-stroke)",
    )
    p.add_argument(
        "--points-per-cycle",
        type=whole,
        metavar="P",
        help="points of the uniform angle grid per cycle (default 2 per tooth pitch, more if --max-order needs them)",
    )
    p.add_argument(
        "--no-denoise",
        action="store_true",
        help="δ from all orders up to --max-order, not weighted by their signal-to-noise ratio",
    )
    add_edge(p)
    add_json(p)
    add_plot(p, "the combined plot")
    p.set_defaults(func=cmd_analyze)


def log_plot(drawn: object, folder: str, log: str, kind: str) -> str:
    """Save a plot of the log ``log`` as ``folder/<log stem>_<kind>.png``; the path."""
    plot_folder(folder)
    stem = os.path.splitext(os.path.basename(log))[0]
    return save_plot(drawn, folder, f"{stem}_{kind}.png")


def _engine_orders(text: str) -> str | tuple[int, ...]:
    from ..errors import LogError

    if text == "auto":
        return "auto"
    if text == "none":
        return ()
    try:
        return tuple(int(k) for k in text.split(","))
    except ValueError:
        raise LogError(f"--engine-orders {text!r}: auto, none, or whole orders such as 1,2,3") from None


def cmd_analyze(args: argparse.Namespace) -> None:
    """Analyse the log: its summary or JSON, the tooth errors and the plot if asked for."""
    from ..engine.file import load_engine
    from ..errors import LogError
    from ..logs.analysis import analyze_log

    if (args.compression_ratio is None) != (args.rod_ratio is None):
        raise LogError("--compression-ratio and --rod-ratio go together")
    res = analyze_log(
        args.log,
        args.wheel,
        columns=args.columns,
        strokes=args.strokes,
        cylinders=args.cylinders,
        tdc_deg=args.tdc_deg,
        firing=int(args.firing) if args.firing in ("0", "1") else args.firing,
        tooth_errors={"estimate": "estimate", "none": None}.get(args.tooth_errors, args.tooth_errors),
        engine_orders=_engine_orders(args.engine_orders),
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
        written.append(log_plot(res.plot(), args.plot, args.log, "analysis"))
    if args.json:
        print_json(res.to_json_dict(), indent=1)
    else:
        print_text(res.summary())
        print_written(written)
