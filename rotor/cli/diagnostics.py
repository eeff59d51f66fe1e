"""``rotor diagnose``: per-cylinder IMEP, load and misfires of a recording from its crank speed."""

from __future__ import annotations

import argparse
import os
from typing import Any

from .args import add_edge, add_json, add_plot, angle_deg, positive_float
from .logs import BULK_HELP, PLOT_LOCK, FileOutput, add_bulk, for_each_log, log_plot
from .output import print_json, print_text, print_written

__all__ = ["add_parsers", "cmd_diagnose", "cmd_calibrate"]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``diagnose`` and ``calibrate`` to the subcommands ``sub``."""
    p = sub.add_parser("diagnose", help="per-cylinder IMEP, load and misfires of a recording from its crank speed")
    p.add_argument(
        "log",
        metavar="LOG",
        nargs="+",
        help="CSV/TSV log: a sampled wheel signal or tooth times (a pressure channel "
        "is optional: used for --save-calibration and compared with when a calibration is given)" + BULK_HELP,
    )
    p.add_argument("--engine", required=True, metavar="ENGINE", help="engine file (.toml) or preset name")
    p.add_argument("--wheel", metavar="N-M", help="trigger wheel, e.g. 60-2 (default: the calibration's)")
    p.add_argument(
        "--columns",
        "--channel",
        metavar="NAMES",
        help="column names in file order, or the file's channels by role (time=t,crank=CRANK), as for analyze; "
        "- skips a column (time,-,encoder_v: speed only)",
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
    _add_pressure_scale(p, "for --save-calibration ")
    p.add_argument(
        "--tdc-deg",
        type=_tdc_arg,
        metavar="DEG|speed",
        help="angle from the gap to TDC of cylinder 1 [deg], or 'speed': found from the speed alone "
        "(default: the calibration's, checked against the speed and corrected where the speed contradicts "
        "it; else from the pressure channel)",
    )
    p.add_argument(
        "--no-tdc-check",
        action="store_true",
        help="use the calibration's TDC as it is, without checking it against the recording's speed",
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
    add_edge(p)
    add_json(p)
    add_plot(p, "the diagnosis plot")
    add_bulk(p)
    p.set_defaults(func=cmd_diagnose)
    _add_calibrate(sub)


def _tdc_arg(text: str) -> float | str:
    """``--tdc-deg``: an angle [deg] or ``speed``."""
    if text.strip().lower() == "speed":
        return "speed"
    try:
        return angle_deg(text)
    except argparse.ArgumentTypeError as e:
        raise argparse.ArgumentTypeError(f"{e}, or 'speed'") from None


def _gain_arg(text: str) -> float | str:
    """``--pressure-gain``: a positive number [Pa per signal unit] or ``motored``."""
    if text.strip().lower() == "motored":
        return "motored"
    try:
        return positive_float(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"{text!r}: a positive gain [Pa per signal unit] or 'motored'") from None


def cmd_diagnose(args: argparse.Namespace) -> None:
    """Calibrate (``--save-calibration``, one LOG) if asked, then diagnose the log (or each of
    several) with the calibration given, saved, the preset's own, or none."""
    _calibration(args)  # a bad engine or calibration is the command's error, not each file's
    for_each_log(args, diagnose_file, "diagnosing", one_only=("save_calibration",))


def _calibration(args: argparse.Namespace) -> tuple[Any, Any, str | None]:
    """The engine of ``--engine`` and the calibration of ``--calibration`` (checked against
    it) with where it came from."""
    from ..diagnostics.calibration_record import Calibration
    from ..engine.file import load_engine

    engine = load_engine(args.engine)
    cal, cal_source = None, None
    if args.calibration:
        cal, cal_source = Calibration.load(args.calibration), f"file {args.calibration}"
        cal.check_engine(engine, where=f"--calibration {args.calibration}")
    return engine, cal, cal_source


