"""What every command does with a result: print its summary or its JSON (or a table as
CSV), write its plots. The one writer of JSON and CSV: neither ever carries NaN or
Infinity; a number that does not exist is ``null`` (put there by the result, with a note),
a number that should exist and does not is an internal error naming its key path."""

from __future__ import annotations

import errno
import json
import os
import sys
from collections.abc import Iterable, Sequence
from typing import Any

from ..errors import InternalError
from ..fileio import csv_text as exact_csv_text
from ..fileio import find_nonfinite, key_path_text

__all__ = [
    "MADE_FOLDERS",
    "csv_text",
    "json_line",
    "json_text",
    "plot_folder",
    "print_json",
    "print_text",
    "print_written",
    "remove_made_folders",
    "save_plot",
]


def csv_text(header: Sequence[str], rows: Iterable[Sequence[float]], what: str = "the table") -> str:
    """A table as CSV text (:func:`rotor.fileio.csv_text`: 10 significant digits, zeros
    written as 0 where the computation left round-off, NaN and infinities refused by name)."""
    return exact_csv_text(header, rows, what=what)


def print_text(text: str) -> None:
    """Write ``text`` (a result's ``summary()``) to standard output as it is."""
    sys.stdout.write(text)


def json_text(data: Any, indent: int = 2, what: str = "the result") -> str:
    """``data`` (a result's ``to_json_dict()``) as JSON text ending in a newline.

    A NaN or an infinity is refused, never written: an :class:`rotor.errors.InternalError`
    names its key path, e.g. ``the result's "mean_rpm" is NaN`` (``what`` names the data).
    ``indent``: spaces per level."""
    found = find_nonfinite(data)
    if found is not None:
        keys, kind = found
        raise InternalError(
            f"{what}'s {key_path_text(keys)} is {kind}: a number that should exist does not, and JSON cannot hold it"
        )
    try:
        return json.dumps(data, indent=indent, allow_nan=False) + "\n"
    except TypeError as e:  # a value that is not plain JSON data: a result that forgot json_safe
        raise InternalError(f"{what} is not plain JSON data ({e})") from None


def json_line(data: Any, what: str = "the result") -> str:
    """``data`` as one line of JSON ending in a newline (a JSON-lines stream), checked as
    :func:`json_text` checks it."""
    json_text(data, indent=0, what=what)  # the checks
    return json.dumps(data, allow_nan=False) + "\n"


def print_json(data: Any, indent: int = 2) -> None:
    """Print ``data`` (a result's ``to_json_dict()``) as JSON (see :func:`json_text`);
    ``indent``: spaces per level."""
    sys.stdout.write(json_text(data, indent))


MADE_FOLDERS: list[str] = []
"""The folders this command made for its output; :func:`remove_made_folders` removes those
still empty when it fails, so that a failed command leaves none of its folders behind."""


def plot_folder(folder: str) -> str:
    """Make ``folder`` (``--plot DIR``, a folder's path) and select matplotlib's file
    backend; ``folder``. A ``folder`` that cannot hold the plots (a file, or under one, a
    link to nothing, a folder this user cannot write) raises an ``OSError`` naming it,
    before the work starts; the folders made are noted in :data:`MADE_FOLDERS`."""
    import matplotlib

    from ..fileio import check_folder_writable

    matplotlib.use("Agg")
    check_folder_writable(folder, "the plots")
    here = os.path.abspath(folder)
    made = []
    while not os.path.exists(here) and os.path.dirname(here) != here:
        made.append(here)
        here = os.path.dirname(here)
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as e:
        raise type(e)(e.errno or errno.EIO, f"cannot make the folder for the plots ({e.strerror})", folder) from None
    finally:
        MADE_FOLDERS.extend(made)
    return folder


def remove_made_folders() -> None:
    """Remove the folders of :data:`MADE_FOLDERS` that are empty (deepest first) and forget them all."""
    for folder in sorted(set(MADE_FOLDERS), key=len, reverse=True):
        try:
            os.rmdir(folder)
        except OSError:
            pass
    MADE_FOLDERS.clear()


def save_plot(drawn: Any, folder: str, name: str) -> str:
    """Save the figure of ``drawn`` (what a ``plot()`` returned) to ``folder/name`` (a
    folder's path and a file name); the path."""
    from ..plotting.common import save_figure

    path = os.path.join(folder, name)
    save_figure(drawn, path)
    return path


def print_written(paths: list[str]) -> None:
    """``wrote PATH`` for each file written (after a text summary; not with ``--json``)."""
    for path in paths:
        print(f"wrote {path}")
