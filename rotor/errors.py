"""rotor's exceptions: input errors apart from solver outcomes.

An *input error* (:class:`EngineError`, :class:`LogError`) names what is wrong with what
the user gave and what to do; the command line exits with code 2 on it. A *solver
outcome* (:class:`SolverError`) is valid input for which a solver could not reach an
answer (no periodic steady state, a stall): the command line exits with code 1. An
*internal error* (:class:`InternalError`) is a result rotor should never have produced
(a NaN or an infinity where a number must exist): a bug in rotor, reported as one by the
command line (exit code 70). Base layer: imports nothing from rotor.
"""

from __future__ import annotations

__all__ = ["RotorError", "EngineError", "LogError", "SolverError", "NoSteadyStateError", "InternalError"]


class RotorError(Exception):
    """Base of every error rotor raises on purpose.

    ``argument``: the name of the function argument at fault (``"wheel"``), where the error
    is about one; its message then starts with ``argument=`` (``wheel='36-2-…': …``), which
    the command line turns into the option's flag (``--wheel '36-2-…': …``)."""

    def __init__(self, *args: object, argument: str | None = None) -> None:
        super().__init__(*args)
        self.argument = argument

    def __reduce__(self):  # the argument survives a copy or a trip to another process
        return (type(self), self.args, {"argument": self.argument})


class EngineError(RotorError, ValueError):
    """An engine description or argument that cannot be used: names the key and the problem."""


class LogError(RotorError, ValueError):
    """A recording that cannot be analysed: names the file, row, column or time and the problem."""


class SolverError(RotorError, RuntimeError):
    """Valid input for which a solver could not reach an answer."""


class NoSteadyStateError(SolverError):
    """No usable periodic solution: the kinetic energy reaches zero inside the cycle."""


class InternalError(RotorError, RuntimeError):
    """A result rotor should never have produced (e.g. a NaN or an infinity where a number
    must exist): a bug in rotor. The message names the value (its key path) and what it is."""
