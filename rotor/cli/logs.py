"""``rotor analyze``: a logged crank speed, cycle by cycle."""

from __future__ import annotations

import argparse
import os
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from .args import (
    add_edge,
    add_json,
    add_plot,
    add_quiet,
    angle_deg,
    cli_json_words,
    cli_words,
    error_text,
    positive_float,
    whole,
)
from .output import plot_folder, print_json, print_text, print_written, save_plot

__all__ = [
    "PLOT_LOCK",
    "FileOutput",
    "add_bulk",
    "add_parsers",
    "cmd_analyze",
    "cmd_wheels",
    "cylinder_count",
    "for_each_log",
    "log_plot",
]

PLOT_LOCK = threading.Lock()
"""Held while a file's plot is drawn and saved: matplotlib's pyplot is not thread-safe, and
several LOGs run on threads (``--jobs``)."""

BULK_HELP = (
    "; several LOGs, or a glob pattern such as 'logs/*.csv' (quoted: rotor expands it itself), are done in one "
    "run across --jobs threads (or --scheduler's Dask cluster): with --json one JSON line per file in the "
    'order given, {"file": LOG, ...the result...} or {"file": LOG, "error": ..., "exit_status": ...}; '
    "without, each file's summary under a ==> LOG <== line. A bad file does not stop the others: the exit "
    "status is 0 when every file was done, else the highest of the failed files' (1 a solver without an "
    "answer, 2 a bad file, 70 a bug), and a pattern that matches no file is an error (2)"
)


