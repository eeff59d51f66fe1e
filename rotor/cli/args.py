"""Argument types and the options every command group shares.

The flag convention of the whole command line lives here, so that each command module
adds the same option the same way:

- ``ENGINE``: an engine file (TOML) or a preset name, a positional argument (``diagnose``
  and ``analyze``, whose positional is the log, take ``--engine ENGINE``);
- ``--json``: print the result as one JSON object (``result.to_json_dict()``), on every
  command that computes a result;
- ``--plot DIR``: write the command's plots (PNG) into DIR, on every command that draws;
- ``--quiet``: no progress bar, on the commands that can show one;
- ``--format``: only for tables (``rotor table``).
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable
from typing import Any, NoReturn

__all__ = [
    "percent_of_firings",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_SOLVER",
    "EXIT_USAGE",
    "Parser",
    "add_dynamics_options",
    "add_edge",
    "add_engine",
    "add_json",
    "add_plot",
    "add_quiet",
    "angle_deg",
    "delta_list",
    "error_text",
    "fidelity_option",
    "nonnegative_float",
    "positive_float",
    "pressure_pa",
    "scale_list",
    "speed",
    "speed_list",
    "whole",
]

EXIT_USAGE = 2
"""Exit status of bad input: a usage error, an engine or log that cannot be read."""
EXIT_SOLVER = 1
"""Exit status of valid input without an answer (a solver that did not converge)."""
EXIT_INTERNAL = 70
"""Exit status of an internal error, a bug in rotor (``EX_SOFTWARE`` of BSD's sysexits.h)."""
EXIT_INTERRUPTED = 130
"""Exit status of a run stopped by Ctrl-C (128 + SIGINT, as a shell reports it)."""

FIDELITIES = ("variable", "series", "coefficients", "constant")


class Parser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` whose usage errors are one line and exit 2, and
    which takes any negative number as an option's value (``--step -inf``, ``--tdc-deg
    -1e3``), so that it is refused by the option's own check, not as a missing value."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE
        )
        self._help_later: list[tuple[argparse.Action, Callable[[], str]]] = []

    def help_later(self, action: argparse.Action, make: Callable[[], str]) -> None:
        """Set ``action``'s help to ``make()`` when this parser's help is shown, not before:
        for a help text that lives in a module too slow to import for every command. A later
        call for the same action replaces an earlier one."""
        self._help_later = [(a, m) for a, m in self._help_later if a is not action]
        self._help_later.append((action, make))

    def format_help(self) -> str:
        """The help, with the texts of :meth:`help_later` filled in."""
        while self._help_later:
            action, make = self._help_later.pop()
            action.help = make()
        return super().format_help()

    def error(self, message: str) -> NoReturn:
        """One line on stderr, exit status 2, as for any bad input."""
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


ARGUMENT_FLAGS = {
    "calibration": "--calibration",
    "columns": "--columns",
    "compression_ratio": "--compression-ratio",
    "cylinders": "--cylinders",
    "edge": "--edge",
    "firing": "--firing",
    "intake_pa": "--intake-pa",
    "max_order": "--max-order",
    "points_per_cycle": "--points-per-cycle",
    "pressure_gain": "--pressure-gain",
    "rod_ratio": "--rod-ratio",
    "scaling": "--scaling",
    "step_deg": "--step",
    "tdc_deg": "--tdc-deg",
    "tooth_errors": "--tooth-errors",
    "wheel": "--wheel",
}
"""The library's argument names that its messages recommend (``give wheel='60-2'``), and the
command line's flag for each; ``calibration=None`` is ``--no-calibration``."""
_ARGUMENT_SETTING = re.compile(r"(?<![\w.'\"])(" + "|".join(ARGUMENT_FLAGS) + r")=('[^']*'|\"[^\"]*\"|[^\s,;:)]+)?")


def _flag(m: re.Match) -> str:
    name, value = m.group(1), m.group(2)
    if name == "calibration" and value == "None":
        return "--no-calibration"
    if value is None:
        return ARGUMENT_FLAGS[name]
    if value[0] in "'\"":
        value = value[1:-1]
    return f"{ARGUMENT_FLAGS[name]} {value}"


_FLAG_LIST = re.compile(r"(--[\w-]+(?: [^\s,;]+)?), (?=--)")


def cli_words(text: str) -> str:
    """``text`` (a library note or summary) with the arguments it names as settings
    (``wheel='60-2', edge='rising'``, ``tooth_errors=FILE``) written as the command line's
    flags (``--wheel 60-2 --edge rising``, ``--tooth-errors FILE``, :data:`ARGUMENT_FLAGS`)."""
    return _FLAG_LIST.sub(r"\1 ", _ARGUMENT_SETTING.sub(_flag, text))


def cli_json_words(data: Any) -> Any:
    """``data`` (a ``to_json_dict()``) with :func:`cli_words` applied to its strings."""
    if isinstance(data, str):
        return cli_words(data)
    if isinstance(data, dict):
        return {k: cli_json_words(v) for k, v in data.items()}
    if isinstance(data, list):
        return [cli_json_words(v) for v in data]
    return data


def error_text(e: BaseException) -> str:
    """``e``'s message as one line, in the command line's words: where a library error
    names its argument (``RotorError.argument``, the message starting ``wheel=…``), the
    option's flag in its place (``--wheel …``); a setting the message recommends
    (``give wheel='60-2'``, ``calibration=None``) as the flag (``give --wheel 60-2``,
    ``--no-calibration``, :data:`ARGUMENT_FLAGS`)."""
    text = " ".join(str(e).split("\n")).strip()
    argument = getattr(e, "argument", None)
    if isinstance(argument, str) and text.startswith(f"{argument}="):
        text = f"--{argument.replace('_', '-')} {text[len(argument) + 1 :]}"
    if hasattr(e, "argument"):  # a library error (rotor.RotorError)
        text = _ARGUMENT_SETTING.sub(_flag, text)
        for function, command in LIBRARY_COMMANDS.items():
            text = text.replace(function, command)
    return terminal_safe(text)


LIBRARY_COMMANDS = {
    "rotor.simulate(..., method='time')": "`rotor simulate ENGINE --method time`",
    "with rotor.simulate": "with `rotor simulate ENGINE`",
    "use rotor.simulate": "use `rotor simulate`",
    "rotor.preset_names()": "`rotor presets`",
}
"""The library's functions its messages recommend, and the command that does the same."""


MAX_MESSAGE_CHARS = 800
"""The longest error line printed [characters]; a longer one (a log of 10 000 columns named)
is cut, saying how long it was."""


def terminal_safe(text: str, limit: int = MAX_MESSAGE_CHARS) -> str:
    """``text`` as one line a terminal shows as it is: control characters (an escape, a
    carriage return, a line feed in a file's name) written as their escapes, and cut to
    ``limit`` characters, saying so."""
    out = "".join(ch if ch == "\t" or (ch.isprintable() or ch == " ") else ascii(ch)[1:-1] for ch in text)
    if len(out) > limit:
        out = out[: limit - 40].rstrip() + f" … ({len(out)} characters in all)"
    return out


# ----------------------------------------------------------------------------- types
def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def percent_of_firings(text: str) -> float:
    """An option's value as a percentage of the firings, above 0 and up to 100."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (0 < v <= 100):
        raise argparse.ArgumentTypeError(f"{text!r}: a percentage of the firings, above 0 and up to 100")
    return v


def positive_float(text: str) -> float:
    """A finite number > 0."""
    v = _number(text)
    if not (0 < v < math.inf):
        raise argparse.ArgumentTypeError(f"{text!r} must be a positive number")
    return v


def nonnegative_float(text: str) -> float:
    """A finite number ≥ 0."""
    v = _number(text)
    if not (0 <= v < math.inf):
        raise argparse.ArgumentTypeError(f"{text!r} must be zero or positive")
    return v


MAX_ANGLE_DEG = 3600.0
"""The largest angle option taken, in magnitude [deg]: ten revolutions. Beyond it an angle is
no plausible input (a float of 10¹⁹ degrees has no digits left below a revolution) and is
refused, as an engine file's angles are."""


def angle_deg(text: str) -> float:
    """An angle [deg], finite and within ±:data:`MAX_ANGLE_DEG` (an angle option, as ``--tdc-deg``)."""
    v = _number(text)
    if not (-MAX_ANGLE_DEG <= v <= MAX_ANGLE_DEG):
        raise argparse.ArgumentTypeError(
            f"{text!r} is no angle to use: give a finite angle from {-MAX_ANGLE_DEG:g} to {MAX_ANGLE_DEG:g} degrees"
        )
    return v


speed = nonnegative_float
"""A crank speed [rev/min]: zero allowed (from rest)."""


def pressure_pa(quantity: str) -> Callable[[str], float]:
    """The type of a pressure option [Pa] (``--intake-pa``): a number within the plausible
    range of ``quantity`` (a key of :data:`rotor.engine.plausible.EDGE_RANGES`, e.g.
    ``"intake_pa"``), else a usage error naming the unit it reads as (``0.95``: bar)."""

    def convert(text: str) -> float:
        from ..errors import EngineError

        v = _number(text)
        from ..engine.plausible import check_edge  # imports JAX: only when the option is given

        try:
            check_edge(repr(text), v, quantity)
        except EngineError as e:
            raise argparse.ArgumentTypeError(str(e).replace(f"{text!r} = {v:g} ", f"{text!r} ", 1)) from None
        return v

    convert.__name__ = f"pressure_pa_{quantity}"
    return convert


def whole(text: str) -> int:
    """A whole number ≥ 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be 1 or more")
    return v


def _number_list(text: str, check: Callable[[str], float], what: str) -> list[float]:
    out = []
    for item in filter(None, (t.strip() for t in text.split(","))):
        try:
            out.append(check(item))
        except argparse.ArgumentTypeError as e:
            raise argparse.ArgumentTypeError(f"{text!r}: {e}; expected {what}") from None
    if not out:
        raise argparse.ArgumentTypeError(f"{text!r}: expected {what}")
    return out


def speed_list(text: str) -> list[float]:
    """Speeds > 0 [rev/min] separated by commas."""
    return _number_list(text, positive_float, "speeds in rpm separated by commas, e.g. 800,1250,2000")


def delta_list(text: str) -> list[float]:
    """Irregularity targets > 0 separated by commas."""
    return _number_list(text, positive_float, "targets separated by commas, e.g. 0.01 or 0.03,0.01,0.005")


def scale_list(text: str) -> list[float]:
    """Scales ≥ 0 separated by commas."""
    return _number_list(text, speed, "scales ≥ 0 separated by commas, e.g. 0.3,1,1")


# ----------------------------------------------------------------------------- options
ENGINE_HELP = "engine file (.toml) or preset name (see `rotor presets`)"


def add_engine(p: argparse.ArgumentParser, rpm: bool = True) -> None:
    """The positional ENGINE and (``rpm``) ``--rpm`` at one speed > 0."""
    p.add_argument("engine", metavar="ENGINE", help=ENGINE_HELP)
    if rpm:
        p.add_argument("--rpm", type=positive_float, help="crank speed [rev/min] (default: the file's [operating] rpm)")


def add_json(p: argparse.ArgumentParser) -> None:
    """``--json``: print the result as one JSON object."""
    p.add_argument("--json", action="store_true", help="print one JSON object")


def add_plot(p: argparse.ArgumentParser, what: str = "plots", default: str | None = None) -> None:
    """``--plot DIR``: write ``what`` into DIR (only when given, unless ``default``)."""
    text = f"write {what} to DIR" + (f" (default {default}/)" if default else "")
    p.add_argument("--plot", metavar="DIR", default=default, help=text)


def add_edge(p: argparse.ArgumentParser) -> None:
    """``--edge auto|rising|falling``: which edges of the wheel signal (analog or digital) mark the teeth."""
    p.add_argument(
        "--edge",
        choices=("auto", "rising", "falling"),
        default="auto",
        help="which edges of the wheel signal (analog or digital) mark the teeth (default auto: both are read, the "
        "one that fits the wheel with the fewest repairs, then the lower tooth-period jitter, is taken; the summary "
        "says which)",
    )


def add_quiet(p: argparse.ArgumentParser) -> None:
    """``--quiet``: no progress bar."""
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def fidelity_option(p: argparse.ArgumentParser, text: str) -> None:
    """``--fidelity``: the inertia model."""
    p.add_argument("--fidelity", choices=FIDELITIES, default="variable", help=text)


def add_dynamics_options(p: argparse.ArgumentParser) -> None:
    """``--load``, ``--fidelity``, ``--json`` and ``--plot`` of ``steady`` and ``simulate``."""

    def load_help() -> str:
        from ..dynamics.load_help import LOAD_HELP

        return LOAD_HELP + " (default none)"

    load = p.add_argument("--load", default="none", metavar="SPEC", help="the load (default none)")
    if isinstance(p, Parser):
        p.help_later(load, load_help)
    else:
        load.help = load_help()
    fidelity_option(
        p,
        "inertia model: exact I(θ) (default), the A·cos²θ + B·cosθ + C form of Anisimov, Yelenich & "
        "Melnyk, or constant + textbook torque",
    )
    add_json(p)
    add_plot(p)
