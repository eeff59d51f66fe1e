"""``rotor diagnose``: per-cylinder IMEP, load and misfires of a recording from its crank speed."""

from __future__ import annotations

import argparse
import os
import sys

from .args import add_json, add_plot, positive_float
from .logs import log_plot
from .output import print_json, print_text, print_written

__all__ = ["add_parsers", "cmd_diagnose"]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``diagnose`` to the subcommands ``sub``."""
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
        type=positive_float,
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
        type=positive_float,
        default=0.5,
        help="misfire threshold of the contribution index (default 0.5)",
    )
    p.add_argument("--edge", choices=("rising", "falling"), default="rising", help="edges of an analog wheel signal")
    add_json(p)
    add_plot(p, "the diagnosis plot")
    p.set_defaults(func=cmd_diagnose)


def cmd_diagnose(args: argparse.Namespace) -> None:
    """Calibrate (``--save-calibration``) if asked, then diagnose the log with the calibration
    given, saved, the preset's own, or none."""
    from ..diagnostics.calibration import Calibration, calibrate, diagnose
    from ..engine.file import load_engine
    from ..errors import EngineError

    engine = load_engine(args.engine)
    cal, cal_source = None, None
    if args.calibration:
        cal, cal_source = Calibration.load(args.calibration), f"file {args.calibration}"
        cal.check_engine(engine, where=f"--calibration {args.calibration}")
    written = []
    if args.save_calibration:
        folder = os.path.dirname(os.path.abspath(args.save_calibration))
        if not os.path.isdir(folder):
            raise EngineError(f"--save-calibration {args.save_calibration}: no folder {folder}")
        new = calibrate(
            engine,
            args.log,
            wheel=args.wheel,
            columns=args.columns,
            pressure_gain=args.pressure_gain,
            edge=args.edge,
        )
        new.save(args.save_calibration)
        written.append(args.save_calibration)
        if cal is None:
            cal, cal_source = new, f"saved from this log to {args.save_calibration}"
    try:
        res = diagnose(
            engine,
            args.log,
            cal if cal is not None or args.no_calibration else "preset",  # the preset's own, if it ships one
            wheel=args.wheel,
            columns=args.columns,
            tdc_deg=args.tdc_deg,
            load_per=args.load_per,
            scaling=args.scaling,
            threshold=args.threshold,
            calibration_source=cal_source,
            edge=args.edge,
        )
    except ArithmeticError as e:  # a one-line error, not a traceback
        raise EngineError(f"{args.log}: the diagnosis failed ({e})") from None
    for w in res.warnings:  # on stderr too, where a pipe or --json would hide it
        print(f"rotor: warning: {args.log}: {w}", file=sys.stderr)
    if args.plot:
        written.append(log_plot(res.plot(), args.plot, args.log, "diagnosis"))
    if args.json:
        print_json(res.to_json_dict(written=written), indent=1)
    else:
        print_text(res.summary())
        print_written(written)
