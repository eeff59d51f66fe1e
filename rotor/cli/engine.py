"""``rotor table``, ``rotor info``, ``rotor plot`` and ``rotor presets``: an engine by itself."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from .args import add_engine, add_json, add_plot, positive_float
from .output import csv_text, json_text, plot_folder, print_json, print_text, print_written, save_plot

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = ["add_parsers", "cmd_info", "cmd_plot", "cmd_presets", "cmd_table", "engine_plots", "preset_listing"]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``table``, ``info``, ``plot`` and ``presets`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "table",
        help="one-cylinder kinematic and dynamic table over the cycle (as in Shishkov, "
        "Dinamika dvigatelei, SUSU 2014, appendix 5)",
    )
    add_engine(p)
    p.add_argument("--step", type=positive_float, default=10.0, help="angle step [deg] (default 10)")
    fmt = p.add_mutually_exclusive_group()
    fmt.add_argument("--format", choices=("text", "csv"), default="text", help="table format (default text)")
    add_json(fmt)
    p.add_argument(
        "--kinematics",
        choices=("series", "exact"),
        default="series",
        help="piston kinematics: the textbook lambda series (default, as in Shishkov 2014) or exact",
    )
    p.add_argument("--cylinder", type=int, default=1, help="cylinder number (default 1)")
    p.add_argument(
        "--output", "-o", metavar="FILE", help="write to FILE instead of standard output (- is standard output)"
    )
    p.set_defaults(func=cmd_table)

    p = sub.add_parser("info", help="summary of an engine: geometry, IMEP, power, torque range, inertia")
    add_engine(p)
    add_json(p)
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("plot", help="plots of kinematics, forces, total torque and inertia to a folder")
    add_engine(p)
    add_plot(p, "the plots", default="out")
    p.set_defaults(func=cmd_plot)

    p = sub.add_parser("presets", help="list the built-in engines")
    add_json(p)
    p.set_defaults(func=cmd_presets)


def cmd_table(args: argparse.Namespace) -> None:
    """The textbook table of one cylinder (Shishkov 2014, appendix 5): text, CSV or JSON, to
    standard output or ``--output`` (``-``: standard output); the same call again reads its kept output
    (:mod:`rotor.cli.kept`) without importing JAX."""
    from ..fileio import write_text_atomic
    from .kept import keep_output, kept_output, output_key

    options = {k: getattr(args, k) for k in ("rpm", "step", "kinematics", "cylinder", "json", "format")}
    key = output_key("table", args.engine, options)
    text = kept_output(key)
    if text is None:
        from ..engine.file import load_engine
        from ..engine.table import TABLE_COLUMNS, crank_table

        engine = load_engine(args.engine)
        table = crank_table(
            engine, rpm=args.rpm, step_deg=args.step, kinematics=args.kinematics, cylinder=args.cylinder
        )
        if args.json:
            text = json_text(table.to_json_dict())
        elif args.format == "csv":
            text = csv_text(TABLE_COLUMNS, zip(*(table.columns[c] for c in TABLE_COLUMNS)), what="the crank table")
        else:
            text = table.to_text() + same_table_note(engine, table, args)
        keep_output(key, text)
    if args.output and args.output != "-":
        write_text_atomic(args.output, text)
    else:
        print_text(text)


def same_table_note(engine: Engine, table: Any, args: argparse.Namespace) -> str:
    """The line under a multi-cylinder engine's table that names the cylinders whose table
    is the same (every column equal to 1e-9 of its largest magnitude), and why: each table
    is in its own cylinder's cycle angle, so cylinders with the same crank-throw kinematics,
    masses and pressure cycle differ only in their phase on the crankshaft. Empty for one
    cylinder."""
    import numpy as np

    from ..engine.table import TABLE_COLUMNS, crank_table

    if engine.cylinders < 2:
        return ""
    ours = {c: np.asarray(table.columns[c], dtype=float) for c in TABLE_COLUMNS}
    same = []
    for cylinder in range(1, engine.cylinders + 1):
        other = (
            table
            if cylinder == table.cylinder
            else crank_table(engine, rpm=args.rpm, step_deg=args.step, kinematics=args.kinematics, cylinder=cylinder)
        )
        if all(
            np.allclose(
                np.asarray(other.columns[c], dtype=float), v, rtol=0.0, atol=1e-9 * max(np.abs(v).max(), 1e-300)
            )
            for c, v in ours.items()
        ):
            same.append(cylinder)
    why = (
        "each table is in its own cylinder's cycle angle (0° at its TDC at the start of its cycle), and these "
        "cylinders share the crank-throw kinematics, masses and pressure cycle; they differ only in their phase "
        "on the crankshaft (the firing order and the throw angles)"
    )
    if len(same) == engine.cylinders:
        return f"note: every cylinder (1–{engine.cylinders}) has this table: {why}\n"
    if len(same) > 1:
        names = ", ".join(str(c) for c in same)
        return f"note: cylinders {names} have this table: {why}; the others differ\n"
    return f"note: no other cylinder has this table (cylinder {table.cylinder}'s mechanism or pressure differs)\n"


def cmd_info(args: argparse.Namespace) -> None:
    """The engine's key figures at ``--rpm``; the same call again reads its kept output
    (:mod:`rotor.cli.kept`) without importing JAX."""
    from .kept import keep_output, kept_output, output_key

    key = output_key("info", args.engine, {"rpm": args.rpm, "json": args.json})
    text = kept_output(key)
    if text is None:
        from ..engine.file import load_engine
        from ..engine.summary import engine_summary

        summary = engine_summary(load_engine(args.engine), rpm=args.rpm)
        text = json_text(summary.to_json_dict()) if args.json else summary.summary()
        keep_output(key, text)
    print_text(text)


def engine_plots(engine: Engine, rpm: float | None, folder: str) -> list[str]:
    """Kinematics, forces (the exact crank table at 2° steps), total torque and inertia of
    ``engine`` at ``rpm`` into ``folder``; the paths written."""
    from ..engine.summary import engine_curves
    from ..engine.table import crank_table

    plot_folder(folder)
    table = crank_table(engine, rpm=rpm, step_deg=2.0, kinematics="exact")
    curves = engine_curves(engine, rpm)
    return [
        save_plot(table.plot(which="kinematics"), folder, "kinematics.png"),
        save_plot(table.plot(which="forces"), folder, "forces.png"),
        save_plot(curves.plot(which="torque"), folder, "torque.png"),
        save_plot(curves.plot(which="inertia"), folder, "inertia.png"),
    ]


def cmd_plot(args: argparse.Namespace) -> None:
    """Write the engine's plots to ``--plot DIR``."""
    from ..engine.file import load_engine

    print_written(engine_plots(load_engine(args.engine), args.rpm, args.plot))


def preset_listing() -> dict[str, str]:
    """{preset name: engine name} of the built-in engines, read from their TOML files
    without building the engines (that would import JAX: ``rotor presets`` needs none;
    tests/cli/test_cli_latency.py checks the names against :func:`rotor.load_engine`)."""
    import tomllib
    from importlib import resources

    files = resources.files("rotor.presets")
    names = sorted(p.name[: -len(".toml")] for p in files.iterdir() if p.name.endswith(".toml"))
    return {
        name: str(tomllib.loads((files / f"{name}.toml").read_text(encoding="utf-8-sig"))["name"]) for name in names
    }


def cmd_presets(args: argparse.Namespace) -> None:
    """The built-in engines: preset name and engine name."""
    names = preset_listing()
    if args.json:
        print_json({"presets": [{"name": k, "engine": v} for k, v in names.items()]})
    else:
        for name, engine in names.items():
            print(f"{name:12s} {engine}")