def diagnose_file(args: argparse.Namespace, log: str) -> FileOutput:
    """``rotor diagnose`` of the one file ``log`` with the options ``args``: what it prints and writes."""
    from ..diagnostics.calibration import calibrate
    from ..diagnostics.diagnosis import diagnose
    from ..errors import EngineError

    engine, cal, cal_source = _calibration(args)
    written = []
    if args.save_calibration:
        folder = os.path.dirname(os.path.abspath(args.save_calibration))
        if not os.path.isdir(folder):
            raise EngineError(f"--save-calibration {args.save_calibration}: no folder {folder}")
        new = calibrate(
            engine,
            log,
            wheel=args.wheel,
            columns=args.columns,
            pressure_gain=args.pressure_gain,
            intake_pa=args.intake_pa,
            edge=args.edge,
        )
        new.save(args.save_calibration)
        written.append(args.save_calibration)
        if cal is None:
            cal, cal_source = new, f"saved from this log to {args.save_calibration}"
    try:
        res = diagnose(
            engine,
            log,
            cal if cal is not None or args.no_calibration else "preset",  # the preset's own, if it ships one
            wheel=args.wheel,
            columns=args.columns,
            tdc_deg=args.tdc_deg,
            load_per=args.load_per,
            scaling=args.scaling,
            threshold=args.threshold,
            calibration_source=cal_source,
            edge=args.edge,
            check_tdc=not args.no_tdc_check,
        )
    except ArithmeticError as e:  # a one-line error, not a traceback
        raise EngineError(f"{log}: the diagnosis failed ({e})") from None
    if args.plot:
        with PLOT_LOCK:
            written.append(log_plot(res.plot(), args.plot, log, "diagnosis"))
    if args.json:
        return FileOutput(res.to_json_dict(written=written), "", written, list(res.warnings))
    return FileOutput({}, res.summary(), written, list(res.warnings))


def _add_pressure_scale(p: argparse.ArgumentParser, use: str = "") -> None:
    """``--pressure-gain`` and ``--intake-pa`` of a calibration (``use``: what the gain is for)."""
    p.add_argument(
        "--pressure-gain",
        type=_gain_arg,
        metavar="PA_PER_UNIT|motored",
        help=f"pressure sensor gain {use}[Pa per signal unit], or 'motored': from the log's motored cycles (their "
        "compression polytropic, pegged at the intake pressure; refused without any). Default: from the "
        "motored cycles where the log has some, else left unknown: the gain that gives the log's mean IMEP "
        "the engine file's (TDC, tooth errors and the inertia that reproduces that IMEP are calibrated all "
        "the same)",
    )
    p.add_argument(
        "--intake-pa",
        type=positive_float,
        metavar="PA",
        help="intake pressure of the motored cycles [Pa] for a gain from them (default: the engine file's intake_pa)",
    )


def _add_calibrate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "calibrate",
        help="inertia, TDC, tooth errors and the pressure sensor's offset of an installation, from a log with pressure",
    )
    p.add_argument(
        "log",
        metavar="LOG",
        nargs="+",
        help="CSV/TSV log with a wheel signal (or tooth times) and a pressure channel; several logs of one "
        "installation (other loads or speeds) make one calibration that states what they cover",
    )
    p.add_argument("--engine", required=True, metavar="ENGINE", help="engine file (.toml) or preset name")
    p.add_argument("--wheel", metavar="SPEC", help="trigger wheel, e.g. 60-2")
    p.add_argument("--columns", "--channel", metavar="NAMES", help="column names in file order, as for analyze")
    _add_pressure_scale(p)
    p.add_argument(
        "--scaling",
        choices=("charge", "none"),
        default="charge",
        help="scale the engine file's whole cycle with the load (charge: SI, default) or only its combustion",
    )
    p.add_argument("--output", "-o", metavar="FILE", help="write the calibration as JSON (for --calibration)")
    add_edge(p)
    add_json(p)
    add_plot(p, "the calibration plot")
    p.set_defaults(func=cmd_calibrate)


def cmd_calibrate(args: argparse.Namespace) -> None:
    """Calibrate from the log's pressure channel; print (text or JSON) and write it if asked."""
    from ..diagnostics.calibration import calibrate
    from ..engine.file import load_engine
    from ..errors import EngineError

    engine = load_engine(args.engine)
    if args.output:
        folder = os.path.dirname(os.path.abspath(args.output))
        if not os.path.isdir(folder):
            raise EngineError(f"--output {args.output}: no folder {folder}")
    try:
        cal = calibrate(
            engine,
            args.log[0] if len(args.log) == 1 else list(args.log),
            wheel=args.wheel,
            columns=args.columns,
            pressure_gain=args.pressure_gain,
            intake_pa=args.intake_pa,
            scaling=args.scaling,
            edge=args.edge,
        )
    except ArithmeticError as e:
        raise EngineError(f"{', '.join(args.log)}: the calibration failed ({e})") from None
    written = []
    if args.output:
        cal.save(args.output)
        written.append(args.output)
    if args.plot:
        written.append(log_plot(cal.plot(), args.plot, args.log[0], "calibration"))
    if args.json:
        print_json({**cal.to_json_dict(), "written": written}, indent=1)
    else:
        print_text(cal.summary())
        print_written(written)
