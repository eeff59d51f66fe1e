"""The ``rotor`` parser, assembled from each command group's ``add_parsers``, and ``main``.

Errors, each one line on stderr (with its traceback before it only under ``rotor --debug``):

- bad input (an engine or log that cannot be read, an option out of range, a file that
  cannot be written, named by the user's path: :class:`rotor.EngineError`,
  :class:`rotor.LogError`, a ``ValueError`` raised by rotor, an ``OSError``) is
  ``rotor: error: …`` and exit status 2; so is running out of memory (reduce the size);
- valid input without an answer (:class:`rotor.SolverError`): exit status 1;
- anything else (a ``TypeError``, a JAX error, a ``ValueError`` raised inside numpy or
  JAX, a NaN or infinity in a result: :class:`rotor.errors.InternalError`) is a bug in
  rotor, reported as ``rotor: internal error: this is a bug in rotor: …`` with exit
  status 70 (``EX_SOFTWARE`` of BSD's sysexits.h);
- Ctrl-C: ``rotor: interrupted``, exit status 130;
- a closed pipe (``rotor table … | head``): exit status 0.
"""

from __future__ import annotations

import argparse
import atexit
import os
import re
import signal
import sys
import threading
import traceback
import warnings
from collections.abc import Sequence
from typing import Any

from ..cache import ask_read_ahead, enable_compilation_cache
from ..errors import InternalError, RotorError, SolverError
from ..fileio import INTERRUPT

# light: see tests/cli/test_cli_latency.py
from . import demo, design, diagnostics, engine, logs, monitor, report, run, torsion
from .args import EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_SOLVER, EXIT_USAGE, Parser, error_text, terminal_safe

__all__ = [
    "COMMAND_GROUPS",
    "build_parser",
    "check_outputs",
    "command",
    "main",
    "option_names",
    "report_error",
    "warning_line",
]

COMMAND_GROUPS = (engine, run, logs, diagnostics, monitor, design, torsion, report, demo)
"""The command modules, in the order of ``rotor --help``; each has ``add_parsers(sub)``."""

EPILOG = """\
ENGINE is an engine file (.toml) or a preset name (`rotor presets`) everywhere.

One convention for options:
  --json      print the result as one JSON object (every command with a result)
  --plot DIR  write the command's plots as PNG files into DIR (every command that draws;
              `rotor plot` and `rotor demo` write to out/ unless given another DIR)
  --out DIR   only `rotor report`: the folder of the whole report (HTML page, PNG, CSV)
  --quiet     no progress bar (the commands that may show one)
  --format    only for tables (`rotor table --format text|csv`)

Exit status: 0 done; 1 a solver without an answer; 2 bad input (an option, an engine, a log,
a file that cannot be written, a run too big for the memory); 70 an internal error, a bug
in rotor (please report it); 130 interrupted (Ctrl-C). Each error is one line on stderr;
`rotor --debug COMMAND …` prints the traceback too.
`rotor COMMAND --help` for a command's options."""


_EXIT: list[int] = []  # the status of the command line that :func:`command` ran


def _exit_without_teardown() -> None:
    """At the ``rotor`` command's exit, once every other exit handler has run (this one is
    registered by :func:`command` only where none was before it, so it runs last): flush the
    output and end the process with the command's status, skipping the interpreter's
    teardown of its modules, which takes a sixth of a second once JAX is imported
    (``benchmarks/cli_latency.py`` times ``import jax, equinox`` ended both ways) and does
    nothing a finished command needs (its files are written and closed, its threads joined,
    the exit handlers run)."""
    if not _EXIT:
        return
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe or stream: what was written is out
            pass
    os._exit(_EXIT[-1])


def command() -> int:
    """The ``rotor`` command (``python -m rotor.cli`` too): :func:`main` on ``sys.argv``, the
    process then ended without the interpreter's teardown (:func:`_exit_without_teardown`)
    where no exit handler was registered before it (one registered earlier would run after
    it, so it would be skipped: the process then ends as usual)."""
    fast = getattr(atexit, "_ncallbacks", lambda: 1)() == 0
    if fast:
        atexit.register(_exit_without_teardown)
    status = main()
    if fast:
        _EXIT[:] = [status]
    return status


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
    parser.add_argument(
        "--debug", action="store_true", help="print the traceback of an error (to report a bug in rotor)"
    )
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
            argv[i] in ("--columns", "--channel")
            and i + 1 < len(argv)
            and argv[i + 1].startswith("-")
            and argv[i + 1]
            not in (
                "-h",
                "--help",
            )
        ):
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out