def cylinder_count(text: str) -> int:
    """``--cylinders``: a whole number from 1 to the most cylinders of any engine
    (:data:`rotor.engine.model.MAX_CYLINDERS`, read when the option is given)."""
    n = whole(text)
    from ..engine.model import MAX_CYLINDERS

    if n > MAX_CYLINDERS:
        raise argparse.ArgumentTypeError(f"{text!r}: at most {MAX_CYLINDERS} cylinders (more than any engine built)")
    return n


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``analyze`` to the subcommands ``sub``."""
    p = sub.add_parser("analyze", help="logged crank speed: per-cycle mean speed, δ and orders from a wheel signal")
    p.add_argument(
        "log",
        metavar="LOG",
        nargs="+",
        help="log (CSV/TSV text, or an MDF, TDMS, MATLAB .mat, Parquet or Arrow file): tooth times, a sampled "
        "wheel signal, logic-analyser transitions, or time and rpm" + BULK_HELP,
    )
    p.add_argument(
        "--wheel",
        metavar="SPEC",
        help="trigger wheel: a catalogue name (`rotor wheels` lists them: mazda-nb-crank, gm-24x, …), N-M (60-2, "
        "36-1), N-g1-g2… (36-2-1, 36-2-2-2: N positions, the missing teeth of each gap; where they lie is found "
        "from the log), a wheel file (.toml), or N alone with an index_v column; default auto: found from the "
        "log, every catalogue pattern tried; angle 0 = the first tooth after gap 1",
    )
    p.add_argument(
        "--columns",
        "--channel",
        metavar="NAMES",
        help="column names in file order: time, encoder_v, pressure_v, cam_v, index_v, encoder_d, cam_d "
        "(digital 0/1 channels, one row per transition), tooth_time_s, rpm, - (skip), e.g. "
        "time,pressure_v,encoder_v or time,encoder_d,-; a time in ms or µs: time_ms, time_us, tooth_time_ms, "
        "tooth_time_us; or the file's channels by role, time=t,crank=CRANK (any format; roles crank, cam, "
        "pressure, speed besides the names above); --channel is the same option; default: recognised by "
        "their content",
    )
    p.add_argument(
        "--strokes", type=int, choices=(2, 4), default=4, help="strokes per cycle of the engine logged (default 4)"
    )
    p.add_argument(
        "--cylinders",
        type=cylinder_count,
        default=1,
        metavar="N",
        help="cylinders of the (evenly firing) engine, default 1: a tooth-error estimate from the log "
        "leaves the multiples of the firing order to the engine",
    )
    p.add_argument(
        "--tdc-deg",
        type=angle_deg,
        metavar="DEG",
        help="angle from the gap to TDC of cylinder 1 [deg] (default: as the log's header states it, "
        "# tdc_after_gap_deg, else from the pressure channel, else 0)",
    )
    p.add_argument(
        "--firing",
        default="auto",
        choices=("auto", "pressure", "cam", "speed", "0", "1"),
        help="which revolution fires (4-stroke; default auto: pressure, cam, else speed)",
    )
    p.add_argument(
        "--compression-ratio",
        type=positive_float,
        metavar="R",
        help="for TDC from the pressure by a polytropic fit (with --rod-ratio)",
    )
    p.add_argument("--rod-ratio", type=positive_float, metavar="LAMBDA", help="crank radius / rod length")
    p.add_argument(
        "--tooth-errors",
        default="estimate",
        metavar="estimate|none|FILE",
        help="tooth-spacing correction: estimate from this log (default), none, or a JSON file",
    )
    p.add_argument(
        "--engine-orders",
        default="auto",
        metavar="auto|none|K,K",
        help="orders of the per-revolution pattern left to the engine when estimating (default auto)",
    )
    p.add_argument(
        "--engine",
        metavar="ENGINE",
        help="engine file or preset on the wheel: its inertia ripple is taken "
        "out of the tooth-error estimate (needs --tdc-deg), so its own fuel-cut coast-down calibrates the "
        "wheel",
    )
    p.add_argument("--save-tooth-errors", metavar="FILE", help="write the tooth errors applied as JSON")
    p.add_argument(
        "--max-order",
        type=positive_float,
        help="highest order reported and used for δ (default teeth/4; 0.5 or more for a four-stroke, 1 for a two-stroke)",
    )
    p.add_argument(
        "--points-per-cycle",
        type=whole,
        metavar="P",
        help="points of the uniform angle grid per cycle (default 2 per tooth pitch, more if --max-order needs them)",
    )
    p.add_argument(
        "--no-denoise",
        action="store_true",
        help="δ from all orders up to --max-order, not weighted by their signal-to-noise ratio",
    )
    add_edge(p)
    add_json(p)
    add_plot(p, "the combined plot")
    add_bulk(p)
    p.set_defaults(func=cmd_analyze)

    p = sub.add_parser("wheels", help="list the trigger patterns rotor knows (crank and cam wheels), or one's edges")
    p.add_argument("name", metavar="NAME", nargs="?", help="a pattern's name or alias, or N-g1-g2… (e.g. 36-2-1)")
    add_json(p)
    p.set_defaults(func=cmd_wheels)


def add_bulk(p: argparse.ArgumentParser) -> None:
    """``--jobs``, ``--scheduler`` and ``--quiet`` of a command over several LOGs."""
    p.add_argument(
        "--jobs",
        "-j",
        type=whole,
        metavar="N",
        help="with several LOGs: files done at once, by threads sharing this process's compiled code "
        "(default: the machine's cores; 1 = one after the other)",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="with several LOGs: run them on the Dask cluster whose scheduler is at ADDRESS, e.g. "
        "tcp://10.0.0.5:8786 (its workers need rotor and the files' paths; needs the dask extra: "
        "pip install 'crank-rotor[dask]')",
    )
    add_quiet(p)


def log_plot(drawn: object, folder: str, log: str, kind: str) -> str:
    """Save a plot of the log ``log`` as ``folder/<log stem>_<kind>.png``; the path."""
    plot_folder(folder)
    stem = os.path.splitext(os.path.basename(log))[0]
    return save_plot(drawn, folder, f"{stem}_{kind}.png")


def _engine_orders(text: str) -> str | tuple[int, ...]:
    from ..errors import LogError

    if text == "auto":
        return "auto"
    if text == "none":
        return ()
    try:
        return tuple(int(k) for k in text.split(","))
    except ValueError:
        raise LogError(f"--engine-orders {text!r}: auto, none, or whole orders such as 1,2,3") from None


def cmd_analyze(args: argparse.Namespace) -> None:
    """Analyse the log (or each of several): its summary or JSON, the tooth errors and the plot if asked for."""
    from ..errors import LogError

    if (args.compression_ratio is None) != (args.rod_ratio is None):
        raise LogError("--compression-ratio and --rod-ratio go together")
    for_each_log(args, analyze_file, "analysing", one_only=("save_tooth_errors",))


def _engine_of(name: str | None) -> Any:
    """The engine of ``--engine`` (a preset or an engine file), or None: JAX is imported only
    where an engine is given (a log alone is read with NumPy)."""
    if not name:
        return None
    from ..engine.file import load_engine

    return load_engine(name)


def analyze_file(args: argparse.Namespace, log: str) -> FileOutput:
    """``rotor analyze`` of the one file ``log`` with the options ``args``: what it prints and writes."""
    from ..errors import LogError
    from ..logs.analysis import analyze_log

    tdc_deg, firing = args.tdc_deg, int(args.firing) if args.firing in ("0", "1") else args.firing
    if tdc_deg is None:  # a log that states its phase (rotor simulate --record) is read at it
        from ..diagnostics.stated import stated_phase

        stated = stated_phase(log)
        if stated is not None:
            tdc_deg, firing = stated[0], stated[1] if firing == "auto" else firing
    res = analyze_log(
        log,
        args.wheel,
        columns=args.columns,
        strokes=args.strokes,
        cylinders=args.cylinders,
        tdc_deg=tdc_deg,
        firing=firing,
        tooth_errors={"estimate": "estimate", "none": None}.get(args.tooth_errors, args.tooth_errors),
        engine_orders=_engine_orders(args.engine_orders),
        max_order=args.max_order,
        points_per_cycle=args.points_per_cycle,
        edge=args.edge,
        compression_ratio=args.compression_ratio,
        rod_ratio=args.rod_ratio,
        denoise=not args.no_denoise,
        engine=_engine_of(args.engine),
    )
    written = []
    if args.save_tooth_errors:
        if res.tooth_errors is None:
            raise LogError("--save-tooth-errors: no tooth errors were applied (--tooth-errors none, or a speed log)")
        res.tooth_errors.save(args.save_tooth_errors)
        written.append(args.save_tooth_errors)
    if args.plot:
        with PLOT_LOCK:
            written.append(log_plot(res.plot(), args.plot, log, "analysis"))
            if res.reading is not None:  # the signal as read: levels, edges and repairs
                written.append(log_plot(res.reading.plot(), args.plot, log, "reading"))
    return FileOutput(res.to_json_dict(), "", written) if args.json else FileOutput({}, res.summary(), written)


# ----------------------------------------------------------------------------- several LOGs
@dataclass
class FileOutput:
    """What a log command prints and writes for one file: its JSON (``to_json_dict()``, with
    ``--json``) or its text summary (without: only the one asked for is made), the files it
    wrote and its warnings (for stderr)."""

    json: dict
    text: str
    written: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:  # the library's notes name arguments, the command line flags
        self.json, self.text = cli_json_words(self.json), cli_words(self.text)
        self.warnings = [cli_words(w) for w in self.warnings]


def _print_one(args: argparse.Namespace, log: str, out: FileOutput) -> None:
    """A single LOG's output, as the command has always printed it."""
    for w in out.warnings:  # on stderr too, where a pipe or --json would hide it
        print(f"rotor: warning: {log}: {w}", file=sys.stderr)
    if args.json:
        print_json(out.json, indent=1)
    else:
        print_text(out.text)
        print_written(out.written)


