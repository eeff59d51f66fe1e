"""``rotor loads``, ``rotor balance`` and ``rotor report``: the textbook dynamic calculation
after the forces table (Shishkov, Dinamika dvigatelei, SUSU 2014, §3.2.4–3.2.12)."""

from __future__ import annotations

import argparse
from typing import Any

from .args import add_engine, add_json, add_plot, positive_float, whole
from .output import plot_folder, print_json, print_text, print_written, save_plot

__all__ = ["add_parsers", "cmd_balance", "cmd_loads", "cmd_report", "load_plots"]


def load_plots(loads: Any, folder: str) -> list[str]:
    """The diagrams of a :class:`rotor.BearingLoads` into ``folder``: crank pin 1 and the
    big end of cylinder 1 (polar), crank pin 1 developed, the most loaded main journal and
    its bearing (polar), the wear of crank pin 1 and of that journal, the running torques;
    the paths written."""
    j = loads.worst_journal
    drawings: tuple[tuple[Any, dict[str, Any], str], ...] = (
        (loads.plot_crank_pin, {}, "crank_pin_polar.png"),
        (loads.plot_big_end, {}, "big_end_polar.png"),
        (loads.plot_developed, {}, "crank_pin_developed.png"),
        (loads.plot_main_journal, {"journal": j}, "main_journal_polar.png"),
        (loads.plot_main_bearing, {"journal": j}, "main_bearing_polar.png"),
        (loads.plot_wear, {}, "crank_pin_wear.png"),
        (loads.plot_wear, {"journal": j}, "main_journal_wear.png"),
        (loads.plot_running_torques, {}, "running_torques.png"),
    )
    return [save_plot(draw(**kwargs), folder, name) for draw, kwargs, name in drawings]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``loads``, ``balance`` and ``report`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "loads",
        help="loads on the crank pins, big-end bearings, main journals and main bearings over the cycle, the wear "
        "diagram and the running torques (Shishkov, Dinamika dvigatelei, SUSU 2014, §3.2.4–3.2.9)",
    )
    add_engine(p)
    p.add_argument("--step", type=positive_float, default=1.0, help="angle step [deg], dividing the cycle (default 1)")
    add_json(p)
    add_plot(p, "the polar, developed and wear diagrams and the running torques")
    p.set_defaults(func=cmd_loads)

    p = sub.add_parser(
        "balance",
        help="free forces and moments of the reciprocating and rotating masses by order, with the file's "
        "counterweights, and the textbook's balance conditions (Shishkov 2014, §3.2.10)",
    )
    add_engine(p)
    p.add_argument(
        "--orders", type=whole, default=6, metavar="K", help="the highest order of the expansion (default 6)"
    )
    add_json(p)
    add_plot(p, "the balance plot")
    p.set_defaults(func=cmd_balance)

    p = sub.add_parser(
        "report",
        help="the whole kinematic and dynamic calculation as one self-contained HTML page, with its figures (PNG) "
        "and tables (CSV), into --out DIR",
    )
    add_engine(p)
    p.add_argument(
        "--out",
        metavar="DIR",
        required=True,
        help="the report's folder: new, empty, or a previous report's (replaced whole); written whole or not at all",
    )
    p.add_argument(
        "--step",
        type=positive_float,
        default=10.0,
        help="angle step of the tables [deg], dividing the cycle (default 10; the figures are drawn every 1° or finer)",
    )
    p.add_argument(
        "--delta",
        type=positive_float,
        default=0.01,
        help="target irregularity δ = (ω_max − ω_min)/ω_mean of the textbook flywheel (default 0.01)",
    )
    p.add_argument(
        "--kinematics",
        choices=("exact", "series"),
        default="exact",
        help="piston kinematics: exact (default) or the guide's lambda series",
    )
    p.add_argument("--orders", type=whole, default=6, metavar="K", help="the highest order of the balance (default 6)")
    add_json(p)
    p.set_defaults(func=cmd_report)


def cmd_loads(args: argparse.Namespace) -> None:
    """The bearing loads at ``--rpm`` every ``--step`` degrees; their diagrams into ``--plot DIR``."""
    from ..design.bearings import bearing_loads
    from ..engine.file import load_engine

    engine = load_engine(args.engine)
    if args.plot:
        plot_folder(args.plot)  # a folder that cannot be made fails before the calculation
    loads = bearing_loads(engine, args.rpm, step_deg=args.step)
    written = load_plots(loads, args.plot) if args.plot else []
    if args.json:
        print_json({**loads.to_json_dict(), "plots": written})
    else:
        print_text(loads.summary().rstrip("\n") + "\n")
        print_written(written)


def cmd_balance(args: argparse.Namespace) -> None:
    """Free forces and moments by order up to ``--orders`` at ``--rpm``; the plot into ``--plot DIR``."""
    from ..design.balance import balance
    from ..engine.file import load_engine

    engine = load_engine(args.engine)
    if args.plot:
        plot_folder(args.plot)
    result = balance(engine, args.rpm, orders=args.orders)
    written = [save_plot(result.plot(), args.plot, "balance.png")] if args.plot else []
    if args.json:
        print_json({**result.to_json_dict(), "plots": written})
    else:
        print_text(result.summary().rstrip("\n") + "\n")
        print_written(written)


def cmd_report(args: argparse.Namespace) -> None:
    """Write the report of the engine at ``--rpm`` into ``--out DIR``."""
    import matplotlib

    from ..design.report import report
    from ..engine.file import load_engine

    matplotlib.use("Agg")  # files only, no window
    done = report(
        load_engine(args.engine),
        args.out,
        args.rpm,
        step_deg=args.step,
        delta=args.delta,
        kinematics=args.kinematics,
        orders=args.orders,
    )
    if args.json:
        print_json(done.to_json_dict())
    else:
        print_text(done.summary())
