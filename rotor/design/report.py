"""The whole kinematic and dynamic calculation of an engine as one self-contained HTML page.

:func:`report` runs the course-project calculation of Shishkov, "Dinamika dvigatelei"
(Engine dynamics: a guide to the course project, South Ural State University, 2014; after
Kolchin & Demidov and Popyk) at one speed and writes it into a folder:

- ``index.html``: one page that needs nothing else (every figure is a PNG inside it as
  base64, no external address, one small inline script that counts the figures that
  rendered): the inputs, the kinematic and dynamic table (S, V, J, Pg, Pj, PΣ, N, K, Z, T,
  M of cylinder 1), the total tangential force and torque, the turning-moment diagram
  with its excess work and the textbook flywheel, the bearing loads (crank pin, big-end
  bearing, main journals and bearings, wear, running torques) and the balance of free
  forces and moments; every diagram the guide lists under "Graphs of the dynamic
  calculation" (Графики к динамическому расчёту);
- ``figures/*.png``: the same figures, one file each;
- ``tables/*.csv``: the tables, SI units in the column names, at the report's step.

The tables are at ``step_deg``; the figures at a finer step that divides it (about 1°),
so that the polar diagrams are smooth.

**Written whole or not at all.** The report is built in a new hidden folder
(``.rotor-report-…``) and put in place only when every file is in it, so that an error
(or Ctrl-C) leaves no trace and the old report, if any, as it was. A new ``out_dir``: the
hidden folder is made beside it and renamed onto it, at once. An existing ``out_dir``
(empty, or a previous report's, see below) keeps its identity, since it may be the
working directory or a mount point: the hidden folder is made inside it and its entries
replace the old ones by renames, the page last.

**Only its own files.** Beside the page the report writes its record,
``.rotor-report.json`` (:data:`RECORD_NAME`): every file it wrote (``index.html``,
``figures/…``, ``tables/…``) with its SHA-256. An existing folder is replaced only where
everything in it is the report's own: ``index.html``, ``figures/`` and ``tables/`` (real
folders, not links), each file in them a regular file listed in the record with the
content listed there, and nothing else (a hidden ``.rotor-report-…`` folder left by a
killed run apart). Anything else — the user's ``figures/holiday.jpg``, their own
``index.html``, a subfolder, a link, a report's file edited since, a folder without a
record (a report of an older rotor included) — refuses the folder with a one-line
``FileExistsError`` naming it and what is not the report's; nothing there is touched.
While the entries are swapped the record lists the old files and the new, so that a run
killed halfway leaves a folder the next report still recognises.

Where the figures are drawn: the diagrams of the results (bearing loads, balance,
flywheel, the crank table's kinematics) draw themselves in :mod:`rotor.plotting`; the
few line diagrams that belong to this page alone (forces, tangential forces, the
turning-moment diagram) are in :mod:`rotor.plotting.report`.
"""

from __future__ import annotations

import base64
import dataclasses
import errno
import html
import math
import os
import secrets
import shutil
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import jax.numpy as jnp
import numpy as np

from ..engine.forces import crank_forces, table_angles_deg, total_torque
from ..engine.kinematics import mean_piston_speed
from ..engine.model import Engine, require_engine
from ..engine.plausible import check_results_finite, check_speed_rpm, require_number, require_whole
from ..engine.table import CrankTable, crank_table
from ..errors import EngineError
from ..fileio import INTERRUPT, check_folder_writable, csv_text, made_folders
from ..plotting.common import save_figure
from ..plotting.report import plot_curves, plot_tangential_forces, plot_turning_moment
from ..results import json_safe
from ..units import RAD_S_PER_RPM
from .balance import balance
from .bearings import bearing_loads
from .flywheel import DELTA_MIN, textbook_flywheel

__all__ = [
    "Report",
    "report",
    "report_folder",
    "REPORT_ENTRIES",
    "RECORD_NAME",
    "TEMPORARY_PREFIX",
    "FIGURE_STEP_DEG",
    "DEFAULT_DELTA",
]

REPORT_ENTRIES = frozenset({"index.html", "figures", "tables"})
"""What a report folder holds besides its record (:data:`RECORD_NAME`)."""
RECORD_NAME = ".rotor-report.json"
"""The report's record of the files it wrote, in its folder: ``{"written_by": "rotor
report", "files": {"figures/flywheel.png": ["<sha256>"], …}}`` (paths relative to the
folder, with ``/``; each file's accepted SHA-256 digests, two while a report replaces
another). A folder is a previous report, which :func:`report` may replace, only where
every file in it is listed there with its content (see the module's doc)."""
RECORD_WRITER = "rotor report"
"""The record's ``written_by``."""
TEMPORARY_PREFIX = ".rotor-report-"
"""The name of the hidden folder a report is built in before it is put in place (one left
by a killed run is not counted as another file of a report's folder)."""
FIGURE_STEP_DEG = 1.0
"""The finest step the figures need [deg]: they are drawn at the largest step ≤ this that
divides the tables' step."""
DEFAULT_DELTA = 0.01
"""The target irregularity δ of the report's textbook flywheel when none is given [-]."""

SOURCES = (
    "V. V. Shishkov (comp.), <i>Dinamika dvigatelei: metodicheskie ukazaniya k kursovomu proektirovaniyu</i> "
    "(Engine dynamics: a guide to the course project), South Ural State University, Chelyabinsk, 2014: the "
    "calculation, its tables and its list of diagrams (§3.2).",
    "A. I. Kolchin &amp; V. P. Demidov, <i>Raschet avtomobil'nykh i traktornykh dvigatelei</i> (Design "
    "calculation of automotive and tractor engines), Vysshaya shkola, Moscow, 2008: the method the guide follows, "
    "the bearing-load diagrams and the wear diagram.",
    "K. G. Popyk, <i>Dinamika avtomobil'nykh i traktornykh dvigatelei</i> (Dynamics of automotive and tractor "
    "engines), 2nd ed., Vysshaya shkola, Moscow, 1970: balancing and the flywheel.",
)


