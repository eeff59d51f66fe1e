"""``rotor demo``: a tour of the default preset: summary, steady state, a load step, a flywheel, plots."""

from __future__ import annotations

import argparse

from .args import add_plot, add_quiet
from .output import plot_folder, print_text, print_written, save_plot

__all__ = ["DEMO_CYCLES", "STEP_CYCLE", "add_parsers", "cmd_demo", "load_step_line", "load_step_time_s"]

DEMO_CYCLES = 40
"""The cycles of the demo's load step."""
STEP_CYCLE = 6
"""The cycle (counted from 1) at whose start the demo's load steps up."""


def load_step_time_s(rpm: float, strokes: int) -> float:
    """When the demo's load steps up [s]: the start of cycle :data:`STEP_CYCLE` at ``rpm``
    [rev/min] for an engine of ``strokes`` (2 or 4), so that it lies inside the run of
    :data:`DEMO_CYCLES` cycles at any speed, to 3 significant digits."""
    cycle_s = strokes / 2 * 60.0 / rpm
    return float(f"{(STEP_CYCLE - 1) * cycle_s:.3g}")


def load_step_line(load_Nm: float, step_s: float, end_s: float) -> str:
    """The demo's line announcing its load step of ``load_Nm`` [N·m] by 20 % at ``step_s``
    [s] in a run that ends at ``end_s`` [s]."""
    return (
        f"load step {load_Nm:.0f} -> {1.2 * load_Nm:.0f} N·m at t = {step_s:g} s "
        f"(the start of cycle {STEP_CYCLE} of a run of {end_s:.3g} s), PI governor:"
    )


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
    # a transient: the load steps up by 20 % after the first cycles, a PI governor holds the speed
    load = jnp.asarray(steady.load_torque_Nm)  # the loads and the governor are typed with array fields
    step_s = load_step_time_s(float(steady.mean_rpm), engine.strokes)
    step = LoadStep(ConstantLoad(load), ConstantLoad(1.2 * load), time_s=jnp.asarray(step_s))
    trans = simulate(
        engine,
        rpm=float(steady.omega[0]) * RPM_PER_RAD_S,
        cycles=DEMO_CYCLES,
        load=step,
        governor=Governor(jnp.asarray(steady.mean_rpm)),
        progress=False if args.quiet else None,
    )
    print(load_step_line(float(load), step_s, float(trans.t[-1])))
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
