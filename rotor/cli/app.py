"""The ``rotor`` parser, assembled from each command group's ``add_parsers``, and ``main``.

Errors: bad input (an engine or log that cannot be read, an option out of range, a file
that cannot be written: :class:`rotor.EngineError`, :class:`rotor.LogError`, any
``ValueError`` or ``OSError``) is one line ``rotor: error: …`` on stderr and exit status 2;
valid input without an answer (:class:`rotor.SolverError`) one line and exit status 1; a
closed pipe (``rotor table … | head``) exit status 0.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from ..errors import SolverError
from . import demo, design, diagnostics, engine, logs, run
from .args import EXIT_SOLVER, EXIT_USAGE, Parser

__all__ = ["COMMAND_GROUPS", "build_parser", "main"]

COMMAND_GROUPS = (engine, run, logs, diagnostics, design, demo)
"""The command modules, in the order of ``rotor --help``; each has ``add_parsers(sub)``."""

EPILOG = """\
ENGINE is an engine file (.toml) or a preset name (`rotor presets`) everywhere.

One convention for options:
  --json      print the result as one JSON object (every command with a result)
  --plot DIR  write the command's plots as PNG files into DIR (every command that draws;
              `rotor plot` and `rotor demo` write to out/ unless given another DIR)
  --quiet     no progress bar (the commands that may show one)
  --format    only for tables (`rotor table --format text|csv`)

Bad input exits with status 2, a solver without an answer with 1, each with one line on stderr.
`rotor COMMAND --help` for a command's options."""


def _version() -> str:
    from .. import __version__

    return str(__version__)


def build_parser() -> argparse.ArgumentParser:
    """The ``rotor`` parser with every command; each command's function is its ``func`` default."""
    parser = Parser(
        prog="rotor",
        description="Rotational dynamics of piston engines.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"rotor {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser, metavar="COMMAND")
    for group in COMMAND_GROUPS:
        group.add_parsers(sub)
    return parser


def _join_columns(argv: list[str]) -> list[str]:
    """``--columns -,encoder_v,time``: argparse takes a value that starts with '-' for an
    option; joined as ``--columns=-,encoder_v,time`` it is a value."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        if (
            argv[i] == "--columns"
            and i + 1 < len(argv)
            and argv[i + 1].startswith("-")
            and argv[i + 1]
            not in (
                "-h",
                "--help",
            )
        ):
            out.append(f"--columns={argv[i + 1]}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rotor`` command: run ``argv`` (default ``sys.argv[1:]``); the exit status."""
    args = build_parser().parse_args(_join_columns(list(sys.argv[1:] if argv is None else argv)))
    from ..cache import enable_compilation_cache

    enable_compilation_cache()  # the command's compiled kernels are reused by its next run
    try:
        args.func(args)
    except BrokenPipeError:  # e.g. `rotor table ... | head`
        return 0
    except SolverError as e:  # valid input, no answer: not a usage error
        print(f"rotor: {str(e).replace(chr(10), ' ')}", file=sys.stderr)
        return EXIT_SOLVER
    except (ValueError, OSError) as e:  # EngineError and LogError are ValueErrors
        msg = str(e).replace("\n", " ")
        if isinstance(e, OSError) and e.filename:
            msg = f"{e.filename}: {e.strerror}"
        print(f"rotor: error: {msg}", file=sys.stderr)
        return EXIT_USAGE
    return 0
