"""What every command does with a result: print its summary or its JSON, write its plots."""

from __future__ import annotations

import json
import os
import sys
from typing import Any

__all__ = ["json_text", "plot_folder", "print_json", "print_text", "print_written", "save_plot"]


def print_text(text: str) -> None:
    """Write ``text`` (a result's ``summary()``) to standard output as it is."""
    sys.stdout.write(text)


def json_text(data: Any, indent: int = 2) -> str:
    """``data`` (a result's ``to_json_dict()``) as JSON text ending in a newline; NaN is
    refused, never written."""
    return json.dumps(data, indent=indent, allow_nan=False) + "\n"


def print_json(data: Any, indent: int = 2) -> None:
    """Print ``data`` (a result's ``to_json_dict()``) as JSON (see :func:`json_text`)."""
    sys.stdout.write(json_text(data, indent))


def plot_folder(folder: str) -> str:
    """Make ``folder`` (``--plot DIR``) and select matplotlib's file backend; ``folder``."""
    import matplotlib

    matplotlib.use("Agg")
    os.makedirs(folder, exist_ok=True)
    return folder


def save_plot(drawn: Any, folder: str, name: str) -> str:
    """Save the figure of ``drawn`` (what a ``plot()`` returned) to ``folder/name``; the path."""
    from ..plotting.common import save_figure

    path = os.path.join(folder, name)
    save_figure(drawn, path)
    return path


def print_written(paths: list[str]) -> None:
    """``wrote PATH`` for each file written (after a text summary; not with ``--json``)."""
    for path in paths:
        print(f"wrote {path}")