def _error_line(e: Exception) -> tuple[int, str]:
    """The exit status and the one line ``rotor`` reports for ``e`` (``rotor: error: …``):
    the classification of :func:`rotor.cli.app.report_error` (which this module cannot
    import: app imports it), for one file among several; ``tests/diagnostics/test_bulk.py`` holds the
    two to the same answers."""
    import traceback

    from ..errors import InternalError, RotorError, SolverError

    text = error_text(e)
    if isinstance(e, MemoryError) or (isinstance(e, RuntimeError) and "RESOURCE_EXHAUSTED" in str(e)):
        return 2, "rotor: error: the machine ran out of memory: reduce the size of the run (a shorter log)"
    if isinstance(e, SolverError):
        return 1, f"rotor: {text}"
    if isinstance(e, RotorError) and not isinstance(e, InternalError):
        return 2, f"rotor: error: {text}"
    if isinstance(e, OSError) and not isinstance(e, InternalError):
        return 2, f"rotor: error: {e.filename}: {e.strerror}" if e.filename and e.strerror else f"rotor: error: {text}"
    if isinstance(e, ValueError) and type(e).__module__.split(".")[0] not in ("jax", "jaxlib"):
        last = traceback.extract_tb(e.__traceback__)[-1:] if e.__traceback__ else []
        where = last[0].filename.replace(os.sep, "/") if last else ""
        if not ("/site-packages/" in where or "/dist-packages/" in where):
            return 2, f"rotor: error: {text}"
    brief = " ".join(text.split())
    brief = brief if len(brief) <= 400 else brief[:399] + "…"
    return 70, f"rotor: internal error: this is a bug in rotor: {type(e).__name__}: {brief} (please report it)"


