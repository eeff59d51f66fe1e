"""``rotor steady`` and ``rotor simulate``: the crank speed over one cycle or many."""

from __future__ import annotations

import argparse
import warnings
from typing import Any

from .args import Parser, add_dynamics_options, add_engine, add_quiet, percent_of_firings, positive_float, speed, whole
from .output import plot_folder, print_json, print_text, print_written, save_plot

__all__ = [
    "add_parsers",
    "cmd_simulate",
    "cmd_steady",
    "parse_misfires",
    "random_misfires",
    "speed_plots",
    "KEEP_CYCLES",
]

#: cycles whose samples ``rotor simulate`` keeps by default (it prints summaries, the last
#: cycle's orders and plots): 100 cycles of 720 samples, about 9 MB
KEEP_CYCLES = 100


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``steady`` and ``simulate`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "steady",
        help="periodic steady state over one cycle: δ, speed and torque orders",
        description="The periodic steady state at --rpm. An operating point is a load and a fuelling, one given "
        "and the other solved: with --load the fuel scale is solved so that the engine carries the load; without "
        "it the load is solved that the engine carries at --fuel-scale (default 1, the engine file's pressure). "
        "The output states both and which was solved.",
    )
    add_engine(p)
    add_dynamics_options(p)
    for action in p._actions:  # steady: a load given is carried by solving the fuelling
        if action.dest == "load":
            action.help = _steady_load_help_short
            action.default = None
            if isinstance(p, Parser):  # the full list of SPECs when the help is shown
                p.help_later(action, _steady_load_help)
    add_fuel_scale(p, "the fuel scale to run at; the load it carries is solved (not with --load)")
    p.add_argument(
        "--method",
        choices=("auto", "closed", "shooting"),
        default="auto",
        help="auto (default: the closed form where the losses allow it, else shooting), closed or shooting",
    )
    p.set_defaults(func=cmd_steady)

    p = sub.add_parser(
        "simulate",
        help="transient run over many cycles (load steps, misfires, stall, start)",
        description="A transient run over --cycles cycles. The fuelling stays at --fuel-scale (default 1, the "
        "engine file's pressure) unless --balance solves it so that the engine carries --load at the start "
        "speed. Without --load the engine is given the constant load that balances its mean torque at the start "
        "speed (at the --governor speed if one is set), so that it holds its speed; --load none runs it with no "
        "load at all (it accelerates). The output states the load, the fuel scale and which was solved. "
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
            action.help = _simulate_load_help_short
            if isinstance(p, Parser):  # the full list of SPECs when the help is shown
                p.help_later(action, _simulate_load_help)
    add_fuel_scale(p, "the fuel scale of every firing (not with --balance)")
    p.add_argument(
        "--balance",
        action="store_true",
        help="solve the fuel scale so that the engine carries --load at the start speed (needs a --load)",
    )
    add_quiet(p)
    p.add_argument(
        "--method",
        choices=("auto", "closed", "grid", "angle", "time"),
        default="auto",
        help="auto (default: the cheapest that answers), closed, grid (fixed-step RK4), angle or time (adaptive)",
    )
    p.add_argument("--rtol", type=positive_float, help="relative tolerance of the adaptive solvers (default 1e-9)")
    p.add_argument("--steps-per-cycle", type=whole, help="RK4 steps per cycle of --method grid (default 2 per degree)")
    p.add_argument(
        "--misfire",
        metavar="CYCLE:CYL,...",
        default="",
        help="misfiring firings, e.g. 3:1,7:2: cycle CYCLE (1 … --cycles) of cylinder CYL (1 … cylinders), "
        "both counted from 1",
    )
    p.add_argument(
        "--misfire-rate",
        type=percent_of_firings,
        metavar="PCT",
        help="random misfires on PCT %% of all the firings of cycles 1 … --cycles (the rate an OBD monitor counts): "
        "on --misfire-cylinder alone, else on any cylinder; with --misfire's firings",
    )
    p.add_argument(
        "--misfire-cylinder",
        type=whole,
        metavar="CYL",
        help="the cylinder (from 1) that --misfire-rate's misfires fall on (default: spread over all)",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        metavar="N",
        help="the random draw of --misfire-rate: the same N gives the same misfires (default 0)",
    )
    p.add_argument("--governor", type=positive_float, metavar="RPM", help="PI speed governor set to RPM")
    p.add_argument(
        "--record",
        metavar="FILE",
        help="write the run as a wheel log to FILE (tooth edge times under the header tooth_time_s, read back by "
        "`rotor analyze` and `rotor diagnose` with --wheel alone) and its truth beside it as FILE's stem + "
        ".truth.json (each firing's IMEP, the misfires, TDC after the gap); keeps every cycle's samples",
    )
    p.add_argument(
        "--wheel",
        metavar="SPEC",
        default="60-2",
        help="the trigger wheel of --record, with a gap (default 60-2; e.g. 36-1)",
    )
    p.add_argument(
        "--signal",
        choices=("teeth",),
        default="teeth",
        help="what --record writes: teeth, the tooth edge times (default)",
    )
    p.set_defaults(func=cmd_simulate)


_steady_load_help_short = "the load to carry: a torque [N·m] or a SPEC; the fuel scale is solved to carry it"


def _steady_load_help() -> str:
    from ..dynamics.load_help import LOAD_HELP

    return (
        "the load to carry, the fuel scale solved to carry it (default: none given, the load solved at "
        "--fuel-scale); " + LOAD_HELP
    )


_simulate_load_help_short = (
    "the load: a torque [N·m] or a SPEC (default: the constant load balancing the mean engine torque at the start "
    "speed; 'none' for no load)"
)


def _simulate_load_help() -> str:
    from ..dynamics.load_help import LOAD_HELP

    return (
        "the load; " + LOAD_HELP + " (default: the constant load balancing the mean engine torque at the start "
        "speed; 'none' for no load)"
    )


def fuel_scale(text: str) -> float:
    """A fuel scale: a number in 0 … 10 (:data:`rotor.dynamics.operating.FUEL_SCALE_MAX`)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (0 <= v <= 10):
        raise argparse.ArgumentTypeError(
            f"{text!r}: a fuel scale lies in 0 … 10 (1 = the engine file's pressure; above 1.2 more than it is rated for)"
        )
    return v


def add_fuel_scale(p: argparse.ArgumentParser, what: str) -> None:
    """``--fuel-scale X``: the combustion as a multiple of the engine file's."""
    p.add_argument(
        "--fuel-scale",
        type=fuel_scale,
        metavar="X",
        help=f"{what}: the combustion of every firing as a multiple of the engine file's pressure "
        "(default 1; 0 … 10, a warning above 1.2)",
    )


def speed_plots(res: Any, folder: str, prefix: str) -> list[str]:
    """The plots of a :class:`rotor.SpeedResult` into ``folder`` as ``<prefix>_<kind>.png``
    (cycle, time, torque and orders; no time plot of a steady state, only the time plot of
    a run without a whole cycle); the paths written."""
    plot_folder(folder)
    kinds: tuple[str, ...] = ("cycle", "time", "torque", "orders") if res.uniform_cycles else ("time",)
    if res.kind == "steady":
        kinds = tuple(k for k in kinds if k != "time")
    return [save_plot(res.plot(kind=kind), folder, f"{prefix}_{kind}.png") for kind in kinds]


def _report(
    res: Any, args: argparse.Namespace, prefix: str, note: str | None = None, recorded: tuple[str, ...] = ()
) -> None:
    written = [*recorded, *(speed_plots(res, args.plot, prefix) if args.plot else [])]
    if args.json:
        out = res.to_json_dict()
        if recorded:
            out["written"] = list(recorded)
        print_json(out)
    else:
        if note is not None:
            print_text(f"operating point: {note}\n")
        print_text(res.summary())
        print_written(written)


def cmd_steady(args: argparse.Namespace) -> None:
    """The periodic steady state at ``--rpm``: the fuel scale solved for ``--load``, or the
    load solved at ``--fuel-scale``."""
    from ..dynamics.loads import parse_load
    from ..dynamics.steady import steady_state
    from ..engine.file import load_engine
    from ..errors import EngineError

    load = None if args.load is None else parse_load(args.load)
    if load is not None and args.fuel_scale is not None:
        raise EngineError(
            "--load and --fuel-scale: give one, the other is solved (--load: the fuelling that carries it; "
            "--fuel-scale: the load it carries)"
        )
    engine = load_engine(args.engine)
    scale = 1.0 if args.fuel_scale is None else args.fuel_scale
    res = steady_state(engine, rpm=args.rpm, load=load, fidelity=args.fidelity, method=args.method, imep_scale=scale)
    _report(res, args, "steady")


def random_misfires(
    cycles: int, cylinders: int, rate_pct: float, cylinder: int | None = None, seed: int = 0
) -> list[tuple[int, int]]:
    """Random misfires on ``rate_pct`` % of all the firings of ``cycles`` cycles of a
    ``cylinders``-cylinder engine, as (cycle, cylinder) pairs from 1: on ``cylinder`` alone
    (each of its firings with probability ``cylinders``·rate, so that the rate over all the
    firings is ``rate_pct``), else on every firing alike; drawn by
    ``numpy.random.default_rng(seed)``."""
    import numpy as np

    from ..errors import EngineError

    rng = np.random.default_rng(seed)
    if cylinder is None:
        hit = rng.random((cycles, cylinders)) < rate_pct / 100.0
        return [(int(k) + 1, int(c) + 1) for k, c in zip(*np.nonzero(hit), strict=True)]
    if not 1 <= cylinder <= cylinders:
        raise EngineError(f"--misfire-cylinder {cylinder}: cylinders count from 1: give 1 … {cylinders}")
    p = cylinders * rate_pct / 100.0
    if p > 1.0:
        raise EngineError(
            f"--misfire-rate {rate_pct:g} on one cylinder of {cylinders}: at most {100.0 / cylinders:g} % of all the "
            "firings fall on one cylinder (every one of its firings); give a lower rate or leave out --misfire-cylinder"
        )
    return [(int(k) + 1, cylinder) for k in np.flatnonzero(rng.random(cycles) < p)]


def parse_misfires(text: str, cycles: int | None = None, cylinders: int | None = None) -> list[tuple[int, int]]:
    """``--misfire 3:1,7:2`` as (cycle, cylinder) pairs, both counted from 1 as in
    :func:`rotor.combustion_pattern`; each checked against ``cycles`` and ``cylinders`` when
    given."""
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
        pairs.append((k, c))
    return pairs


def _operating_point(engine: Any, args: argparse.Namespace) -> tuple[Any, float, str | None, str]:
    """The load, the fuel scale, which was solved (``"load"``, ``"fuel_scale"`` or None) and
    a note for the text output, from ``--load``, ``--fuel-scale`` and ``--balance``: the
    fuel scale is given (default 1) unless ``--balance`` solves it for the load at the start
    speed; without ``--load`` the constant load balancing the mean engine torque at the start
    speed (at the governor's speed if one is set) is solved."""
    import numpy as np

    from ..checks import as_f64
    from ..dynamics.loads import ConstantLoad, parse_load
    from ..dynamics.steady import steady_state
    from ..errors import EngineError

    load = None if args.load is None else parse_load(args.load)
    if args.balance and args.fuel_scale is not None:
        raise EngineError("--balance solves the fuel scale: give --balance or --fuel-scale, not both")
    if args.balance and load is None:
        raise EngineError("--balance solves the fuel scale that carries the load: give a --load (a torque in N·m)")
    rpm = args.governor or (args.rpm if args.rpm else float(engine.operating.rpm))
    fuel = 1.0 if args.fuel_scale is None else args.fuel_scale
    if args.balance:
        st = steady_state(engine, rpm=rpm, load=load, fidelity=args.fidelity)
        fuel = float(np.asarray(st.fuel_scale))
        return load, fuel, "fuel_scale", f"--balance: the fuel scale {fuel:.4f} carries the load at {rpm:g} rpm"
    if args.load is not None:
        if args.fuel_scale is not None:
            _check_given_fuel(engine, fuel)
        return load, fuel, None, "load and fuel scale given (nothing solved): the speed follows from them"
    if args.rpm == 0:  # from rest: no balancing speed; the run-up is the point
        if args.fuel_scale is not None:
            _check_given_fuel(engine, fuel)
        return None, fuel, None, "no --load given: a start from rest, no load"
    # with random misfires, the mean torque of the firings that burn (a share 1 − rate of them)
    burning = 1.0 - (getattr(args, "misfire_rate", None) or 0.0) / 100.0
    st = steady_state(engine, rpm=rpm, fidelity=args.fidelity, imep_scale=fuel * burning)
    torque = float(np.asarray(st.load_torque_Nm))
    note = f"no --load given: the constant load balancing the mean engine torque at {rpm:g} rpm, {torque:.2f} N·m"
    if burning < 1.0:
        note += f" (with {100 * (1 - burning):g} % of the firings misfiring at random)"
    return ConstantLoad(as_f64(torque)), fuel, "load", note


def _check_given_fuel(engine: Any, fuel: float) -> None:
    """Warn about a given fuel scale above 1.2, naming the IMEP it implies."""
    from ..dynamics.operating import FUEL_SCALE_WARN, check_fuel_scale

    if fuel > FUEL_SCALE_WARN:
        from ..engine.forces import imep_pa

        fired = float(imep_pa(engine))
        motored = float(imep_pa(engine.replace(pressure=engine.pressure.motored(engine.strokes))))
        check_fuel_scale(fuel, [motored], [fired - motored], solved=False, name="--fuel-scale")


def cmd_simulate(args: argparse.Namespace) -> None:
    """A transient run of ``--cycles`` cycles from ``--rpm``."""
    import dataclasses

    from ..dynamics.combustion import combustion_pattern
    from ..dynamics.loads import ConstantLoad, Governor
    from ..dynamics.transient import simulate
    from ..engine.file import load_engine
    from ..errors import EngineError

    if args.record and args.cycles < 2:
        raise EngineError(f"--record needs --cycles 2 or more (a whole cycle and a revolution), not {args.cycles}")
    engine = load_engine(args.engine)
    pairs = parse_misfires(args.misfire, args.cycles, engine.cylinders)
    if args.misfire_cylinder is not None and args.misfire_rate is None:
        raise EngineError("--misfire-cylinder names the cylinder of --misfire-rate's misfires: give a --misfire-rate")
    if args.misfire_rate is not None:
        drawn = random_misfires(args.cycles, engine.cylinders, args.misfire_rate, args.misfire_cylinder, args.seed)
        pairs = sorted(set(pairs) | set(drawn))
    load, fuel, solved, note = _operating_point(engine, args)
    pattern = None
    if pairs or fuel != 1.0:
        pattern = combustion_pattern(args.cycles, engine.cylinders, imep_scale=fuel, misfires=pairs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(
            engine,
            rpm=args.rpm,
            cycles=args.cycles,
            load=load,
            method=args.method,
            fidelity=args.fidelity,
            rtol=args.rtol,
            combustion=pattern,
            steps_per_cycle=args.steps_per_cycle,
            governor=Governor(args.governor) if args.governor else None,
            progress=False if (args.json or args.quiet) else None,
            keep_cycles=None if args.record else args.keep_cycles,
        )
    for w in caught:  # the library's warnings in the command line's words
        if not issubclass(w.category, UserWarning) or solved is not None or args.rpm == 0:
            continue  # numpy's are not the user's business; a solved or no load the output states
        text = str(w.message)
        if "will accelerate" in text:
            text = (
                text.split("; give a load")[0]
                .removeprefix("simulate: ")
                .replace("no load and no governor", "--load none")
                + "; leave out --load for the constant load that balances it at the start speed, or give a --governor"
            )
        warnings.warn(text, w.category, stacklevel=1)
    constant = isinstance(load, ConstantLoad)
    res = dataclasses.replace(
        res,
        load_torque_Nm=float(load.torque_Nm) if constant else (0.0 if load is None else None),
        fuel_scale=None if args.governor else fuel,
        solved_for=solved,
    )
    recorded: tuple[str, ...] = ()
    if args.record:
        from ..diagnostics.record import record_run

        log, truth = record_run(args.record, res, wheel=args.wheel, signal=args.signal, misfires=pairs)
        recorded = (str(log), str(truth))
    _report(res, args, "simulate", note, recorded)
