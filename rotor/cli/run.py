"""``rotor steady`` and ``rotor simulate``: the crank speed over one cycle or many."""

from __future__ import annotations

import argparse
import warnings
from typing import Any

from .args import add_dynamics_options, add_engine, add_quiet, positive_float, speed, whole
from .output import plot_folder, print_json, print_text, print_written, save_plot

__all__ = ["add_parsers", "cmd_simulate", "cmd_steady", "parse_misfires", "speed_plots", "KEEP_CYCLES"]

#: cycles whose samples ``rotor simulate`` keeps by default (it prints summaries, the last
#: cycle's orders and plots): 100 cycles of 720 samples, about 9 MB
KEEP_CYCLES = 100


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``steady`` and ``simulate`` to the subcommands ``sub``."""
    p = sub.add_parser("steady", help="periodic steady state over one cycle: δ, speed and torque orders")
    add_engine(p)
    add_dynamics_options(p)
    p.add_argument("--method", choices=("auto", "closed", "shooting"), default="auto")
    p.set_defaults(func=cmd_steady)

    p = sub.add_parser(
        "simulate",
        help="transient run over many cycles (load steps, misfires, stall, start)",
        description="A transient run over --cycles cycles. Without --load the engine is given the constant load "
        "that balances its mean torque at the start speed (at the --governor speed if one is set), so that it "
        "holds its speed, and the output says so; --load none runs it with no load at all (it accelerates). "
        "δ is that of the last complete cycle with its linear trend removed; the speed range over the whole "
        "run, drift included, is printed apart.",
    )
    add_engine(p, rpm=False)
    p.add_argument("--rpm", type=speed, help="start speed [rev/min], 0 = from rest (default: [operating] rpm)")
    p.add_argument("--cycles", type=whole, default=10, help="number of cycles (default 10)")
    p.add_argument(
        "--keep-cycles",
        type=whole,
        default=KEEP_CYCLES,
        metavar="N",
        help=f"keep the samples of the last N complete cycles only (default {KEEP_CYCLES}): the output's δ, "
        "speeds and range cover every cycle, its orders and plots the kept ones; memory stays bounded "
        "however long the run",
    )
    add_dynamics_options(p)
    for action in p._actions:  # this command's own default: the balancing load, not none
        if action.dest == "load":
            action.default = None
            action.help = (
                str(action.help).replace(" (default none)", "")
                + " (default: the constant load balancing the mean engine torque at the start speed; "
                "'none' for no load)"
            )
    add_quiet(p)
    p.add_argument("--method", choices=("auto", "closed", "grid", "angle", "time"), default="auto")
    p.add_argument("--rtol", type=positive_float, help="relative tolerance of the adaptive solvers (default 1e-9)")
    p.add_argument("--steps-per-cycle", type=whole, help="RK4 steps per cycle of --method grid (default 2 per degree)")
    p.add_argument(
        "--misfire",
        metavar="CYCLE:CYL,...",
        default="",
        help="misfiring firings, e.g. 3:1,7:2: cycle CYCLE (1 … --cycles) of cylinder CYL (1 … cylinders), "
        "both counted from 1",
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


def _report(res: Any, args: argparse.Namespace, prefix: str, load_info: dict | None = None) -> None:
    written = speed_plots(res, args.plot, prefix) if args.plot else []
    if args.json:
        out = res.to_json_dict()
        if load_info is not None:
            out["load"] = load_info
        print_json(out)
    else:
        if load_info is not None:
            print_text(f"load: {load_info['note']}\n")
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


def parse_misfires(text: str, cycles: int | None = None, cylinders: int | None = None) -> list[tuple[int, int]]:
    """``--misfire 3:1,7:2`` (cycle and cylinder both counted from 1) as (cycle from 0,
    cylinder from 1) pairs, the convention of :func:`rotor.combustion_pattern`; each
    checked against ``cycles`` and ``cylinders`` when given."""
    from ..errors import EngineError

    pairs = []
    for item in filter(None, (t.strip() for t in text.split(","))):
        try:
            ks, cs = item.split(":")
            k, c = int(ks), int(cs)
        except ValueError:
            raise EngineError(f"--misfire {text!r}: expected CYCLE:CYLINDER pairs such as 3:1,7:2") from None
        if k < 1 or (cycles is not None and k > cycles):
            top = f"1 … {cycles}" if cycles is not None else "1 or more"
            raise EngineError(f"--misfire {item}: cycle {k} is not in the run; cycles count from 1: give {top}")
        if c < 1 or (cylinders is not None and c > cylinders):
            top = f"1 … {cylinders}" if cylinders is not None else "1 or more"
            raise EngineError(f"--misfire {item}: cylinder {c} does not exist; cylinders count from 1: give {top}")
        pairs.append((k - 1, c))
    return pairs


def _balancing_load(engine: Any, args: argparse.Namespace) -> tuple[Any, dict]:
    """The constant load that balances the mean engine torque at the start speed (at the
    governor's speed if one is set), and what to say about it."""
    import jax.numpy as jnp

    from ..dynamics.loads import ConstantLoad
    from ..dynamics.steady import steady_state

    rpm = args.governor or (args.rpm if args.rpm else float(engine.operating.rpm))
    torque = float(jnp.asarray(steady_state(engine, rpm=rpm, fidelity=args.fidelity).load_torque_Nm))
    note = f"no --load given: a constant load balancing the mean engine torque at {rpm:g} rpm, {torque:.2f} N·m"
    return ConstantLoad(jnp.asarray(torque)), {"torque_Nm": torque, "rpm": rpm, "note": note}


def cmd_simulate(args: argparse.Namespace) -> None:
    """A transient run of ``--cycles`` cycles from ``--rpm``."""
    from ..dynamics.combustion import combustion_pattern
    from ..dynamics.loads import Governor, parse_load
    from ..dynamics.transient import simulate
    from ..engine.file import load_engine

    engine = load_engine(args.engine)
    pairs = parse_misfires(args.misfire, args.cycles, engine.cylinders)
    load_info = None
    if args.load is not None:
        load = parse_load(args.load)
    elif args.rpm == 0:  # from rest: no balancing speed; the run-up is the point
        load, load_info = None, {"torque_Nm": None, "rpm": None, "note": "no --load given: a start from rest, no load"}
    else:
        load, load_info = _balancing_load(engine, args)
    with warnings.catch_warnings():
        if load_info is not None:  # the output says what the load is
            warnings.simplefilter("ignore", UserWarning)
        res = simulate(
            engine,
            rpm=args.rpm,
            cycles=args.cycles,
            load=load,
            method=args.method,
            fidelity=args.fidelity,
            rtol=args.rtol,
            combustion=combustion_pattern(args.cycles, engine.cylinders, misfires=pairs) if pairs else None,
            steps_per_cycle=args.steps_per_cycle,
            governor=Governor(args.governor) if args.governor else None,
            progress=False if (args.json or args.quiet) else None,
            keep_cycles=args.keep_cycles,
        )
    _report(res, args, "simulate", load_info)