def _bulk_file(one: Callable[[argparse.Namespace, str], FileOutput], args: argparse.Namespace, log: str) -> dict:
    """Run ``one`` on ``log`` (in a worker): its output, or its error's exit status and line."""
    try:
        out = one(args, log)
    except Exception as e:  # noqa: BLE001 - one file's error is that file's line
        status, line = _error_line(e)
        return {"output": None, "status": status, "line": line}
    return {"output": out, "status": 0, "line": ""}


def _with_file(line: str, log: str) -> tuple[str, str]:
    """``rotor: error: MSG`` → (``rotor: error: LOG: MSG``, ``MSG``), the file named once."""
    for head in ("rotor: error: ", "rotor: internal error: this is a bug in rotor: ", "rotor: "):
        if line.startswith(head):
            msg = line[len(head) :]
            return head + (msg if msg.startswith(log) else f"{log}: {msg}"), msg
    return f"rotor: {log}: {line}", line


def _dask_client(address: str) -> Any:
    from ..diagnostics.bulk import DASK_HINT
    from ..errors import EngineError

    try:
        from distributed import Client
    except ImportError:
        raise EngineError(f"--scheduler needs Dask, which is not installed: {DASK_HINT}") from None
    try:
        return Client(address, timeout=10)
    except (OSError, TimeoutError, ValueError) as e:
        raise EngineError(f"--scheduler {address}: cannot reach the Dask scheduler ({e})") from None
    except (MemoryError, Exception) as e:  # noqa: BLE001 - whatever a server that is no scheduler makes the client raise
        raise EngineError(
            f"--scheduler {address}: what answers there is not a Dask scheduler ({type(e).__name__}); give the "
            "address a Dask scheduler prints (tcp://HOST:8786)"
        ) from None


