"""The one protocol every rotor result speaks, and JSON that never holds NaN.

Every result object — a steady state or a transient run, a crank table, an order
spectrum, a log analysis, an identification, a calibration, a flywheel design — has

- ``summary() -> str``: one screen of text for people;
- ``to_pandas()``: a tidy :class:`pandas.DataFrame`, units in the column names;
- ``to_json_dict()``: exactly what the command line's ``--json`` prints: plain Python
  numbers, strings, lists and dicts, ``None`` where a number is undefined (never NaN);
- ``plot(ax=None)``: draws itself (on ``ax``, one Axes or an array of them, or on a new
  figure) and returns what it drew;
- a short ``repr`` and, in notebooks, ``_repr_html_`` (the summary).

:class:`Result` gives the last two from ``summary()``; a result class inherits it and
writes the other four. Base layer: imports nothing from rotor.
"""

from __future__ import annotations

import abc
import html
import math
from typing import Any

import numpy as np

from .errors import InternalError

__all__ = ["Result", "json_safe"]


class Result(abc.ABC):
    """Base of every result: ``summary``, ``to_pandas``, ``to_json_dict``, ``plot``.

    Dataclass results must be declared with ``repr=False`` so that this short ``repr``
    is kept instead of the dataclass one (which would print every array).
    """

    @abc.abstractmethod
    def summary(self) -> str:
        """One screen of text for people."""

    @abc.abstractmethod
    def to_pandas(self) -> Any:
        """A tidy :class:`pandas.DataFrame` with units in the column names."""

    @abc.abstractmethod
    def to_json_dict(self) -> dict:
        """Plain JSON-ready data (what ``--json`` prints); ``None``, never NaN."""

    @abc.abstractmethod
    def plot(self, ax: Any = None) -> Any:
        """Draw the result on ``ax`` (or a new figure) and return what was drawn."""

    def __repr__(self) -> str:
        lines = [line.strip() for line in self.summary().splitlines() if line.strip()]
        head = lines[0] if lines else ""
        if len(head) > 120:
            head = head[:117] + "..."
        return f"<{type(self).__name__}: {head}>"

    def _repr_html_(self) -> str:
        return f"<pre>{html.escape(self.summary())}</pre>"


def json_safe(x: Any, where: str = "") -> Any:
    """``x`` as plain JSON data: arrays to lists, numpy and JAX scalars to Python numbers,
    tuples to lists, dict keys to strings; recursively.

    **NaN** becomes ``None``: the result's way of saying that a number does not exist (a
    δ without a whole cycle, an order not resolved), which its summary explains.
    **±Infinity** is never hidden: it is a number that overflowed, not one that does not
    exist, and raises :class:`rotor.errors.InternalError` naming its key path (``where``:
    the path of ``x`` itself, ``""`` at the top). A ``set``, ``bytes`` or an object that
    is not data raises ``TypeError`` naming its key path."""
    if isinstance(x, dict):
        return {str(k): json_safe(v, f'{where}["{k}"]' if where else f'"{k}"') for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v, f"{where}[{i}]") for i, v in enumerate(x)]
    if isinstance(x, str) or x is None:
        return x
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        f = float(x)
        if math.isinf(f):
            raise InternalError(
                f"json_safe: {where or 'the value'} is {'' if f > 0 else '-'}Infinity: a number that overflowed; "
                "JSON cannot hold it and null would hide it"
            )
        return f if math.isfinite(f) else None
    if isinstance(x, complex):
        raise TypeError(f"json_safe: {where or 'the value'} = {x!r}: a complex number is not JSON data")
    if hasattr(x, "__array__"):
        a = np.asarray(x)
        if a.dtype.kind == "c":
            raise TypeError(f"json_safe: {where or 'the value'}: a complex array is not JSON data")
        if a.ndim == 0:
            return json_safe(a.item(), where)
        return [json_safe(v, f"{where}[{i}]") for i, v in enumerate(a.tolist())]
    if isinstance(x, (set, frozenset, bytes, bytearray)) or callable(x):
        raise TypeError(
            f"json_safe: {where or 'the value'} is a {type(x).__name__}: expected numbers, strings, None, "
            "lists, tuples, dicts or arrays"
        )
    return x
