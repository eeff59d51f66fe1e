"""A one-line progress bar on stderr for long runs (:func:`rotor.simulate`,
:func:`rotor.steady_sweep`, the command line's many-file commands).

A compiled kernel reports its progress through a host callback
(:func:`rotor.dynamics.equation.report_progress`) that carries the bar's :attr:`Progress.key`,
a number passed to the kernel as an argument: the kernel is compiled once for every bar,
and :func:`report` finds the bar the key belongs to while the bar is open. Pure Python:
base layer, imports nothing from rotor (and not JAX).
"""

from __future__ import annotations

import itertools
import sys
import time
import weakref

__all__ = ["Progress", "report"]

_KEYS = itertools.count(1)
_OPEN: weakref.WeakValueDictionary[int, Progress] = weakref.WeakValueDictionary()


class Progress:
    """A one-line progress bar on stderr, shown only after ~2 s and only on a terminal.

    ``total``: units of work (cycles in a run); ``enabled``: True, False or None (when
    stderr is a terminal); ``verb`` and ``unit``: what the bar says (``simulating``,
    ``cycles``). :attr:`key` names the bar to :func:`report` until :meth:`close`.
    """

    def __init__(self, total: int, enabled: bool | None, verb: str = "simulating", unit: str = "cycles"):
        self.total, self.start, self.shown, self.last = total, time.perf_counter(), False, 0
        self.enabled = sys.stderr.isatty() if enabled is None else bool(enabled)
        self.verb, self.unit = verb, unit
        self.base, self.span = 0, total  # the units of work of the call now running: from base, span of them
        self.key = next(_KEYS)
        if self.enabled:
            _OPEN[self.key] = self

    def within(self, base: int, span: int) -> None:
        """The next reports (:meth:`fraction`) are of a part of the work: ``span`` units from
        ``base`` (a chunk of a run's cycles)."""
        self.base, self.span = base, span

    def fraction(self, done: float) -> None:
        """Show that the fraction ``done`` (0…1) of the part of the work now running (all of
        it unless :meth:`within` said otherwise) is done."""
        self.update(min(self.total, self.base + int(round(done * self.span))))

    def update(self, done: int) -> None:
        """Show that ``done`` of the cycles are done (once the run has taken ~2 s)."""
        if not self.enabled or (self.shown and done < self.last):
            return
        self.last = done
        elapsed = time.perf_counter() - self.start
        if elapsed < 2.0 and done < self.total:
            return
        frac = done / self.total
        bar = "#" * int(30 * frac)
        eta = elapsed / frac - elapsed if frac > 0 else float("nan")
        sys.stderr.write(
            f"\r{self.verb} [{bar:<30}] {done}/{self.total} {self.unit}, {elapsed:5.1f} s, ~{eta:4.0f} s left"
        )
        sys.stderr.flush()
        self.shown = True

    def clear(self) -> None:
        """Blank the bar's line (before a line of its own on stderr); the next update redraws it."""
        if self.shown:
            sys.stderr.write("\r" + " " * 79 + "\r")
            sys.stderr.flush()

    def close(self) -> None:
        """End the bar's line, if it was shown; reports to its key are dropped from now on."""
        _OPEN.pop(self.key, None)
        if self.shown:
            sys.stderr.write("\n")
            sys.stderr.flush()


def report(key: int, fraction: float) -> None:
    """Tell the open bar with ``key`` that ``fraction`` of its running part is done (from
    a compiled kernel's host callback); a closed or disabled bar ignores it."""
    bar = _OPEN.get(int(key))
    if bar is not None:
        bar.fraction(fraction)