# ----------------------------------------------------------------------------- the result
@dataclass(frozen=True, repr=False)
class Report:
    """What :func:`report` wrote.

    **Fields:** ``engine_name``; ``rpm`` [rev/min]; ``step_deg``: the tables' step [deg];
    ``figure_step_deg``: the figures' step [deg]; ``delta``: the flywheel's target δ [-];
    ``kinematics`` (``"exact"`` or ``"series"``); ``out_dir``: the report's folder;
    ``figures`` and ``tables``: the files written under ``figures/`` and ``tables/``
    (names); ``seconds``: how long the report took [s]. ``page`` is the path of
    ``index.html``.
    """

    engine_name: str
    rpm: float
    step_deg: float
    figure_step_deg: float
    delta: float
    kinematics: str
    out_dir: str
    figures: tuple[str, ...] = field(default=())
    tables: tuple[str, ...] = field(default=())
    seconds: float = 0.0

    @property
    def page(self) -> str:
        """The path of the page, ``out_dir/index.html``."""
        return os.path.join(self.out_dir, "index.html")

    def paths(self) -> list[str]:
        """Every file written: the page, the figures and the tables (paths)."""
        return (
            [self.page]
            + [os.path.join(self.out_dir, "figures", f) for f in self.figures]
            + [os.path.join(self.out_dir, "tables", t) for t in self.tables]
        )

    def summary(self) -> str:
        """What was written, where, and how long it took."""
        lines = [
            f"report of {self.engine_name} at {self.rpm:g} rpm ({self.kinematics} kinematics, tables every "
            f"{self.step_deg:g}°, figures every {self.figure_step_deg:g}°, flywheel for δ = {self.delta:g})",
            f"  {self.page}  (open it in a browser: one self-contained page)",
            f"  {len(self.figures)} figures in {os.path.join(self.out_dir, 'figures')}: {', '.join(self.figures)}",
            f"  {len(self.tables)} tables in {os.path.join(self.out_dir, 'tables')}: {', '.join(self.tables)}",
            f"  took {self.seconds:.1f} s",
        ]
        return "\n".join(lines) + "\n"

    def to_json_dict(self) -> dict:
        """The fields and every path written, as plain JSON (what ``rotor report --json`` prints)."""
        return json_safe(
            {
                "engine": self.engine_name,
                "rpm": self.rpm,
                "step_deg": self.step_deg,
                "figure_step_deg": self.figure_step_deg,
                "delta": self.delta,
                "kinematics": self.kinematics,
                "out_dir": self.out_dir,
                "page": self.page,
                "figures": [os.path.join(self.out_dir, "figures", f) for f in self.figures],
                "tables": [os.path.join(self.out_dir, "tables", t) for t in self.tables],
                "seconds": self.seconds,
            }
        )

    def __repr__(self) -> str:
        return f"<Report: {self.engine_name} at {self.rpm:g} rpm in {self.out_dir}>"

    def _repr_html_(self) -> str:
        return f"<pre>{html.escape(self.summary())}</pre>"


# ----------------------------------------------------------------------------- the folder
def _sha256(path: str) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _read_record(folder: str) -> dict[str, list[str]] | None:
    """The record (:data:`RECORD_NAME`) in ``folder``: {relative path: accepted SHA-256
    digests}; ``None`` where there is none, or what is there is not a record rotor wrote."""
    import json
    import stat

    path = os.path.join(folder, RECORD_NAME)
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode):
            return None
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("written_by") != RECORD_WRITER or not isinstance(data.get("files"), dict):
        return None
    files: dict[str, list[str]] = {}
    for name, digests in data["files"].items():
        if not (isinstance(name, str) and isinstance(digests, list) and all(isinstance(d, str) for d in digests)):
            return None
        files[name] = list(digests)
    return files


def _record_text(files: dict[str, list[str]]) -> str:
    import json

    return json.dumps({"written_by": RECORD_WRITER, "files": dict(sorted(files.items()))}, indent=1) + "\n"


def _write_record(path: str, files: dict[str, list[str]]) -> None:
    with open(path, "w", encoding="utf-8", newline="") as f:
        f.write(_record_text(files))


def _files_written(folder: str) -> dict[str, list[str]]:
    """{relative path: [SHA-256]} of every file the report wrote into ``folder`` (its
    hidden folder: the page and what is under ``figures/`` and ``tables/``)."""
    files: dict[str, list[str]] = {}
    for top, dirs, names in os.walk(folder):
        dirs.sort()
        for name in sorted(names):
            path = os.path.join(top, name)
            rel = os.path.relpath(path, folder).replace(os.sep, "/")
            if rel != RECORD_NAME:
                files[rel] = [_sha256(path)]
    return files


def _not_the_reports(folder: str) -> list[str]:
    """What the existing folder ``folder`` holds that is not a report's own (see the
    module's doc), as the names to show: empty for an empty folder or a previous report."""
    import stat

    record = _read_record(folder)
    known: dict[str, list[str]] = {} if record is None else record
    others: list[str] = []

    def own_file(rel: str) -> None:
        path = os.path.join(folder, *rel.split("/"))
        try:
            regular = stat.S_ISREG(os.lstat(path).st_mode)
        except OSError:
            regular = False
        if not regular or rel not in known:
            others.append(rel)
        elif _sha256(path) not in known[rel]:
            others.append(f"{rel}, changed since the report wrote it")

    for name in sorted(os.listdir(folder)):
        if name.startswith(TEMPORARY_PREFIX) or (name == RECORD_NAME and record is not None):
            continue
        path = os.path.join(folder, name)
        if name in REPORT_ENTRIES - {"index.html"} and os.path.isdir(path) and not os.path.islink(path):
            for inner in sorted(os.listdir(path)):
                if os.path.isdir(os.path.join(path, inner)) and not os.path.islink(os.path.join(path, inner)):
                    others.append(f"{name}/{inner}/")
                else:
                    own_file(f"{name}/{inner}")
        elif name == "index.html":
            own_file(name)
        else:
            others.append(name + ("/" if os.path.isdir(path) and not os.path.islink(path) else ""))
    return others


def _check_out_dir(out_dir: Any) -> str:
    """``out_dir`` as a ``str`` if a report can be written there, else a one-line
    ``OSError`` naming it (a file, a folder holding anything that is not a previous
    report's own files, a parent that is a file, a link that points nowhere, a folder this
    user cannot write): checked before the work."""
    if isinstance(out_dir, bytes) or not isinstance(out_dir, (str, os.PathLike)):
        raise TypeError(f"report(out_dir) = {out_dir!r}: expected a folder's path (a str or pathlib.Path)")
    path = os.fspath(out_dir)
    if not isinstance(path, str):
        raise TypeError(f"report(out_dir) = {out_dir!r}: expected a folder's path (a str or pathlib.Path)")
    if not path:
        raise FileNotFoundError(errno.ENOENT, "an empty path: give a folder for the report", path)
    if os.path.exists(path):
        if not os.path.isdir(path):
            raise NotADirectoryError(errno.ENOTDIR, "is a file, not a folder for the report: give a folder", path)
        others = _not_the_reports(path)
        if others:
            shown = "; ".join(others[:3]) + ("; …" if len(others) > 3 else "")
            raise FileExistsError(
                errno.EEXIST,
                f"holds other files ({shown}) than a report rotor wrote there: give an empty or new folder for "
                "the report",
                path,
            )
    check_folder_writable(path, "the report")
    return path


