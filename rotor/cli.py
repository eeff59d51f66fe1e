"""The ``rotor`` command line: a thin layer over the library.

ENGINE is an engine file (TOML) or a preset name everywhere. Bad input exits with
code 2 and a one-line message on stderr; no traceback.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

__all__ = ["main"]

EXIT_USAGE = 2


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


def _build_parser():
    parser = _Parser(prog="rotor", description="Rotational dynamics of piston engines.")
    parser.add_argument("--version", action="version", version=f"rotor {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="COMMAND")

    p = sub.add_parser("table", help="one-cylinder kinematic and dynamic table over the cycle (seed 004)")
    _engine_arg(p)
    p.add_argument("--step", type=_positive_float, default=10.0, help="angle step [deg] (default 10)")
    p.add_argument("--format", choices=("text", "csv"), default="text")
    p.add_argument("--kinematics", choices=("series", "exact"), default="series",
                   help="piston kinematics: the textbook lambda series (default, as in seed 004) or exact")
    p.add_argument("--cylinder", type=int, default=1, help="cylinder number (default 1)")
    p.add_argument("--output", "-o", metavar="FILE", help="write to FILE instead of standard output")

    p = sub.add_parser("info", help="summary of an engine: geometry, IMEP, power, torque range, inertia")
    _engine_arg(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")

    p = sub.add_parser("plot", help="plots of kinematics, forces, total torque and inertia to a folder")
    _engine_arg(p)
    p.add_argument("--out", default="out", metavar="DIR", help="output folder (default out/)")

    sub.add_parser("presets", help="list the built-in engines")

    p = sub.add_parser("demo", help="summary and plots of the default preset (4chn15)")
    p.add_argument("--engine", default="4chn15", metavar="ENGINE")
    p.add_argument("--out", default="out", metavar="DIR", help="output folder (default out/)")
    return parser


def _version():
    from . import __version__

    return __version__


def _cmd_table(args):
    import rotor
    from ._io import write_text_atomic

    engine = rotor.load_engine(args.engine)
    table = rotor.crank_table(engine, rpm=args.rpm, step_deg=args.step, kinematics=args.kinematics,
                              cylinder=args.cylinder)
    text = table.to_csv() if args.format == "csv" else table.to_text()
    if args.output:
        write_text_atomic(args.output, text)
    else:
        sys.stdout.write(text)


def _cmd_info(args):
    import rotor
    from .summary import format_summary

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
    from .plotting import plot_inertia, plot_torque, save_figure

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


def _cmd_presets(args):
    import rotor

    for name in rotor.preset_names():
        print(f"{name:12s} {rotor.load_engine(name).name}")


def _cmd_demo(args):
    import rotor
    from .summary import format_summary

    engine = rotor.load_engine(args.engine)
    sys.stdout.write(format_summary(rotor.engine_summary(engine)))
    print()
    for path in _write_plots(engine, None, args.out):
        print(f"wrote {path}")


_COMMANDS = {"table": _cmd_table, "info": _cmd_info, "plot": _cmd_plot, "presets": _cmd_presets, "demo": _cmd_demo}


def main(argv=None) -> int:
    """Entry point of the ``rotor`` command."""
    parser = _build_parser()
    args = parser.parse_args(argv)
    try:
        _COMMANDS[args.command](args)
    except BrokenPipeError:  # e.g. `rotor table ... | head`
        return 0
    except (ValueError, OSError) as e:  # EngineError is a ValueError
        msg = str(e).replace("\n", " ")
        if isinstance(e, OSError) and e.filename:
            msg = f"{e.filename}: {e.strerror}"
        print(f"rotor: error: {msg}", file=sys.stderr)
        return EXIT_USAGE
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