def _raised_outside(e: BaseException) -> bool:
    """Whether ``e`` was raised inside a third-party package (numpy, JAX, pandas, …), not in
    rotor or Python's standard library: a ``ValueError`` from there is a check rotor missed."""
    tb = e.__traceback__
    if tb is None:
        return False
    while tb.tb_next is not None:
        tb = tb.tb_next
    top = str(tb.tb_frame.f_globals.get("__name__", "")).split(".")[0]
    where = tb.tb_frame.f_code.co_filename.replace(os.sep, "/")
    return top != "rotor" and ("/site-packages/" in where or "/dist-packages/" in where)


def _quiet_interrupts(previous: Any) -> Any:
    """An unraisable-exception hook that drops a Ctrl-C Python could not raise (one landing in a
    garbage collector's callback, which it would print with a traceback), noting it as the
    interrupt flag so the run still ends with 130; anything else goes to ``previous``."""

    def hook(unraisable: Any) -> None:
        if isinstance(unraisable.exc_type, type) and issubclass(unraisable.exc_type, KeyboardInterrupt):
            INTERRUPT.set()
            return
        previous(unraisable)

    return hook


def _one_line(e: BaseException) -> str:
    return error_text(e)


_ERROR_LINE = re.compile(r"^[A-Za-z_][\w.]*(Error|Exception): ", re.MULTILINE)


def _brief(e: BaseException, limit: int = 400) -> str:
    """The gist of a foreign exception's message as one line: from the last line of the form
    ``SomeError: …`` (JAX and equinox repeat the inner error after a stack dump), its first
    paragraph, at most ``limit`` characters."""
    text = str(e)
    starts = [m.end() for m in _ERROR_LINE.finditer(text)]
    if starts:
        text = text[starts[-1] :]
    text = " ".join(text.strip().split("\n\n")[0].split())
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _silence_stdout() -> None:
    """After a closed pipe: point standard output at the null device, so that Python's
    final flush does not report the closed pipe again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no real file behind sys.stdout (a test's capture)
        pass


def warning_line(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: object = None,
    line: object = None,
) -> None:
    """Show a Python warning to a command-line user (``warnings.showwarning`` while a command
    runs): rotor's own as one line ``rotor: warning: …`` on stderr, without a source path;
    numpy's floating-point complaints ("divide by zero"), deprecations and other packages'
    warnings are not the user's business and are not shown."""
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # rotor/
    if not issubclass(category, UserWarning) or not os.path.abspath(str(filename)).startswith(package + os.sep):
        return
    print(
        f"rotor: warning: {_one_line(message if isinstance(message, BaseException) else Exception(message))}",
        file=sys.stderr,
    )


SIZE_OPTIONS = (
    ("--cycles", "cycles"),
    ("--steps-per-cycle", "steps_per_cycle"),
    ("--step", "step"),
    ("--points-per-cycle", "points_per_cycle"),
)
"""The options that set the size of a run (flag, ``args`` attribute), named where the
machine runs out of memory, each only for the commands that have it."""


def size_flags(args: argparse.Namespace | None) -> list[str]:
    """The flags of :data:`SIZE_OPTIONS` that the command of ``args`` has."""
    return [flag for flag, key in SIZE_OPTIONS if args is not None and hasattr(args, key)]