@contextmanager
def _locked(folder: str) -> Iterator[None]:
    """Hold an exclusive lock on ``folder`` (``flock``; nothing where the system has none):
    two reports put in place at once into one folder take turns, so that it ends with one
    whole report."""
    try:
        import fcntl
    except ImportError:  # not on this system: the renames alone
        yield
        return
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # the lock goes with it


@contextmanager
def report_folder(path: str) -> Iterator[str]:
    """Yield a new hidden folder to write the report into; when the block succeeds, write
    the record of its files into it (:data:`RECORD_NAME`) and put its entries in place at
    ``path``; when it fails (an error or Ctrl-C), delete it and every parent folder made
    for it.

    A missing ``path``: the folder is made beside it and renamed onto it (where another
    report got there first, its entries are replaced as below). An existing folder (empty,
    or a previous report's; perhaps the working directory or a mount point, which must
    stay what they are): the folder is made inside it and its entries replace the old ones
    one by one, ``index.html`` last, under a lock on the folder, where it holds nothing but
    a report's own files (checked again under the lock). An interrupt that arrived while
    the report was written stops it before anything is put in place. An ``OSError`` names
    ``path``, never a temporary folder."""
    target = os.path.realpath(path) if os.path.isdir(path) else os.path.abspath(path)  # a link: where it points
    exists = os.path.isdir(target)
    where = target if exists else os.path.dirname(target)
    tmp = None
    try:
        with made_folders(where):  # the parents made are removed again on failure, after the temporary folder
            try:
                for _ in range(100):
                    candidate = os.path.join(where, f"{TEMPORARY_PREFIX}{secrets.token_hex(4)}")
                    try:
                        os.mkdir(candidate)
                    except FileExistsError:
                        continue
                    tmp = candidate
                    break
                if tmp is None:
                    raise FileExistsError(errno.EEXIST, "no free temporary name for the report", path)
                yield tmp
                INTERRUPT.check()
                _write_record(os.path.join(tmp, RECORD_NAME), _files_written(tmp))
                if exists:
                    _swap_entries(tmp, target)
                else:
                    try:
                        os.rename(tmp, target)
                    except OSError as e:
                        if e.errno not in (errno.EEXIST, errno.ENOTEMPTY) or not os.path.isdir(target):
                            raise
                        _swap_entries(tmp, target)  # another report was put there meanwhile: replace it
                tmp = None
            finally:
                if tmp is not None:
                    shutil.rmtree(tmp, ignore_errors=True)
    except OSError as e:
        name = "" if e.filename is None else str(e.filename)
        if not name or os.path.basename(name).startswith(TEMPORARY_PREFIX) or name in (target, where):
            raise type(e)(e.errno or errno.EIO, e.strerror or str(e), path) from None
        raise


def _swap_entries(tmp: str, target: str) -> None:
    """Replace the report's entries in the folder ``target`` by those of the folder
    ``tmp``, ``index.html`` last; the old ones are set aside and deleted. The record goes
    first, listing the old files and the new while they are swapped, and is replaced by
    the new report's at the end. Where a rename fails, what was moved is moved back."""
    with _locked(target):
        _check_out_dir(target)  # still only a report's files
        old = _read_record(target) or {}
        new = _read_record(tmp) or {}
        both = {k: sorted(set(old.get(k, [])) | set(new.get(k, []))) for k in old.keys() | new.keys()}
        both_file = os.path.join(tmp, f"{TEMPORARY_PREFIX}both.json")
        _write_record(both_file, both)
        aside = f"{tmp}-old"
        os.mkdir(aside)
        set_aside: list[str] = []
        moved_in: list[tuple[str, str]] = []  # (from, to)
        try:
            for name, source in (
                (RECORD_NAME, both_file),
                ("figures", os.path.join(tmp, "figures")),
                ("tables", os.path.join(tmp, "tables")),
                ("index.html", os.path.join(tmp, "index.html")),
            ):
                here = os.path.join(target, name)
                if os.path.lexists(here):
                    os.rename(here, os.path.join(aside, name))
                    set_aside.append(name)
                if os.path.lexists(source):
                    os.rename(source, here)
                    moved_in.append((source, here))
            os.replace(os.path.join(tmp, RECORD_NAME), os.path.join(target, RECORD_NAME))
        except BaseException:  # an error or Ctrl-C halfway: the previous report back as it was
            for source, here in reversed(moved_in):
                if os.path.lexists(here) and not os.path.lexists(source):
                    os.rename(here, source)
            for name in set_aside:
                if not os.path.lexists(os.path.join(target, name)):
                    os.rename(os.path.join(aside, name), os.path.join(target, name))
            raise
        finally:
            shutil.rmtree(aside, ignore_errors=True)
        os.rmdir(tmp)


