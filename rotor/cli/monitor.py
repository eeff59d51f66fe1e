"""``rotor monitor``: a misfire verdict per firing while tooth times stream in."""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any

from .args import add_json, angle_deg, percent_of_firings, positive_float, whole

__all__ = ["add_parsers", "cmd_monitor", "CHUNK_BYTES", "FOLLOW_POLL_S"]

CHUNK_BYTES = 65536
"""The most bytes read at a time (a pipe hands over what it holds, up to this)."""
FOLLOW_POLL_S = 0.2
"""With --follow: how long to wait at the end of the file before looking again [s]."""
TAIL_BYTES = 64
"""With --follow: the last bytes read, looked for again before reading on (a file truncated
and written again past the place read shows other bytes there)."""


AUTO_EDGES = 4000
"""With ``--wheel auto``, the wheel is found from this many edges before the first verdict."""


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``monitor`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "monitor",
        help="misfire monitor on tooth times as they arrive: one verdict per firing (a file, a pipe, a growing file)",
    )
    p.add_argument(
        "log",
        metavar="LOG|-",
        help="tooth edge times [s], one per line (as `rotor simulate --record` writes them; LF, CRLF or CR line "
        "ends); a header line 'tooth_time_ms' or 'tooth_time_us' gives them in ms or µs; - reads standard input",
    )
    p.add_argument(
        "--engine",
        metavar="ENGINE",
        help="engine file or preset: cylinders, strokes, firing angles and each firing's IMEP from the model "
        "(else --cylinders and --firing-order: no IMEP)",
    )
    p.add_argument(
        "--wheel",
        default="auto",
        metavar="SPEC",
        help="trigger wheel with a gap, e.g. 60-2, 36-1, 36-2-1, or auto (the default: found from the log's first "
        f"{AUTO_EDGES} edges, or all of a shorter log, as rotor analyze finds it)",
    )
    p.add_argument("--cylinders", type=_cylinders, metavar="N", help="cylinders, without --engine")
    p.add_argument(
        "--firing-order", type=_order, metavar="1,3,4,2", help="firing order, without --engine (default 1,2,…)"
    )
    p.add_argument("--strokes", type=int, choices=(2, 4), default=4, help="without --engine: 4 (default) or 2")
    p.add_argument(
        "--tdc-deg",
        type=angle_deg,
        metavar="DEG",
        help="cylinder 1's TDC after the gap [deg] (default: the log's header line '# tdc_after_gap_deg')",
    )
    p.add_argument(
        "--firing-parity",
        type=int,
        choices=(0, 1),
        help="which revolutions from the first gap hold cylinder 1's firing TDC (default: the log's header, else 0)",
    )
    p.add_argument(
        "--threshold",
        type=positive_float,
        metavar="X",
        help="a misfire where the index falls below -X baseline spreads (default 8)",
    )
    p.add_argument(
        "--emission-rate",
        type=percent_of_firings,
        metavar="PCT",
        help="the emission threshold: misfires in %% of the firings over an emission window (default 1)",
    )
    p.add_argument(
        "--catalyst-table",
        metavar="FILE",
        help='the catalyst-damage misfire rate over speed and load, a JSON file {"rpm": [...], "load": [...], '
        '"rate_pct": [[...], ...]} (a row per speed, load 0 … 1 of full; default an example table, not an '
        "engine's calibration)",
    )
    p.add_argument(
        "--catalyst-revolutions",
        type=whole,
        metavar="N",
        help="revolutions of the catalyst-damage window (default 200)",
    )
    p.add_argument(
        "--emission-revolutions", type=whole, metavar="N", help="revolutions of the emission window (default 1000)"
    )
    p.add_argument(
        "--window-step",
        type=whole,
        metavar="N",
        help="the windows are judged every N revolutions (default 200: consecutive catalyst windows, emission "
        "windows sliding by 200)",
    )
    p.add_argument(
        "--last-cycle",
        type=whole,
        metavar="K",
        help="the log's last cycle: firings after it are not judged (default: the cycles of the truth file "
        "`rotor simulate --record` writes beside its log, else none)",
    )
    p.add_argument(
        "--follow",
        action="store_true",
        help="at the end of the file, wait for more (a file truncated or replaced is read again from its start, "
        "and that said on stderr; Ctrl-C ends)",
    )
    add_json(p)
    p.set_defaults(func=cmd_monitor)


def _thresholds(args: argparse.Namespace) -> Any:
    """The windows and thresholds of the options (the defaults where none is given)."""
    import dataclasses
    import json

    from ..diagnostics.misfire_rate import CatalystTable, MisfireThresholds
    from ..errors import EngineError

    given: dict[str, Any] = {}
    if args.catalyst_table is not None:
        try:
            with open(args.catalyst_table, encoding="utf-8") as f:
                data = json.load(f)
        except json.JSONDecodeError as e:
            raise EngineError(f"--catalyst-table {args.catalyst_table}: not JSON ({e.msg}, line {e.lineno})") from None
        try:
            given["catalyst"] = CatalystTable.from_dict(data)
        except EngineError as e:
            raise EngineError(f"--catalyst-table {args.catalyst_table}: {e}") from None
    for flag, field in (
        ("emission_rate", "emission_pct"),
        ("catalyst_revolutions", "catalyst_revolutions"),
        ("emission_revolutions", "emission_revolutions"),
        ("window_step", "step_revolutions"),
    ):
        if getattr(args, flag) is not None:
            given[field] = getattr(args, flag)
    return dataclasses.replace(MisfireThresholds(), **given)


def _truth_cycles(path: str) -> int | None:
    """The run's last cycle from the truth file ``rotor simulate --record`` writes beside its
    log (cycles counted from 1); None where there is none (or it is another log's)."""
    import json

    from ..diagnostics.record import truth_path

    try:
        truth = truth_path(path)
        with open(truth, encoding="utf-8") as f:
            d = json.load(f)
    except (OSError, ValueError):
        return None
    cycles, first = d.get("cycles"), d.get("cycles_counted_from", 1)
    if isinstance(cycles, int) and cycles >= 1 and first == 1 and d.get("log") == os.path.basename(path):
        return cycles
    return None


def _last_cycle(args: argparse.Namespace) -> int | None:
    """The log's last cycle: ``--last-cycle``, else the run's cycles by the truth file beside
    a recorded log (the summary says how many firings after it were not judged), else None."""
    if args.last_cycle is not None or args.log == "-" or not os.path.isfile(args.log):
        return args.last_cycle
    return _truth_cycles(args.log)


def _cylinders(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 1 <= n <= 64:
        raise argparse.ArgumentTypeError(f"{text!r}: cylinders from 1 to 64")
    return n


def _order(text: str) -> list[int]:
    try:
        return [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: cylinder numbers separated by commas, e.g. 1,3,4,2") from None


class _Source:
    """Text from a file or standard input, read in chunks as it comes. With ``follow``, at
    the end of the file it waits for more, and before it reads on notices a file truncated
    (its size below what was read, or the bytes before the place it reads from no longer
    those it read: truncated and written again) or replaced (another file under its name:
    rotated, or removed and made again): it reads the file again from its start, and
    :attr:`event` says so (the caller reads it after each call)."""

    def __init__(self, name: str, follow: bool) -> None:
        self.follow = follow
        self.name = name
        self.event: str | None = None
        self._gone = False
        self._at_end = False  # waited at the end of the file: look at it before reading on
        self._tail = b""  # the last bytes read
        if name == "-":
            self.stream: Any = getattr(sys.stdin, "buffer", sys.stdin)
            self.own = False
        else:
            self.stream = open(name, "rb")  # noqa: SIM115 - closed by close()
            self.own = True
        self._decoder = _Decoder()

    def read(self) -> str | None:
        """The next text ("" after an :attr:`event`), or None at the end of the input."""
        from ..fileio import INTERRUPT

        while True:
            if self._at_end:
                self.event = self._changed()
                if self.event is not None:
                    self._at_end, self._tail = False, b""
                    return ""
            reader = getattr(self.stream, "read1", None)
            data = reader(CHUNK_BYTES) if reader is not None else self.stream.read(CHUNK_BYTES)
            if data:
                self._at_end = False
                if self.follow:
                    self._tail = (self._tail + data[-TAIL_BYTES:])[-TAIL_BYTES:]
                return self._decoder(data)
            if not (self.follow and self.own):
                return None
            INTERRUPT.check()  # an interrupt dropped on the way (in a garbage collector's callback) ends the wait
            self._at_end = True
            time.sleep(FOLLOW_POLL_S)

    def _changed(self) -> str | None:
        """What became of the followed file, if it changed other than by growing."""
        try:
            now = os.stat(self.name)
        except FileNotFoundError:
            if self._gone:
                return None
            self._gone = True
            return f"{self.name} was removed: waiting for a file of that name to follow"
        was = os.fstat(self.stream.fileno())
        if (now.st_ino, now.st_dev) != (was.st_ino, was.st_dev):
            if self.stream.read(1):  # written to before it was replaced: read that first
                self.stream.seek(-1, os.SEEK_CUR)
                return None
            self.stream.close()
            self.stream = open(self.name, "rb")  # noqa: SIM115 - closed by close()
            self._decoder = _Decoder()
            self._gone = False
            return f"{self.name} was replaced by another file (rotated?): following the new one from its start"
        read = self.stream.tell()
        size = len(self._tail)
        if now.st_size < read or (size and os.pread(self.stream.fileno(), size, read - size) != self._tail):
            self.stream.seek(0)
            self._decoder = _Decoder()
            return (
                f"{self.name} was truncated ({now.st_size} bytes now, {read} read before): reading it again "
                "from its start"
            )
        return None

    def close(self) -> None:
        if self.own:
            self.stream.close()


class _Decoder:
    def __init__(self) -> None:
        import codecs

        self._d = codecs.getincrementaldecoder("utf-8")(errors="replace")

    def __call__(self, data: bytes | str) -> str:
        return data if isinstance(data, str) else self._d.decode(data)


NOTES_SHOWN = 3
"""Notes of one kind printed on stderr; the rest are counted (the summary gives their number)."""


class _Notes:
    """The notes on stderr, at most :data:`NOTES_SHOWN` of a kind, then one line saying that
    the rest are counted: what a long bad stream prints stays bounded."""

    def __init__(self) -> None:
        import collections

        self.counts: collections.Counter = collections.Counter()

    def __call__(self, kind: str, text: str, level: str = "warning") -> None:
        self.counts[kind] += 1
        n = self.counts[kind]
        if n <= NOTES_SHOWN:
            print(f"rotor: {level}: {text}", file=sys.stderr, flush=True)
        elif n == NOTES_SHOWN + 1:
            print(
                f"rotor: {level}: more notes '{kind}' are counted, not shown: the summary at the end gives how many",
                file=sys.stderr,
                flush=True,
            )


def cmd_monitor(args: argparse.Namespace) -> None:
    """Read the log in chunks, print each verdict as it is decided (a JSON object per line
    with --json), the notes on the stream on stderr (a few of each kind), the per-cylinder
    summary at the end; a log on which no firing was judged is an error."""
    from ..errors import EngineError

    if args.engine is None and args.cylinders is None:
        raise EngineError("--engine ENGINE or --cylinders N (with --firing-order): the monitor needs the firing angles")
    if args.engine is not None and (args.cylinders is not None or args.firing_order is not None):
        raise EngineError("--cylinders and --firing-order are for a monitor without --engine: give one or the other")
    if args.follow and args.log == "-":
        raise EngineError("--follow follows a file as it grows; standard input is followed to its end anyway")
    _monitor(args)  # a Ctrl-C in a garbage collector's callback: dropped quietly by rotor.cli.app.main


def _check_input(args: argparse.Namespace) -> None:
    """The LOG argument refused where it is no file, named pipe or standard input."""
    from ..errors import LogError

    if args.log != "-" and os.path.isdir(args.log):
        raise IsADirectoryError(21, "Is a directory", args.log)
    if args.log != "-" and not os.path.isfile(args.log):
        import stat

        if not os.path.exists(args.log):
            raise FileNotFoundError(2, "No such file", args.log)
        if not stat.S_ISFIFO(os.stat(args.log).st_mode):  # a named pipe is a stream, read as it comes
            raise LogError(
                f"{args.log}: is a device or socket, not a log; give a file, a named pipe or - (standard input)"
            )
        if args.follow:
            raise LogError(f"{args.log}: is a named pipe: it is read as it comes without --follow")


def _monitor(args: argparse.Namespace) -> None:
    import numpy as np

    from ..diagnostics.monitor import DEFAULT_THRESHOLD, MisfireMonitor, NoteKind, ToothLines, check_wheel
    from ..errors import EngineError, LogError
    from ..fileio import INTERRUPT
    from .output import json_line

    engine = None
    if args.engine is not None:
        from ..engine.file import load_engine

        engine = load_engine(args.engine)
    _check_input(args)
    name = "standard input" if args.log == "-" else args.log
    thresholds = _thresholds(args)
    show = _Notes()
    last_cycle = _last_cycle(args)
    # the wheel and the firings checked before anything is read (a wheel too coarse for the
    # monitor refused at once, not at the first edges)
    auto = args.wheel.strip().lower() == "auto"
    if not auto:
        check_wheel(
            args.wheel, engine=engine, cylinders=args.cylinders, firing_order=args.firing_order, strokes=args.strokes
        )
    waiting: list = []  # with --wheel auto, the edges read before the wheel is found
    source = _Source(args.log, args.follow)
    lines = ToothLines(name=name)
    monitor: MisfireMonitor | None = None

    def emit(verdicts: list) -> None:
        # the notes first: what was met on the stream comes before the verdicts it bears on
        if monitor is not None:
            for note in monitor.pop_notes():
                show(note.kind.value, note.text, "note" if note.kind is NoteKind.FOUND else "warning")
        for v in verdicts:
            sys.stdout.write(json_line(v.to_json_dict(), "a verdict") if args.json else v.line() + "\n")
        if monitor is not None:
            for w in monitor.pop_windows():
                sys.stdout.write(json_line({"window": w.to_json_dict()}) if args.json else w.line() + "\n")
        sys.stdout.flush()

    def found_wheel(times) -> str:
        """The wheel of the edges read so far, found as ``rotor analyze`` finds it; a note says which."""
        from ..logs.reader import Log
        from ..logs.recording import PatternReading, read_wheel

        reading = read_wheel(Log.from_arrays(tooth_time_s=times), "auto", name=name)
        if isinstance(reading, PatternReading):
            raise LogError(
                f"{name}: the log's wheel is the {reading.pattern.name} pattern; the monitor follows missing-tooth "
                f"wheels (--wheel N-M, e.g. 60-2)"
            )
        spec = reading.wheel.spec
        check_wheel(spec, engine=engine, cylinders=args.cylinders, firing_order=args.firing_order, strokes=args.strokes)
        show("wheel", f"wheel {spec} found from the log's first {times.size} edges (--wheel {spec} pins it)", "note")
        return spec

    def start(wheel: str) -> MisfireMonitor:
        tdc = args.tdc_deg
        if tdc is None and "tdc_after_gap_deg" in lines.stated:
            try:
                tdc = float(lines.stated["tdc_after_gap_deg"])
            except ValueError:
                tdc = None
        if tdc is None:
            raise EngineError(
                "--tdc-deg: where cylinder 1's TDC lies after the gap [deg]; the log's header does not say "
                "('# tdc_after_gap_deg: DEG')"
            )
        parity = args.firing_parity
        if parity is None:
            parity = 1 if lines.stated.get("firing_parity", "0").strip() == "1" else 0
        return MisfireMonitor(
            wheel,
            tdc_deg=tdc,
            engine=engine,
            cylinders=args.cylinders,
            firing_order=args.firing_order,
            strokes=args.strokes,
            firing_parity=parity,
            threshold=DEFAULT_THRESHOLD if args.threshold is None else args.threshold,
            log_name=name,
            thresholds=thresholds,
            last_cycle=last_cycle,
        )

    def take(text: str, final: bool) -> None:
        nonlocal monitor
        times, notes = lines.feed(text, final=final)
        for note in notes:
            show(note.kind.value, note.text, "note" if note.kind is NoteKind.UNITS else "warning")
        if monitor is None and auto:
            if times.size:
                waiting.append(times)
            held = sum(w.size for w in waiting)
            if held < AUTO_EDGES and not (final and held):
                return
            times = np.concatenate(waiting)
            waiting.clear()
            monitor = start(found_wheel(times))
            emit(monitor.feed(times))
            return
        if times.size:
            if monitor is None:
                monitor = start(args.wheel)
            emit(monitor.feed(times))

    if args.log != "-" and not args.follow and os.path.isfile(args.log) and _a_recording(args.log):
        # (also a measurement file: MDF, TDMS, MATLAB, Parquet, Arrow)
        # a capture or bench file (several columns): read through the stages `rotor analyze` uses,
        # and its wheel's edges, as placed, followed as tooth times
        spec, teeth = _recording_teeth(args, show)
        check_wheel(spec, engine=engine, cylinders=args.cylinders, firing_order=args.firing_order, strokes=args.strokes)
        monitor = start(spec)
        source.close()
        emit(monitor.feed(teeth))
        _close(monitor, args, lines, name, emit)
        return
    try:
        while True:
            text = source.read()
            if source.event is not None:
                take("", final=True)  # the last line of what was read before
                lines.restart()
                print(f"rotor: note: {source.event}", file=sys.stderr, flush=True)
                source.event = None
                continue
            take("" if text is None else text, final=text is None)
            INTERRUPT.check()
            if text is None:
                break
    finally:
        source.close()
    if monitor is None:
        raise LogError(f"{name}: no tooth time in the input")
    _close(monitor, args, lines, name, emit)


def _recording_teeth(args, show) -> tuple[str, Any]:
    """A capture or bench file's wheel read as `rotor analyze` reads it: (the wheel the monitor
    follows, its tooth times [s]). A catalogue pattern's edges are followed as the tooth times
    of a 60-2 wheel whose first tooth is at the pattern's angle 0, the angle between its edges
    linear in time."""
    import numpy as np

    from ..logs.reader import read_log
    from ..logs.recording import PatternReading, read_wheel

    recording = read_log(args.log)
    reading = read_wheel(recording, args.wheel, name=os.path.basename(args.log))
    for note in recording.notes:
        show("reading", note, "note")
    if isinstance(reading, PatternReading):
        show(
            "wheel",
            f"wheel {reading.pattern.name} ({reading.fit.pattern.edges_per_turn} edges a turn), as `rotor analyze` "
            f"reads the file, followed as a 60-2 wheel at its angle 0 (--tdc-deg from the pattern's angle 0; the "
            "speed between its edges taken as steady)",
            "note",
        )
        return "60-2", reading.fit.tooth_times(60, 2)
    spec = reading.wheel.spec
    show("wheel", f"wheel {spec}, {reading.edge or 'tooth'} edges, as `rotor analyze` reads the file", "note")
    return spec, np.asarray(reading.track.t, dtype=np.float64)


def _a_recording(path: str) -> bool:
    """Whether the file is a measurement file (:func:`rotor.logs.formats.detect_format`) or its
    first row of numbers holds several columns (a capture or a bench recording), not tooth times
    one per line."""
    import re

    from ..logs.formats import detect_format

    if detect_format(path) is not None:
        return True

    with open(path, "rb") as f:
        head = f.read(65536).decode("utf-8", "replace")
    for line in re.split(r"\r\n|\r|\n", head)[:50]:
        fields = [x for x in re.split(r"[,;\t ]+", line.strip()) if x]
        if not fields or fields[0].startswith("#"):
            continue
        try:
            [float(x) for x in fields]
        except ValueError:
            continue  # a header line: the first row of numbers decides
        return len(fields) > 1
    return False


def _close(monitor, args, lines, name: str, emit) -> None:
    """The last verdicts, the refusal where nothing was judged, and the summary."""
    from ..errors import LogError
    from .output import json_line

    emit(monitor.close())
    result = monitor.result()
    why = monitor.nothing_judged_reason()
    if why is not None:
        raise LogError(f"{name}: {why}")
    if args.json:
        summary = result.to_json_dict()
        summary["lines_skipped"] = lines.skipped
        sys.stdout.write(json_line({"summary": summary}))
    else:
        text = result.summary()
        if lines.skipped:
            text += f"\n  {lines.skipped} line(s) of the log not a time: skipped"
        sys.stdout.write(text + "\n")
    sys.stdout.flush()