def report_error(e: BaseException, debug: bool = False, sizes: Sequence[str] = ()) -> int:
    """Print what ``e`` (an exception that reached the command line) means, as one line on
    stderr (its traceback before it when ``debug``), and return the exit status: 0 for a
    closed pipe, 1 for a :class:`rotor.SolverError`, 2 for bad input (rotor's input errors,
    a ``ValueError`` raised by rotor, a file error naming the user's path, out of memory:
    a ``MemoryError`` or XLA's ``RESOURCE_EXHAUSTED``),
    70 for an internal error (a bug in rotor: anything else, a ``TypeError`` or a JAX error
    included), 130 for Ctrl-C."""
    if isinstance(e, BrokenPipeError):  # e.g. `rotor table ... | head`
        _silence_stdout()
        return 0
    if debug:
        traceback.print_exception(e, file=sys.stderr)
    if isinstance(e, KeyboardInterrupt):
        print("rotor: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    if isinstance(e, MemoryError) or (isinstance(e, RuntimeError) and "RESOURCE_EXHAUSTED" in str(e)):
        way = ", ".join([*sizes, "or a smaller input (a shorter log, fewer masses)"] if sizes else ["a smaller input"])
        print(f"rotor: error: the machine ran out of memory: reduce the size of the run ({way})", file=sys.stderr)
        return EXIT_USAGE
    if isinstance(e, SolverError):  # valid input, no answer: not a usage error
        print(f"rotor: {_one_line(e)}", file=sys.stderr)
        return EXIT_SOLVER
    if isinstance(e, RotorError) and not isinstance(e, InternalError):  # EngineError, LogError
        print(f"rotor: error: {_one_line(e)}", file=sys.stderr)
        return EXIT_USAGE
    if isinstance(e, OSError) and not isinstance(e, InternalError):
        msg = terminal_safe(f"{e.filename}: {e.strerror}") if e.filename and e.strerror else _one_line(e)
        print(f"rotor: error: {msg}", file=sys.stderr)
        return EXIT_USAGE
    if type(e).__module__.split(".")[0] not in ("jax", "jaxlib") and isinstance(e, ValueError):
        if not _raised_outside(e):
            print(f"rotor: error: {_one_line(e)}", file=sys.stderr)
            return EXIT_USAGE
    print(
        f"rotor: internal error: this is a bug in rotor: {type(e).__name__}: {terminal_safe(_brief(e))} "
        "(run again with --debug for the traceback; please report it)",
        file=sys.stderr,
    )
    return EXIT_INTERNAL


OUTPUT_FILES = ("output", "save_calibration", "save_tooth_errors", "record")
"""The options (``args`` attributes) that name a file a command writes."""
OUTPUT_FOLDERS = {"plot": "the plots", "out": "the report"}
"""The options that name a folder a command writes into, and what it writes there."""
STANDARD_OUTPUT = frozenset({("table", "output")})
"""The (command, option) pairs whose file may be ``-``: standard output, where the file is
the command's whole result. Elsewhere ``-`` is refused: standard output already carries the
command's result (``--save-calibration``, ``--save-tooth-errors``, ``calibrate --output``),
the file has another beside it (``--record``'s truth), or the option names a folder."""
INPUT_FILES = ("engine", "log", "calibration", "tooth_errors")
"""The options (``args`` attributes) that may name a file a command reads (a value that is
no existing file, a preset's name or ``estimate``, is not one; ``-`` is standard input)."""


def option_names(parser: argparse.ArgumentParser, args: argparse.Namespace) -> dict[str, str]:
    """{``args`` attribute: how the command line spells it} for the command of ``args``:
    ``--save-tooth-errors`` for an option, ``LOG`` for a positional argument."""
    names: dict[str, str] = {}
    for action in parser._actions:  # argparse keeps a parser's options there
        if isinstance(action, argparse._SubParsersAction):
            sub = action.choices.get(str(getattr(args, "command", "")))
            for a in [] if sub is None else sub._actions:
                longs = [o for o in a.option_strings if o.startswith("--")]
                names[a.dest] = longs[0] if longs else (a.option_strings or [str(a.metavar or a.dest.upper())])[0]
    return names


def _flag(names: dict[str, str], key: str) -> str:
    return names.get(key, "--" + key.replace("_", "-"))


def _values(value: object) -> list[str]:
    """The paths an option's value names: a str, or each str of a list (several LOGs)."""
    if isinstance(value, str):
        return [value] if value else []
    if isinstance(value, (list, tuple)):
        return [v for v in value if isinstance(v, str) and v]
    return []


def _same_file(a: str, b: str) -> bool:
    """Whether the paths ``a`` and ``b`` are one existing file: one name spelt two ways, a
    link to the other, or a hard link (``os.path.samefile``: the same device and inode)."""
    try:
        return os.path.exists(a) and os.path.exists(b) and os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def check_outputs(args: argparse.Namespace, names: dict[str, str] | None = None) -> None:
    """Refuse, before the work starts, an output the command could not or must not write:

    - ``-`` where it is not standard output (:data:`STANDARD_OUTPUT`): a ``ValueError``;
    - an output file that is one of the files the command reads (:data:`INPUT_FILES`; the
      same name, a link or a hard link): a ``ValueError`` naming both options;
    - a file option (:data:`OUTPUT_FILES`, and ``--record``'s truth file beside it) naming a
      folder, a missing folder, one this user cannot write, or something that is not a
      regular file (a link, a device, a named pipe: :func:`rotor.fileio.check_writable_file`);
    - a folder option (:data:`OUTPUT_FOLDERS`) naming a file, a link to nothing or a folder
      that cannot be written or made.

    Each is one line naming the user's path; ``names``: how the command line spells each
    option (:func:`option_names`; default ``--`` and the attribute's name)."""
    from ..fileio import check_folder_writable, check_writable_file

    names = names or {}
    command = getattr(args, "command", None)
    outputs: list[tuple[str, str]] = []  # (the option's words, the path)
    for key in OUTPUT_FILES:
        value = getattr(args, key, None)
        if not (isinstance(value, str) and value):
            continue
        flag = _flag(names, key)
        if value == "-":
            if (command, key) in STANDARD_OUTPUT:
                continue
            why = (
                "the log is written with its truth file beside it, so it needs a file's name"
                if key == "record"
                else "standard output carries the command's result"
            )
            raise ValueError(f"{flag} -: not standard output here ({why}): give a file name")
        outputs.append((flag, value))
        if key == "record":
            from ..diagnostics.record import truth_path

            outputs.append((f"the truth file of {flag}", os.fspath(truth_path(value))))
    for key in OUTPUT_FOLDERS:
        value = getattr(args, key, None)
        if value == "-":
            flag = _flag(names, key)
            raise ValueError(f"{flag} -: {flag} names a folder, not standard output: give a folder")
    inputs = [(_flag(names, k), v) for k in INPUT_FILES for v in _values(getattr(args, k, None)) if v != "-"]
    for out_flag, out in outputs:
        for in_flag, inp in inputs:
            if _same_file(out, inp):
                raise ValueError(
                    f"{out_flag} {out} is the same file as {in_flag} {inp}, which this command reads: "
                    f"give {out_flag} another file"
                )
    for _, path in outputs:
        check_writable_file(path)
    for key, what in OUTPUT_FOLDERS.items():
        value = getattr(args, key, None)
        if isinstance(value, str) and value:
            check_folder_writable(value, what)


def _on_interrupt(signum: int, frame: object) -> None:
    """SIGINT: note the interrupt as a flag (:data:`rotor.fileio.INTERRUPT`), then raise
    ``KeyboardInterrupt`` as Python does. Where that exception is dropped (raised inside a
    garbage collector's callback), the flag still stops the run: before a file is put in
    place and before the exit."""
    INTERRUPT.set()
    raise KeyboardInterrupt


def _catch_interrupts() -> object:
    """Install :func:`_on_interrupt` for SIGINT (in the main thread, where Python's own
    handler is in place); the handler it replaced, or None."""
    if threading.current_thread() is not threading.main_thread():
        return None
    previous = signal.getsignal(signal.SIGINT)
    if previous is not signal.default_int_handler:
        return None  # SIGINT ignored, or handled by the caller: theirs stays
    signal.signal(signal.SIGINT, _on_interrupt)
    return previous


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rotor`` command: run ``argv`` (default ``sys.argv[1:]``); the exit
    status (see the module's docstring: 0, 1, 2, 70 or 130).

    Switches JAX's persistent compilation cache on (:func:`rotor.enable_compilation_cache`;
    with ``argv`` None, a command line of its own, for every kernel however small). Builds
    the parser without importing JAX: the commands import what they compute with, so that
    ``rotor --help`` and ``rotor presets`` never import it.

    Ctrl-C is noted as a flag as well as raised (:func:`_on_interrupt`): a command whose
    interrupt was dropped on the way still ends with exit status 130, its files not put in
    place. A command that fails removes the folders it made for its output. The ``rotor``
    command calls it through :func:`command`."""
    from .output import MADE_FOLDERS, remove_made_folders

    INTERRUPT.clear()
    MADE_FOLDERS.clear()
    previous = _catch_interrupts()
    unraisable = sys.unraisablehook
    sys.unraisablehook = _quiet_interrupts(unraisable)
    task, finished = None, False
    try:
        words = _join_columns(list(sys.argv[1:] if argv is None else argv))
        try:
            parser = build_parser()
            args = parser.parse_args(words)
        except KeyboardInterrupt as e:  # Ctrl-C while the command's modules load
            return report_error(e)
        try:
            # the command's compiled kernels are reused by its next run; from the command line
            # (argv None, a process of its own) its small eager kernels too, which a long
            # Python session calling main(argv) should not pile up in the cache
            enable_compilation_cache(min_compile_time_s=0.0 if argv is None else 0.1)
            # the kept programs its last run used, loaded on a thread once the command
            # imports JAX, while it goes on importing its modules and reading its input
            task = "\0".join(["rotor", *words])
            ask_read_ahead(task)
            check_outputs(args, option_names(parser, args))
            with warnings.catch_warnings():
                warnings.simplefilter("default")  # each distinct warning once
                warnings.showwarning = warning_line
                args.func(args)
            INTERRUPT.check()  # an interrupt dropped on the way: not a finished run
            sys.stdout.flush()  # a closed pipe is found here, not at the interpreter's exit
        except SystemExit:
            raise
        except BaseException as e:  # noqa: BLE001 - every exception is reported, none as a raw traceback
            remove_made_folders()
            return report_error(e, debug=args.debug, sizes=size_flags(args))
        finished = True
        return 0
    finally:
        INTERRUPT.clear()  # reported: a later call in this process starts afresh
        if task is not None:
            ask_read_ahead(None)
            programs = sys.modules.get("rotor.programs")  # imported where the command computed with JAX
            if programs is not None:  # the reading ahead stopped; a finished run's programs noted
                programs.remember_programs(task if finished else None)
        sys.unraisablehook = unraisable
        if previous is not None:
            signal.signal(signal.SIGINT, previous)  # type: ignore[arg-type]