def for_each_log(
    args: argparse.Namespace,
    one: Callable[[argparse.Namespace, str], FileOutput],
    verb: str,
    one_only: tuple[str, ...] = (),
) -> None:
    """Run ``one(args, log)`` on the command's LOG(s) (``args.log``, a list) and print.

    One LOG that is not a pattern: in this process, printed as the command always has (an
    error is the command's error). Several, or a pattern: expanded, then run across
    ``--jobs`` local processes or on the ``--scheduler`` cluster; printed in the order given
    (one JSON line per file with ``--json``), a progress bar on stderr unless ``--quiet``;
    the exit status is the highest of the failed files' (0 when none failed).
    ``one_only``: options (``args`` names) that take a single LOG."""
    import functools

    from ..diagnostics.bulk import expand_logs, is_pattern, map_files
    from ..errors import LogError
    from ..progress import Progress

    logs = [args.log] if isinstance(args.log, str) else list(args.log)
    client = _dask_client(args.scheduler) if getattr(args, "scheduler", None) else None
    try:
        if len(logs) == 1 and not is_pattern(logs[0]):
            _print_one(args, logs[0], one(args, logs[0]))
            return
        for name in one_only:
            if getattr(args, name, None):
                raise LogError(f"--{name.replace('_', '-')} takes a single LOG, not several")
        paths = expand_logs(logs)
        fn = functools.partial(_bulk_file, one, args)
        bar = Progress(len(paths), False if args.quiet else None, verb, unit="files")
        outcomes = map_files(fn, paths, jobs=args.jobs, client=client, progress=False)
        pending: dict[int, dict] = {}
        nxt, failed, worst = 0, 0, 0
        for done, (i, ok, value) in enumerate(outcomes, 1):
            if not ok:  # _bulk_file itself failed: a bug
                value = {
                    "output": None,
                    "status": 70,
                    "line": f"rotor: internal error: {type(value).__name__}: {value}",
                }
            pending[i] = value
            while nxt in pending:
                got, log = pending.pop(nxt), paths[nxt]
                bar.clear()
                if got["output"] is None:
                    failed, worst = failed + 1, max(worst, got["status"])
                    shown, msg = _with_file(got["line"], log)
                    print(shown, file=sys.stderr)
                    if args.json:
                        print_json({"file": log, "error": msg, "exit_status": got["status"]}, indent=None)  # type: ignore[arg-type]
                else:
                    out: FileOutput = got["output"]
                    for w in out.warnings:
                        print(f"rotor: warning: {log}: {w}", file=sys.stderr)
                    if args.json:
                        print_json({"file": log, **out.json}, indent=None)  # type: ignore[arg-type]
                    else:
                        print_text(("\n" if nxt else "") + f"==> {log} <==\n" + out.text)
                        print_written(out.written)
                sys.stdout.flush()
                nxt += 1
            bar.update(done)
        bar.close()
        if failed:
            print(f"rotor: {failed} of {len(paths)} files failed", file=sys.stderr)
            raise SystemExit(worst)
    finally:
        if client is not None:
            client.close()


def cmd_wheels(args: argparse.Namespace) -> None:
    """The trigger-pattern catalogue, a line a pattern; with a name, that pattern's edges."""
    from ..logs.catalogue import CATALOGUE, find_pattern

    if args.name is not None:
        pat = find_pattern(args.name)
        if args.json:
            print_json(pat.to_json_dict())
            return
        rows = [
            pat.describe(),
            f"  kind {pat.kind}, turn {pat.period_deg:g}° of crankshaft, position carried by {pat.read} edges",
            "  rising edges [deg]:  " + (", ".join(f"{x:g}" for x in pat.rising_deg) or "not stated"),
            "  falling edges [deg]: " + (", ".join(f"{x:g}" for x in pat.falling_deg) or "not stated"),
        ]
        if pat.aliases:
            rows.append("  also known as: " + ", ".join(pat.aliases))
        if pat.source:
            rows.append(f"  geometry: {pat.source}")
        print_text("\n".join(rows))
        return
    if args.json:
        print_json({"patterns": [p.to_json_dict() for p in CATALOGUE.values()]})
        return
    lines = [
        f"{p.name:24s} {p.kind:5s} {p.edges_per_turn:3d} edges/{p.period_deg:g}°  {p.title}" for p in CATALOGUE.values()
    ]
    lines.append("any N-g1-g2… wheel by its shorthand too (e.g. 60-2, 36-2-2-2); `rotor wheels NAME` shows one's edges")
    print_text("\n".join(lines))
