"""``rotor demo``: a tour of the default preset: summary, steady state, a load step, a flywheel, plots."""

from __future__ import annotations

import argparse

from .args import add_plot, add_quiet
from .output import plot_folder, print_text, print_written, save_plot

__all__ = ["add_parsers", "cmd_demo"]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``demo`` to the subcommands ``sub``."""
    p = sub.add_parser("demo", help="summary, steady state, a load step and plots of the default preset (4chn15)")
    p.add_argument("--engine", default="4chn15", metavar="ENGINE", help="engine file or preset (default 4chn15)")
    add_plot(p, "the plots", default="out")
    add_quiet(p)
    p.set_defaults(func=cmd_demo)


def cmd_demo(args: argparse.Namespace) -> None:
    """The engine's summary, its steady state, a 20 % load step held by a PI governor, the
    flywheel for δ ≤ 0.01 at rated speed and ≤ 0.03 at a part-load idle, and every plot."""
    import jax.numpy as jnp

    from ..design.flywheel import OperatingPoint, design_flywheel
    from ..dynamics.loads import ConstantLoad, Governor, LoadStep
    from ..dynamics.steady import steady_state
    from ..dynamics.transient import simulate
    from ..engine.file import load_engine
    from ..engine.summary import engine_summary
    from ..units import RPM_PER_RAD_S
    from .engine import engine_plots
    from .run import speed_plots

    engine = load_engine(args.engine)
    print_text(engine_summary(engine).summary() + "\n")
    steady = steady_state(engine)
    print_text(steady.summary() + "\n")
    # a transient: the load steps up by 20 % half a second in, a PI governor holds the speed
    load = jnp.asarray(steady.load_torque_Nm)  # the loads and the governor are typed with array fields
    step = LoadStep(ConstantLoad(load), ConstantLoad(1.2 * load), time_s=jnp.asarray(0.5))
    trans = simulate(
        engine,
        rpm=float(steady.omega[0]) * RPM_PER_RAD_S,
        cycles=40,
        load=step,
        governor=Governor(jnp.asarray(steady.mean_rpm)),
        progress=False if args.quiet else None,
    )
    print(f"load step {float(load):.0f} -> {1.2 * float(load):.0f} N·m at t = 0.5 s, PI governor:")
    print_text(trans.summary() + "\n")
    rpm = float(engine.operating.rpm)
    design = design_flywheel(engine, 0.01, [OperatingPoint(0.5 * rpm, 0.3, None, 0.03), rpm])
    print_text(design.summary() + "\n\n")
    folder = plot_folder(args.plot)
    fly = save_plot(design.plot(), folder, "flywheel.png")
    print_written(
        engine_plots(engine, None, folder)
        + speed_plots(steady, folder, "steady")
        + speed_plots(trans, folder, "load_step")
        + [fly]
    )
