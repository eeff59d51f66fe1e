"""``rotor steady`` and ``rotor simulate``: the crank speed over one cycle or many."""

from __future__ import annotations

import argparse
from typing import Any

from .args import add_dynamics_options, add_engine, add_quiet, positive_float, speed, whole
from .output import plot_folder, print_json, print_text, print_written, save_plot

__all__ = ["add_parsers", "cmd_simulate", "cmd_steady", "parse_misfires", "speed_plots"]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``steady`` and ``simulate`` to the subcommands ``sub``."""
    p = sub.add_parser("steady", help="periodic steady state over one cycle: δ, speed and torque orders")
    add_engine(p)
    add_dynamics_options(p)
    p.add_argument("--method", choices=("auto", "closed", "shooting"), default="auto")
    p.set_defaults(func=cmd_steady)

    p = sub.add_parser("simulate", help="transient run over many cycles (load steps, misfires, stall, start)")
    add_engine(p, rpm=False)
    p.add_argument("--rpm", type=speed, help="start speed [rev/min], 0 = from rest (default: [operating] rpm)")
    p.add_argument("--cycles", type=whole, default=10, help="number of cycles (default 10)")
    add_dynamics_options(p)
    add_quiet(p)
    p.add_argument("--method", choices=("auto", "closed", "grid", "angle", "time"), default="auto")
    p.add_argument("--rtol", type=positive_float, help="relative tolerance of the adaptive solvers (default 1e-9)")
    p.add_argument("--steps-per-cycle", type=whole, help="RK4 steps per cycle of --method grid (default 2 per degree)")
    p.add_argument(
        "--misfire",
        metavar="CYCLE:CYL,...",
        default="",
        help="misfiring firings, e.g. 3:1,7:2 (cycle from 0, cylinder from 1)",
    )
    p.add_argument("--governor", type=positive_float, metavar="RPM", help="PI speed governor set to RPM")
    p.set_defaults(func=cmd_simulate)


def speed_plots(res: Any, folder: str, prefix: str) -> list[str]:
    """The plots of a :class:`rotor.SpeedResult` into ``folder`` as ``<prefix>_<kind>.png``
    (cycle, time, torque and orders; no time plot of a steady state, only the time plot of
    a run without a whole cycle); the paths written."""
    plot_folder(folder)
    kinds: tuple[str, ...] = ("cycle", "time", "torque", "orders") if res.uniform_cycles else ("time",)
    if res.kind == "steady":
        kinds = tuple(k for k in kinds if k != "time")
    return [save_plot(res.plot(kind=kind), folder, f"{prefix}_{kind}.png") for kind in kinds]


def _report(res: Any, args: argparse.Namespace, prefix: str) -> None:
    written = speed_plots(res, args.plot, prefix) if args.plot else []
    if args.json:
        print_json(res.to_json_dict())
    else:
        print_text(res.summary())
        print_written(written)


def cmd_steady(args: argparse.Namespace) -> None:
    """The periodic steady state at ``--rpm``."""
    from ..dynamics.loads import parse_load
    from ..dynamics.steady import steady_state
    from ..engine.file import load_engine

    engine = load_engine(args.engine)
    res = steady_state(engine, rpm=args.rpm, load=parse_load(args.load), fidelity=args.fidelity, method=args.method)
    _report(res, args, "steady")


def parse_misfires(text: str) -> list[tuple[int, int]]:
    """``--misfire 3:1,7:2`` as (cycle, cylinder) pairs."""
    from ..errors import EngineError

    pairs = []
    for item in filter(None, (t.strip() for t in text.split(","))):
        try:
            k, c = item.split(":")
            pairs.append((int(k), int(c)))
        except ValueError:
            raise EngineError(f"--misfire {text!r}: expected CYCLE:CYLINDER pairs such as 3:1,7:2") from None
    return pairs


def cmd_simulate(args: argparse.Namespace) -> None:
    """A transient run of ``--cycles`` cycles from ``--rpm``."""
    from ..dynamics.combustion import combustion_pattern
    from ..dynamics.loads import Governor, parse_load
    from ..dynamics.transient import simulate
    from ..engine.file import load_engine

    engine = load_engine(args.engine)
    pairs = parse_misfires(args.misfire)
    res = simulate(
        engine,
        rpm=args.rpm,
        cycles=args.cycles,
        load=parse_load(args.load),
        method=args.method,
        fidelity=args.fidelity,
        rtol=args.rtol,
        combustion=combustion_pattern(args.cycles, engine.cylinders, misfires=pairs) if pairs else None,
        steps_per_cycle=args.steps_per_cycle,
        governor=Governor(args.governor) if args.governor else None,
        progress=False if (args.json or args.quiet) else None,
    )
    _report(res, args, "simulate")
