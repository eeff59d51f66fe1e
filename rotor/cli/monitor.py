"""``rotor monitor``: a misfire verdict per firing while tooth times stream in."""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any

from .args import add_json, angle_deg, positive_float

__all__ = ["add_parsers", "cmd_monitor", "CHUNK_BYTES", "FOLLOW_POLL_S"]

CHUNK_BYTES = 65536
"""The most bytes read at a time (a pipe hands over what it holds, up to this)."""
FOLLOW_POLL_S = 0.2
"""With --follow: how long to wait at the end of the file before looking again [s]."""


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``monitor`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "monitor",
        help="misfire monitor on tooth times as they arrive: one verdict per firing (a file, a pipe, a growing file)",
    )
    p.add_argument(
        "log",
        metavar="LOG|-",
        help="tooth edge times [s], one per line (as `rotor simulate --record` writes them); - reads standard input",
    )
    p.add_argument(
        "--engine",
        metavar="ENGINE",
        help="engine file or preset: cylinders, strokes, firing angles and each firing's IMEP from the model "
        "(else --cylinders and --firing-order: no IMEP)",
    )
    p.add_argument("--wheel", required=True, metavar="SPEC", help="trigger wheel with a gap, e.g. 60-2, 36-1, 36-2-1")
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
    p.add_argument("--follow", action="store_true", help="at the end of the file, wait for more (Ctrl-C ends)")
    add_json(p)
    p.set_defaults(func=cmd_monitor)


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
    """Text from a file or standard input, read in chunks as it comes."""

    def __init__(self, name: str, follow: bool) -> None:
        self.follow = follow
        self.name = name
        if name == "-":
            self.stream: Any = getattr(sys.stdin, "buffer", sys.stdin)
            self.own = False
        else:
            self.stream = open(name, "rb")  # noqa: SIM115 - closed by close()
            self.own = True
        self._decoder = _Decoder()

    def read(self) -> str | None:
        """The next text, or None at the end of the input."""
        while True:
            reader = getattr(self.stream, "read1", None)
            data = reader(CHUNK_BYTES) if reader is not None else self.stream.read(CHUNK_BYTES)
            if data:
                return self._decoder(data)
            if not (self.follow and self.own):
                return None
            time.sleep(FOLLOW_POLL_S)

    def close(self) -> None:
        if self.own:
            self.stream.close()


class _Decoder:
    def __init__(self) -> None:
        import codecs

        self._d = codecs.getincrementaldecoder("utf-8")(errors="replace")

    def __call__(self, data: bytes | str) -> str:
        return data if isinstance(data, str) else self._d.decode(data)


def cmd_monitor(args: argparse.Namespace) -> None:
    """Read the log in chunks, print each verdict as it is decided (a JSON object per line
    with --json), each note on the stream as one line on stderr, the per-cylinder summary
    at the end."""
    from ..diagnostics.monitor import DEFAULT_THRESHOLD, MisfireMonitor, NoteKind, ToothLines
    from ..errors import EngineError
    from .output import json_line

    if args.engine is None and args.cylinders is None:
        raise EngineError("--engine ENGINE or --cylinders N (with --firing-order): the monitor needs the firing angles")
    if args.engine is not None and (args.cylinders is not None or args.firing_order is not None):
        raise EngineError("--cylinders and --firing-order are for a monitor without --engine: give one or the other")
    if args.follow and args.log == "-":
        raise EngineError("--follow follows a file as it grows; standard input is followed to its end anyway")
    engine = None
    if args.engine is not None:
        from ..engine.file import load_engine

        engine = load_engine(args.engine)
    if args.log != "-" and os.path.isdir(args.log):
        raise IsADirectoryError(21, "Is a directory", args.log)
    if args.log != "-" and not os.path.isfile(args.log):
        raise FileNotFoundError(2, "No such file", args.log)
    source = _Source(args.log, args.follow)
    lines = ToothLines()
    monitor: MisfireMonitor | None = None

    def warn(text: str, level: str = "warning") -> None:
        print(f"rotor: {level}: {text}", file=sys.stderr, flush=True)

    def emit(verdicts: list) -> None:
        for v in verdicts:
            sys.stdout.write(json_line(v.to_json_dict(), "a verdict") if args.json else v.line() + "\n")
            sys.stdout.flush()
        if monitor is not None:
            for note in monitor.pop_notes():
                warn(note.text, "note" if note.kind is NoteKind.FOUND else "warning")

    def start() -> MisfireMonitor:
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
            args.wheel,
            tdc_deg=tdc,
            engine=engine,
            cylinders=args.cylinders,
            firing_order=args.firing_order,
            strokes=args.strokes,
            firing_parity=parity,
            threshold=DEFAULT_THRESHOLD if args.threshold is None else args.threshold,
        )

    try:
        while True:
            text = source.read()
            final = text is None
            times, notes = lines.feed("" if text is None else text, final=final)
            for note in notes:
                warn(note.text)
            if times.size:
                if monitor is None:
                    monitor = start()
                emit(monitor.feed(times))
            if final:
                break
    finally:
        source.close()
    if monitor is None:
        raise EngineError(f"{args.log}: no tooth time in the input")
    emit(monitor.close())
    result = monitor.result()
    if args.json:
        sys.stdout.write(json_line({"summary": result.to_json_dict()}))
    else:
        sys.stdout.write(result.summary() + "\n")
    sys.stdout.flush()
