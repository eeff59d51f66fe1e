"""``rotor modes``, ``rotor campbell`` and ``rotor torsion``: the crankshaft as a torsional chain.

Each needs the engine's ``[torsion]`` table (the chain's inertias, stiffnesses and the mass of
each crank throw); an engine without one is refused in one line that says how to add it.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from .args import add_engine, add_json, add_plot
from .output import plot_folder, print_json, print_text, print_written, save_plot

__all__ = ["add_parsers", "cmd_campbell", "cmd_modes", "cmd_torsion", "rpm_range", "torsion_engine"]


def rpm_range(text: str) -> tuple[float, float]:
    """``A:B``: two speeds [rev/min], 0 < A < B."""
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        lo, hi = float(parts[0]), float(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected two speeds in rpm as A:B, e.g. 600:2400") from None
    if not (0 < lo < hi < math.inf):
        raise argparse.ArgumentTypeError(f"{text!r}: expected 0 < A < B, finite speeds in rpm, e.g. 600:2400")
    return lo, hi


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``modes``, ``campbell`` and ``torsion`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "modes",
        help="natural frequencies and mode shapes of the engine's torsional chain ([torsion] table)",
    )
    add_engine(p)
    add_json(p)
    add_plot(p, "the mode shapes")
    p.set_defaults(func=cmd_modes)

    p = sub.add_parser(
        "campbell",
        help="Campbell diagram: natural frequencies against speed with the engine orders, critical speeds",
    )
    p.add_argument("engine", metavar="ENGINE", help="engine file (.toml) or preset name (see `rotor presets`)")
    p.add_argument(
        "--rpm-range",
        type=rpm_range,
        metavar="A:B",
        help="speed range [rev/min], e.g. 600:2400 (default 0.25…1.25 times the file's [operating] rpm)",
    )
    add_json(p)
    add_plot(p, "the Campbell diagram")
    p.set_defaults(func=cmd_campbell)

    p = sub.add_parser(
        "torsion",
        help="forced torsional response at one speed: twist and vibratory torque of every shaft section, "
        "speed at every mass",
    )
    add_engine(p)
    add_json(p)
    add_plot(p, "the response over the cycle")
    p.set_defaults(func=cmd_torsion)


def torsion_engine(name: str) -> Any:
    """The engine ``name`` (a file or preset), refused in the command line's words where it
    has no ``[torsion]`` table."""
    from ..engine.file import load_engine
    from ..errors import EngineError

    engine = load_engine(name)
    if getattr(engine, "torsion", None) is None:
        raise EngineError(
            f"{name}: engine {engine.name!r} has no [torsion] table; add one to its file (the chain's inertias "
            "[kg·m²], shaft stiffnesses [N·m/rad] and the mass of each crank throw: this command needs them); the "
            "presets mwm6 and tue-single have one (`rotor presets`)"
        )
    return engine


def cmd_modes(args: argparse.Namespace) -> None:
    """The torsional modes of the engine's chain."""
    from ..torsion.modes import torsional_modes

    modes = torsional_modes(torsion_engine(args.engine), rpm=args.rpm)
    written = [save_plot(modes.plot(), plot_folder(args.plot), "modes.png")] if args.plot else []
    if args.json:
        print_json({**modes.to_json_dict(), "plots": written})
    else:
        print_text(modes.summary().rstrip("\n") + "\n")
        print_written(written)


def cmd_campbell(args: argparse.Namespace) -> None:
    """The Campbell diagram of the engine's chain over ``--rpm-range``."""
    from ..torsion.campbell import campbell

    diagram = campbell(torsion_engine(args.engine), rpm=args.rpm_range)
    written = [save_plot(diagram.plot(), plot_folder(args.plot), "campbell.png")] if args.plot else []
    if args.json:
        print_json({**diagram.to_json_dict(), "plots": written})
    else:
        print_text(diagram.summary().rstrip("\n") + "\n")
        print_written(written)


def cmd_torsion(args: argparse.Namespace) -> None:
    """The forced response of the engine's chain at ``--rpm``."""
    from ..torsion.response import torsional_response

    response = torsional_response(torsion_engine(args.engine), args.rpm)
    written = [save_plot(response.plot(), plot_folder(args.plot), "torsion.png")] if args.plot else []
    if args.json:
        print_json({**response.to_json_dict(), "plots": written})
    else:
        print_text(response.summary())
        print_written(written)