# ----------------------------------------------------------------------------- page parts
@dataclass
class _Page:
    """The page as it is built: HTML parts, and the figures and tables written."""

    folder: str
    parts: list[str] = field(default_factory=list)
    figures: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)

    def add(self, text: str) -> None:
        self.parts.append(text)

    def heading(self, level: int, anchor: str, english: str, russian: str = "") -> None:
        sub = f' <span class="ru">{html.escape(russian)}</span>' if russian else ""
        self.add(f'<h{level} id="{anchor}">{html.escape(english)}{sub}</h{level}>')

    def text(self, paragraph: str) -> None:
        """A paragraph of HTML (already escaped where it holds user text)."""
        self.add(f"<p>{paragraph}</p>")

    def pre(self, text: str) -> None:
        self.add(f"<pre>{html.escape(text.rstrip())}</pre>")

    def figure(self, drawn: Any, name: str, caption: str) -> None:
        """Save what a ``plot()`` returned as ``figures/name.png`` and embed it."""
        os.makedirs(os.path.join(self.folder, "figures"), exist_ok=True)
        path = os.path.join(self.folder, "figures", f"{name}.png")
        save_figure(drawn, path)
        with open(path, "rb") as f:
            data = base64.b64encode(f.read()).decode("ascii")
        self.figures.append(f"{name}.png")
        self.add(
            f'<figure id="fig-{name}"><img src="data:image/png;base64,{data}" alt="{html.escape(caption)}">'
            f"<figcaption>Figure {len(self.figures)}. {html.escape(caption)} "
            f"(<code>figures/{name}.png</code>)</figcaption></figure>"
        )

    def table(
        self,
        name: str,
        caption: str,
        columns: Sequence[tuple[str, str, float, str]],
        data: dict[str, Any],
        *,
        open_: bool = True,
    ) -> None:
        """Write ``tables/name.csv`` (every column of ``data``, SI units) and show
        ``columns`` — (key, heading with unit, scale, format) — as an HTML table."""
        os.makedirs(os.path.join(self.folder, "tables"), exist_ok=True)
        keys = list(data)
        rows = np.column_stack([np.asarray(data[k], dtype=float) for k in keys])
        text = csv_text(keys, rows, what=f"the table {name}")
        with open(os.path.join(self.folder, "tables", f"{name}.csv"), "w", encoding="utf-8", newline="") as f:
            f.write(text)
        self.tables.append(f"{name}.csv")
        head = "".join(f"<th>{html.escape(h)}</th>" for _, h, _, _ in columns)
        body = []
        for i in range(rows.shape[0]):
            cells = "".join(
                f"<td>{_cell(float(np.asarray(data[k])[i]) * scale, fmt)}</td>" for k, _, scale, fmt in columns
            )
            body.append(f"<tr>{cells}</tr>")
        opened = " open" if open_ else ""
        self.add(
            f'<details{opened} id="table-{name}"><summary>Table: {html.escape(caption)} '
            f"(<code>tables/{name}.csv</code>, {rows.shape[0]} rows)</summary>"
            f'<div class="scroll"><table><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table></div>'
            "</details>"
        )

    def frame(self, name: str, caption: str, df: Any, *, open_: bool = False) -> None:
        """A ``pandas.DataFrame`` of a result as ``tables/name.csv`` and an HTML table
        (numbers to 5 significant digits; text columns as they are)."""
        os.makedirs(os.path.join(self.folder, "tables"), exist_ok=True)
        cols = [str(c) for c in df.columns]
        numeric = [df[c].dtype.kind in "biuf" for c in df.columns]
        lines = [",".join(_csv_field(c) for c in cols)]
        body = []
        for row in df.itertuples(index=False):
            values = list(row)
            lines.append(",".join(_csv_value(v, n, name, c) for v, n, c in zip(values, numeric, cols)))
            body.append("<tr>" + "".join(f"<td>{_cell_any(v)}</td>" for v in values) + "</tr>")
        with open(os.path.join(self.folder, "tables", f"{name}.csv"), "w", encoding="utf-8", newline="") as f:
            f.write("\n".join(lines) + "\n")
        self.tables.append(f"{name}.csv")
        head = "".join(f"<th>{html.escape(c)}</th>" for c in cols)
        opened = " open" if open_ else ""
        self.add(
            f'<details{opened} id="table-{name}"><summary>Table: {html.escape(caption)} '
            f"(<code>tables/{name}.csv</code>, {len(body)} rows)</summary>"
            f'<div class="scroll"><table><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table></div>'
            "</details>"
        )


def _cell(v: float, fmt: str) -> str:
    if not math.isfinite(v):
        return "—"
    text = f"{v:{fmt}}"
    return text[1:] if text.startswith("-") and not text.strip("-0.") else text  # no "-0.000"


