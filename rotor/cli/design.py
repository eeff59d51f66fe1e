"""``rotor flywheel``: the smallest flywheel that keeps δ within its targets."""

from __future__ import annotations

import argparse

from .args import (
    add_json,
    add_plot,
    delta_list,
    fidelity_option,
    nonnegative_float,
    positive_float,
    scale_list,
    speed_list,
)
from .output import plot_folder, print_json, print_text, print_written, save_plot

__all__ = ["add_parsers", "cmd_flywheel"]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``flywheel`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "flywheel",
        help="the smallest flywheel keeping δ ≤ --delta at every operating point, "
        "against the textbook (Shishkov, Dinamika dvigatelei, SUSU 2014, §3.2.12)",
    )
    p.add_argument("engine", metavar="ENGINE", help="engine file (.toml) or preset name (see `rotor presets`)")
    p.add_argument(
        "--delta",
        type=delta_list,
        required=True,
        metavar="D,...",
        help="target irregularity δ = (ω_max − ω_min)/ω_mean, e.g. 0.01; one for all or one per --rpm "
        "(e.g. 0.03,0.01,0.005: looser at idle)",
    )
    p.add_argument(
        "--rpm",
        type=speed_list,
        metavar="RPM,...",
        help="operating speeds [rev/min], e.g. 800,1250,2000 (default: the file's [operating] rpm)",
    )
    p.add_argument(
        "--imep-scale",
        type=scale_list,
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
        type=positive_float,
        metavar="RPM",
        help="highest crank speed the flywheel must stand, for --max-rim-speed (default: the larger of the "
        "file's [operating] rpm and the highest speed at the points)",
    )
    p.add_argument(
        "--shaft-inertia",
        type=nonnegative_float,
        default=0.0,
        metavar="KGM2",
        help="the crankshaft's own inertia without the flywheel [kg·m²] (default 0)",
    )
    p.add_argument("--max-diameter", type=positive_float, metavar="M", help="outer diameter limit of the disc [m]")
    p.add_argument("--max-width", type=positive_float, metavar="M", help="width limit of the disc [m]")
    p.add_argument("--max-rim-speed", type=positive_float, metavar="M_S", help="rim speed limit [m/s]")
    p.add_argument(
        "--density",
        type=positive_float,
        default=7200.0,
        metavar="KG_M3",
        help="flywheel material density [kg/m³] (default 7200, cast iron)",
    )
    p.add_argument("--bore", type=nonnegative_float, default=0.0, metavar="M", help="bore of the disc [m] (default 0)")
    fidelity_option(p, "inertia model of the steady state (default variable: the exact I(θ))")
    add_json(p)
    add_plot(p, "the design plot")
    p.set_defaults(func=cmd_flywheel)


def _per_point(values: list[float], option: str, n: int) -> list[float]:
    from ..errors import EngineError

    if len(values) not in (1, n):
        raise EngineError(f"{option} gives {len(values)} values for {n} speeds: give one for all or one per --rpm")
    return values * n if len(values) == 1 else values


def cmd_flywheel(args: argparse.Namespace) -> None:
    """Design the flywheel for the operating points of ``--rpm``, ``--imep-scale`` and ``--delta``."""
    from ..design.flywheel import OperatingPoint, design_flywheel
    from ..dynamics.loads import parse_load
    from ..engine.file import load_engine

    engine = load_engine(args.engine)
    rpms = args.rpm if args.rpm else [float(engine.operating.rpm)]
    scales = _per_point(args.imep_scale, "--imep-scale", len(rpms))
    deltas = _per_point(args.delta, "--delta", len(rpms))
    load = parse_load(args.load)
    design = design_flywheel(
        engine,
        None,
        [OperatingPoint(r, s, load, d) for r, s, d in zip(rpms, scales, deltas)],
        shaft_inertia_kgm2=args.shaft_inertia,
        density_kg_m3=args.density,
        bore_m=args.bore,
        max_outer_diameter_m=args.max_diameter,
        max_width_m=args.max_width,
        max_rim_speed_m_s=args.max_rim_speed,
        max_rpm=args.max_rpm,
        fidelity=args.fidelity,
    )
    written = [save_plot(design.plot(), plot_folder(args.plot), "flywheel.png")] if args.plot else []
    if args.json:
        print_json({**design.to_json_dict(), "plots": written})
    else:
        print_text(design.summary() + "\n")
        print_written(written)