def _cell_any(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return "—" if not math.isfinite(f) else f"{f + 0.0:.5g}"
    return html.escape(str(v))


def _csv_field(text: str) -> str:
    return '"' + text.replace('"', '""') + '"' if any(c in text for c in ',"\n') else text


def _csv_value(v: Any, numeric: bool, table: str, column: str) -> str:
    """One CSV cell: a number to 10 significant digits (empty where it does not exist,
    as the result's JSON says null), or text."""
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if numeric or isinstance(v, (int, float, np.integer, np.floating)):
        f = float(v)
        if math.isinf(f):
            from ..errors import InternalError

            raise InternalError(f'the table {table}\'s "{column}" is infinite: a number that should exist does not')
        return "" if math.isnan(f) else f"{f + 0.0:.10g}"
    return _csv_field(str(v))


# ----------------------------------------------------------------------------- the calculation
def _figure_step(step_deg: float) -> float:
    """The largest step ≤ :data:`FIGURE_STEP_DEG` that divides ``step_deg`` (``step_deg``
    itself when it is finer)."""
    return step_deg / max(1, math.ceil(step_deg / FIGURE_STEP_DEG - 1e-9))


def _on_step(angle: Any, step_deg: float) -> np.ndarray:
    """Where the angles [deg] fall on the tables' step (a boolean mask)."""
    a = np.asarray(angle, dtype=float)
    k = a / step_deg
    return np.abs(k - np.round(k)) < 1e-6


def _tangential(engine: Engine, angle_deg: np.ndarray, omega: float, kinematics: str) -> dict[str, Any]:
    """The total torque and tangential force at constant speed and, for each cylinder with
    its own rod (not a slave of an articulated rod), its tangential force, at ``angle_deg``."""
    theta = jnp.deg2rad(jnp.asarray(angle_deg))
    R = float(engine.geometry.crank_radius_m)
    total = np.asarray(total_torque(engine, theta, omega, kinematics))
    slaves = set(engine.slave_index())
    t_cyl = {
        c: np.asarray(crank_forces(engine, theta, omega, c, kinematics)["t_N"])
        for c in range(1, engine.cylinders + 1)
        if c - 1 not in slaves
    }
    check_results_finite(f"the total torque of engine {engine.name!r}", {"total_torque_Nm": total})
    return {"total_Nm": total, "t_sum_N": total / R, "t_cyl_N": t_cyl}


def _counterweights_text(engine: Engine) -> str:
    cw = engine.counterweights
    if cw is None:
        return "none in the engine file"
    mr = np.asarray(cw.mass_kg) * np.asarray(cw.radius_m)
    return f"{len(cw.webs)} on webs {', '.join(map(str, cw.webs))}, Σ m·r = {float(np.sum(mr)):.4g} kg·m"


def _inputs_text(engine: Engine, rpm: float, kinematics: str, delta: float) -> str:
    g = engine.geometry
    m_rec, m_rot = engine.masses.two_mass_split(g.rod_length_m)
    omega = rpm * RAD_S_PER_RPM
    rows = [
        (
            "engine",
            f"{engine.name} ({engine.cylinders} cylinder{'s' if engine.cylinders != 1 else ''}, {engine.strokes}-stroke)",
        ),
        ("speed", f"{rpm:g} rpm (ω = {omega:.2f} rad/s)"),
        ("bore × stroke", f"{float(g.bore_m) * 1e3:.1f} × {float(g.stroke_m) * 1e3:.1f} mm"),
        ("crank radius R, λ = R/L", f"{float(g.crank_radius_m) * 1e3:.2f} mm, {float(g.rod_ratio):.4f}"),
        ("piston pin offset k", f"{float(g.pin_offset_m) * 1e3:.2f} mm"),
        ("piston area", f"{float(g.piston_area_m2):.5f} m²"),
        ("reciprocating mass per cylinder", f"{float(m_rec):.3f} kg"),
        ("rotating mass per cylinder", f"{float(m_rot):.3f} kg"),
        ("mean piston speed", f"{float(mean_piston_speed(g.stroke_m, omega)):.2f} m/s"),
        ("firing order", "-".join(str(c) for c in engine.layout.firing_order)),
        ("throw angles", ", ".join(f"{float(a):g}°" for a in np.ravel(engine.layout.throw_angles_deg))),
        ("bank angles", ", ".join(f"{float(a):g}°" for a in np.ravel(engine.layout.banks_deg))),
        ("counterweights", _counterweights_text(engine)),
        ("piston kinematics", "λ series (as the guide's table)" if kinematics == "series" else "exact"),
        ("flywheel target δ", f"{delta:g}"),
    ]
    w = max(len(k) for k, _ in rows)
    return "\n".join(f"{k.ljust(w)}  {v}" for k, v in rows)


_CRANK_COLUMNS = (
    ("angle_deg", "φ [deg]", 1.0, ".0f"),
    ("s_m", "S [m]", 1.0, ".4f"),
    ("v_m_s", "V [m/s]", 1.0, ".3f"),
    ("j_m_s2", "J [m/s²]", 1.0, ".1f"),
    ("pg_N", "Pg [kN]", 1e-3, ".3f"),
    ("pj_N", "Pj [kN]", 1e-3, ".3f"),
    ("psum_N", "PΣ [kN]", 1e-3, ".3f"),
    ("n_N", "N [kN]", 1e-3, ".3f"),
    ("k_N", "K [kN]", 1e-3, ".3f"),
    ("z_N", "Z [kN]", 1e-3, ".3f"),
    ("t_N", "T [kN]", 1e-3, ".3f"),
    ("m_Nm", "M [N·m]", 1.0, ".1f"),
)


def _kinematics_and_forces(page: _Page, table: CrankTable, fine: CrankTable, cycle: float, vm: float) -> None:
    c = fine.columns
    a = c["angle_deg"]
    head = f"{table.engine_name}, cylinder 1 at {table.rpm:g} rpm"
    page.heading(2, "kinematics", "Piston kinematics", "Кинематический расчёт")
    page.text(
        "Displacement S, velocity V and acceleration J of the piston over one revolution (they repeat in the "
        f"second), with the mean piston speed v<sub>m</sub> = S·n/30 = {vm:.2f} m/s (Shishkov 2014, §3.1)."
    )
    axes = fine.plot(which="kinematics")
    axes[1].axhline(vm, color="C3", ls="--", lw=1.0, label=f"mean piston speed {vm:.2f} m/s")
    axes[1].axhline(-vm, color="C3", ls="--", lw=1.0)
    axes[1].legend(fontsize=8)
    page.figure(axes, "kinematics", "Piston displacement, velocity and acceleration (S, V, J)")

    page.heading(2, "forces", "Forces of the crank mechanism", "Силы, действующие в КШМ")
    page.text(
        "Gas force P<sub>g</sub> = (p − p<sub>0</sub>)·F<sub>p</sub>, reciprocating inertia force "
        "P<sub>j</sub> = −m<sub>j</sub>·J and their sum P<sub>Σ</sub> along the cylinder axis; the force along "
        "the rod K = P<sub>Σ</sub>/cos β (P<sub>ш</sub> in the guide), the normal force N = P<sub>Σ</sub>·tg β "
        "on the cylinder wall, the force along the crank Z and the tangential force T (Shishkov 2014, §3.2.2–3.2.3)."
    )
    page.figure(
        plot_curves(
            a,
            [(c["pg_N"] / 1e3, "gas force P_g"), (c["pj_N"] / 1e3, "inertia force P_j"), (c["psum_N"] / 1e3, "P_Σ")],
            "force [kN]",
            f"{head}: gas, reciprocating inertia and total force",
            cycle,
        ),
        "forces_pg_pj_psum",
        "Gas force Pg, reciprocating inertia force Pj and total force PΣ (сила давления газов, сила инерции, "
        "суммарная сила)",
    )
    page.figure(
        plot_curves(
            a,
            [
                (c["k_N"] / 1e3, "along the rod K (P_ш)"),
                (c["n_N"] / 1e3, "normal N"),
                (c["z_N"] / 1e3, "along the crank Z"),
            ],
            "force [kN]",
            f"{head}: force along the rod, normal force, force along the crank",
            cycle,
        ),
        "forces_k_n_z",
        "Force along the rod K (Pш), normal force N and force along the crank Z",
    )
    page.text(
        "The kinematic and dynamic table of cylinder 1 (Shishkov 2014, appendix 5), angle 0° at TDC at the start "
        "of intake, 360° at firing TDC."
    )
    which = "the λ series, as the guide's table and rotor table" if table.kinematics == "series" else "exact"
    page.table(
        "crank_table",
        f"kinematics and forces of cylinder 1 ({which} kinematics; rotor table gives the λ series unless told)",
        _CRANK_COLUMNS,
        table.columns,
    )


# ----------------------------------------------------------------------------- the page
_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; max-width: 1000px; margin: 2em auto;
       padding: 0 1em; color: #222; line-height: 1.45; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: .2em; margin-top: 2em; }
.ru { color: #777; font-weight: normal; font-size: .75em; margin-left: .5em; }
figure { margin: 1.5em 0; text-align: center; } figure img { max-width: 100%; height: auto; }
figcaption { font-size: .9em; color: #444; }
pre { background: #f6f6f6; padding: .8em; overflow-x: auto; font-size: .85em; }
table { border-collapse: collapse; font-size: .8em; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #ddd; padding: .15em .5em; text-align: right; } th { background: #f0f0f0; }
.scroll { max-height: 32em; overflow: auto; } details { margin: 1em 0; } summary { cursor: pointer; }
nav ol { columns: 2; } #render-check { color: #777; font-size: .85em; }
"""

# counts the figures the browser could decode and draw; a headless browser's test reads it
_SCRIPT = """
window.addEventListener("load", function () {
  var images = document.querySelectorAll("figure img"), drawn = 0;
  for (var i = 0; i < images.length; i++) {
    if (images[i].complete && images[i].naturalWidth > 0) { drawn++; }
  }
  var p = document.getElementById("render-check");
  p.setAttribute("data-figures", String(images.length));
  p.setAttribute("data-rendered", String(drawn));
  p.textContent = drawn + " of " + images.length + " figures rendered in this browser.";
});
"""


def _html(title: str, body: list[str], toc: list[tuple[str, str]], n_figures: int) -> str:
    nav = "".join(f'<li><a href="#{a}">{html.escape(t)}</a></li>' for a, t in toc)
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f'<meta name="generator" content="rotor">\n<title>{html.escape(title)}</title>\n'
        f"<style>{_STYLE}</style>\n</head>\n<body>\n"
        f"<h1>{html.escape(title)}</h1>\n<nav><ol>{nav}</ol></nav>\n"
        + "\n".join(body)
        + f'\n<p id="render-check" data-figures="{n_figures}" data-rendered="">'
        "(a script counts the figures your browser rendered)</p>\n"
        f"<script>{_SCRIPT}</script>\n</body>\n</html>\n"
    )


def report(
    engine: Engine,
    out_dir: str | os.PathLike,
    rpm: float | None = None,
    *,
    step_deg: float = 10.0,
    delta: float = DEFAULT_DELTA,
    kinematics: str = "exact",
    orders: int = 6,
) -> Report:
    """Write the whole kinematic and dynamic calculation of ``engine`` at ``rpm`` into the
    folder ``out_dir``: ``index.html`` (one self-contained page), ``figures/*.png`` and
    ``tables/*.csv`` (see :mod:`rotor.design.report`).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``out_dir``: the report's folder (a ``str`` or ``pathlib.Path``): new, empty or a
      previous report's (which is replaced; a folder holding anything else is refused, see
      :mod:`rotor.design.report`); its parent folders are made.
    - ``rpm``: crank speed [rev/min]; default the engine's ``[operating] rpm``.
    - ``step_deg``: the tables' angle step [deg], dividing the cycle (720° or 360°);
      the figures are drawn at the largest step ≤ 1° that divides it.
    - ``delta``: the textbook flywheel's target irregularity δ = (ω_max − ω_min)/ω_mean [-].
    - ``kinematics``: piston kinematics of every table and diagram, ``"exact"`` (default)
      or ``"series"`` (the λ series of the guide).
    - ``orders``: the highest order of the balance [-].

    **Returns:** a :class:`Report` naming every file written.

    **Raises:** :class:`rotor.EngineError` for a bad argument (checked before anything is
    computed or written); an ``OSError`` naming ``out_dir`` where it cannot be written (a
    file, a folder holding files that are not a previous report's own);
    :class:`rotor.NoSteadyStateError` where the engine has no steady state for the
    flywheel's excess work.
    """
    t0 = time.perf_counter()
    require_engine(engine, "report(engine)").check()
    rpm = float(engine.operating.rpm) if rpm is None else check_speed_rpm(rpm, "rpm")
    if kinematics not in ("exact", "series"):
        raise EngineError(f"kinematics = {kinematics!r}: 'exact' or 'series' (the guide's λ series)")
    table_angles_deg(engine, step_deg)  # the step divides the cycle
    step_deg = float(step_deg)
    d = require_number(delta, "report(delta)")
    if not (math.isfinite(d) and DELTA_MIN <= d < 1):
        raise EngineError(
            f"delta = {delta!r}: the flywheel's target irregularity (ω_max − ω_min)/ω_mean must lie in "
            f"[{DELTA_MIN:g}, 1), e.g. 0.01 for 1 %"
        )
    orders = require_whole(orders, "report(orders)")
    path = _check_out_dir(out_dir)
    fine_deg = _figure_step(step_deg)

    cycle = 360.0 * engine.strokes / 2
    omega = rpm * RAD_S_PER_RPM
    fine = crank_table(engine, rpm, fine_deg, kinematics)
    at = _on_step(fine.columns["angle_deg"], step_deg)  # the table is every k-th row of the figures' one
    table = dataclasses.replace(fine, columns={k: np.asarray(v)[at] for k, v in fine.columns.items()})
    fly = textbook_flywheel(engine, d, rpm)
    loads = bearing_loads(engine, rpm, step_deg=fine_deg, model=kinematics)
    bal = balance(engine, rpm, orders=orders, model=kinematics)
    vm = float(mean_piston_speed(engine.geometry.stroke_m, omega))

    with report_folder(path) as tmp:
        page = _Page(tmp)
        title = f"Dynamic calculation of the {engine.name} at {rpm:g} rpm"
        page.text(
            "The kinematic and dynamic calculation of the crank mechanism as in the course project of Shishkov, "
            "<i>Dinamika dvigatelei</i> (SUSU 2014, after Kolchin &amp; Demidov and Popyk), made by rotor at "
            "constant crank speed. Forces in SI units; angles in degrees of crank rotation. Every figure is also in "
            "<code>figures/</code> and every table in <code>tables/</code> beside this page."
        )
        page.heading(2, "inputs", "Inputs", "Исходные данные")
        page.pre(_inputs_text(engine, rpm, kinematics, d))
        _kinematics_and_forces(page, table, fine, cycle, vm)
        _torque_section(page, engine, table, fine, fly, omega, kinematics, cycle, step_deg)
        _bearing_section(page, loads, step_deg)
        _balance_section(page, bal)
        page.heading(2, "sources", "Sources", "Литература")
        page.add("<ol>" + "".join(f"<li>{s}</li>" for s in SOURCES) + "</ol>")
        page.text(
            f"Written by rotor: <code>rotor report</code> ({kinematics} kinematics, tables every {step_deg:g}°, "
            f"figures every {fine_deg:g}°)."
        )
        text = _html(title, page.parts, list(_TOC), len(page.figures))
        with open(os.path.join(tmp, "index.html"), "w", encoding="utf-8", newline="") as f:
            f.write(text)
        figures, tables = tuple(page.figures), tuple(page.tables)
    return Report(
        engine_name=engine.name,
        rpm=rpm,
        step_deg=step_deg,
        figure_step_deg=fine_deg,
        delta=d,
        kinematics=kinematics,
        out_dir=path,
        figures=figures,
        tables=tables,
        seconds=time.perf_counter() - t0,
    )


_TOC = (
    ("inputs", "Inputs"),
    ("kinematics", "Piston kinematics"),
    ("forces", "Forces of the crank mechanism"),
    ("torque", "Tangential force and total torque"),
    ("flywheel", "Turning-moment diagram and flywheel"),
    ("bearings", "Bearing loads"),
    ("balance", "Balance"),
    ("sources", "Sources"),
)


def _torque_section(
    page: _Page,
    engine: Engine,
    table: CrankTable,
    fine: CrankTable,
    fly: Any,
    omega: float,
    kinematics: str,
    cycle: float,
    step_deg: float,
) -> None:
    a = fine.columns["angle_deg"]
    tq = _tangential(engine, a, omega, kinematics)
    total = tq["total_Nm"]
    mean = float(np.mean(total[:-1]))
    R = float(engine.geometry.crank_radius_m)
    dtheta = np.deg2rad(np.diff(a))
    work = np.concatenate([[0.0], np.cumsum(0.5 * (total[1:] + total[:-1] - 2 * mean) * dtheta)])
    excess = float(np.max(work) - np.min(work))
    head = f"{engine.name} at {fine.rpm:g} rpm"

    page.heading(2, "torque", "Tangential force and total torque", "Суммарная тангенциальная сила и крутящий момент")
    page.text(
        "The tangential force T of each cylinder at its phase in the firing order, their sum T<sub>Σ</sub> and its "
        f"mean T<sub>Σ mean</sub> = {mean / R / 1e3:.3f} kN; the total torque M<sub>Σ</sub> = T<sub>Σ</sub>·R, "
        f"mean {mean:.1f} N·m (Shishkov 2014, §3.2.11)."
    )
    page.figure(
        plot_tangential_forces(a, tq["t_cyl_N"], tq["t_sum_N"], mean / R, f"{head}: tangential forces", cycle),
        "tangential",
        "Tangential force T, total tangential force TΣ and its mean TΣ mean",
    )
    at = _on_step(a, step_deg)
    data: dict[str, Any] = {"angle_deg": a[at]}
    for c, t in tq["t_cyl_N"].items():
        data[f"t{c}_N"] = t[at]
    data["t_sum_N"] = tq["t_sum_N"][at]
    data["m_sum_Nm"] = total[at]
    cols = [("angle_deg", "φ [deg]", 1.0, ".0f")]
    cols += [(f"t{c}_N", f"T{c} [kN]", 1e-3, ".3f") for c in tq["t_cyl_N"]]
    cols += [("t_sum_N", "TΣ [kN]", 1e-3, ".3f"), ("m_sum_Nm", "MΣ [N·m]", 1.0, ".1f")]
    page.table("tangential", "tangential forces of the cylinders and the total torque", cols, data, open_=False)

    page.heading(2, "flywheel", "Turning-moment diagram and flywheel", "Избыточная работа и расчёт маховика")
    page.text(
        "The total torque over the cycle against its mean: the work of the difference, ∫(M<sub>Σ</sub> − "
        "M<sub>mean</sub>)dθ, swings by the excess work L<sub>excess</sub> (the area above the mean, "
        f"L<sub>изб</sub> of the guide): {excess:.1f} J on this diagram ({kinematics} kinematics, trapezoid rule "
        f"on its {float(np.median(np.diff(a))):g}° grid); the flywheel below, like <code>rotor steady</code> and <code>rotor "
        f"flywheel</code>, sums it on the crank-train tables: {float(fly.excess_work_J):.1f} J. The flywheel "
        "follows Shishkov 2014, "
        "§3.2.12: J<sub>0</sub> = L<sub>excess</sub>/(δ·ω²), J<sub>flywheel</sub> = 0.85·J<sub>0</sub>, "
        "m = 4·J<sub>flywheel</sub>/D² at a mean diameter D = 2.5·S."
    )
    page.figure(
        plot_turning_moment(a, total, mean, work, excess, f"{head}: turning-moment diagram", cycle),
        "turning_moment",
        "Turning-moment diagram: total torque, its mean, and the excess work",
    )
    page.pre(fly.summary())
    page.figure(fly.plot(), "flywheel", "Textbook flywheel: J₀ and its split")
    page.frame("flywheel", "textbook flywheel", fly.to_pandas(), open_=False)


def _per_element(
    angle: np.ndarray, at: np.ndarray, parts: Sequence[tuple[str, str, np.ndarray, float, str]], numbers: Sequence[int]
) -> tuple[list[tuple[str, str, float, str]], dict[str, Any]]:
    """Columns and data of a table with one group of columns per element (throw, rod or
    journal): ``parts`` are (key, heading, array (n, elements), scale,
    format) with ``{}`` in the key and heading for the element's number."""
    cols: list[tuple[str, str, float, str]] = [("angle_deg", "φ [deg]", 1.0, ".0f")]
    data: dict[str, Any] = {"angle_deg": angle[at]}
    for e, number in enumerate(numbers):
        for key_form, head, values, scale, fmt in parts:
            key = key_form.format(number)
            data[key] = np.asarray(values)[at, e]
            cols.append((key, head.format(number), scale, fmt))
    return cols, data


def _bearing_section(page: _Page, loads: Any, step_deg: float) -> None:
    page.heading(2, "bearings", "Bearing loads", "Нагрузки на шейки и подшипники")
    page.text(
        "The crank pin carries the rod's force, T and Z<sub>1</sub> = Z + S<sub>2</sub> with the centrifugal force "
        "of the rod's rotating share S<sub>2</sub> = −m<sub>2</sub>·R·ω², resultant Q; the big-end bearing sees the "
        "same load turned with the rod by φ + β; each main journal carries the forces of the throws beside it "
        "(each span simply supported) and the counterweights; the main bearing sees the journal's load in the block. "
        "The wear diagram sums each load over a ±60° sector of the journal's circle; the least loaded ray is the "
        "place for the oil hole. The running torque a main journal passes on is the sum of the torques of the "
        "throws in front of it (Shishkov 2014, §3.2.4–3.2.9; Kolchin &amp; Demidov)."
    )
    page.pre(loads.summary())
    j = int(loads.worst_journal)
    drawings: list[tuple[Callable[[], Any], str, str]] = [
        (loads.plot_crank_pin, "crank_pin_polar", "Polar load diagram of crank pin 1 (ПДН на шатунную шейку)"),
        (
            loads.plot_big_end,
            "big_end_polar",
            "Polar load diagram of the big-end bearing of cylinder 1 (ПДН на шатунный подшипник)",
        ),
        (
            loads.plot_developed,
            "crank_pin_developed",
            "Developed load diagram of crank pin 1 with its mean (РДН на шатунную шейку)",
        ),
        (
            lambda: loads.plot_main_journal(journal=j),
            "main_journal_polar",
            f"Polar load diagram of main journal {j}, the most loaded (ПДН на коренную шейку)",
        ),
        (
            lambda: loads.plot_main_bearing(journal=j),
            "main_bearing_polar",
            f"Polar load diagram of main bearing {j} (ПДН на коренной подшипник)",
        ),
        (loads.plot_wear, "crank_pin_wear", "Wear diagram of crank pin 1 (диаграмма износа шатунной шейки)"),
        (
            lambda: loads.plot_wear(journal=j),
            "main_journal_wear",
            f"Wear diagram of main journal {j} (диаграмма износа коренной шейки)",
        ),
        (
            loads.plot_running_torques,
            "running_torques",
            "Running torques on the main journals (набегающие моменты на коренные шейки)",
        ),
    ]
    for draw, name, caption in drawings:
        page.figure(draw(), name, caption)
    a = np.asarray(loads.angle_deg)
    at = _on_step(a, step_deg)
    kn = (1e-3, ".2f")
    throws = range(1, loads.throws + 1)
    journals = range(1, loads.journals + 1)
    pin = loads.pin_q_N
    cols, data = _per_element(
        a,
        at,
        [
            ("t{}_N", "T{} [kN]", loads.pin_t_N, *kn),
            ("z1_{}_N", "Z₁ {} [kN]", loads.pin_z1_N, *kn),
            ("q{}_N", "Q{} [kN]", pin, *kn),
        ],
        throws,
    )
    page.table("crank_pin_loads", "loads on the crank pins (T, Z₁, Q by throw)", cols, data, open_=False)
    cols, data = _per_element(
        a,
        at,
        [
            ("t{}_N", "t{} [kN]", loads.big_end_t_N, *kn),
            ("z{}_N", "z{} [kN]", loads.big_end_z_N, *kn),
            ("q{}_N", "Q{} [kN]", loads.big_end_q_N, *kn),
        ],
        loads.big_end_cylinders,
    )
    page.table("big_end_loads", "loads on the big-end bearings (rod frame, by cylinder)", cols, data, open_=False)
    cols, data = _per_element(
        a,
        at,
        [
            ("t{}_N", "T{} [kN]", loads.journal_t_N, *kn),
            ("z{}_N", "Z{} [kN]", loads.journal_z_N, *kn),
            ("q{}_N", "Q{} [kN]", loads.journal_q_N, *kn),
            ("m{}_Nm", "M{} [N·m]", loads.running_torque_Nm, 1.0, ".0f"),
        ],
        journals,
    )
    page.table(
        "main_journal_loads",
        "loads on the main journals (shaft frame) and their running torques, by journal",
        cols,
        data,
        open_=False,
    )
    q_bearing = np.hypot(loads.bearing_t_N, loads.bearing_z_N)
    cols, data = _per_element(
        a,
        at,
        [
            ("t{}_N", "t{} [kN]", loads.bearing_t_N, *kn),
            ("z{}_N", "z{} [kN]", loads.bearing_z_N, *kn),
            ("q{}_N", "Q{} [kN]", q_bearing, *kn),
        ],
        journals,
    )
    page.table("main_bearing_loads", "loads on the main bearings (block frame), by journal", cols, data, open_=False)
    page.frame("wear", "wear diagrams: the mean load on each ray, and the oil hole", loads.wear_to_pandas())


def _balance_section(page: _Page, bal: Any) -> None:
    import pandas as pd

    page.heading(2, "balance", "Balance", "Уравновешивание")
    page.text(
        "Free forces and free moments of the reciprocating and rotating masses by order, each the largest magnitude "
        "of that order over the cycle, with and without the counterweights of the engine file; the textbook's six "
        "conditions of a balanced engine (two more of all masses where there are counterweights) and what balance shafts would need (Shishkov 2014, §3.2.10; Popyk)."
    )
    page.pre(bal.summary())
    orders = bal.to_json_dict()["orders"]
    keys = list(orders[0]) if orders else ["order"]
    data = {k: np.array([np.nan if o[k] is None else o[k] for o in orders], dtype=float) for k in keys}
    heads = {
        "order": ("order", 1.0, ".0f"),
        "free_force_N": ("free force [N]", 1.0, ".1f"),
        "free_moment_Nm": ("free moment [N·m]", 1.0, ".1f"),
        "free_force_without_counterweights_N": ("free force without counterweights [N]", 1.0, ".1f"),
        "free_moment_without_counterweights_Nm": ("free moment without counterweights [N·m]", 1.0, ".1f"),
    }
    cols = [(k, *heads.get(k, (k, 1.0, ".5g"))) for k in keys]
    page.table("balance_orders", "free forces and moments by order", cols, data)
    page.figure(bal.plot(), "balance_orders", "Free forces and moments by order, with and without counterweights")
    page.figure(bal.plot(which="ellipses"), "balance_ellipses", "Force and moment ellipses of orders 1 and 2")
    page.frame(
        "balance_conditions",
        f"the {len(bal.conditions)} conditions of a balanced engine (the textbook's six"
        + (", and two of all masses with the counterweights)" if len(bal.conditions) > 6 else ")"),
        pd.DataFrame(list(bal.conditions)),
    )
    page.frame("balance_detail", "every source's force and moment ellipses by order", bal.to_pandas())
