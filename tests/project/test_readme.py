"""The code of README.md and of the documentation runs as written, and their text speaks to users.

- Every ```python and ```sh block of README.md and of the pages of docs/ runs, in order,
  in one namespace per page (a later block may use names from an earlier one), in a
  temporary working directory of its own, with matplotlib's Agg backend. Each command of
  a shell block runs and must exit with 0: ``rotor …`` in this process (what the pages
  before compiled is reused), anything else in bash. A synopsis is a ```text block, not
  run. A ```toml block
  right after ``<!-- file: NAME -->`` is written to NAME there first, so that a page can
  show a whole engine file and then load it. A block right after ``<!-- no-test -->`` is
  skipped (use it only with a reason written next to it: an install, a command that needs
  a server). A failure names the page's own line. All pages run in one process, so that a
  kernel compiled for one is reused by the next (the pages keep to the same presets and
  small cycle counts for that reason).
- A few figures the pages' comments quote are checked against what the blocks computed.
- Every ``rotor …`` command line of their ```sh blocks, those left out of the run too, is
  parsed by the ``rotor`` parser (a real command, options it takes).
- The README stays a landing page (at most 300 lines) that keeps `make demo` and
  `make test`, and every figure it shows exists.
- No text in README.md, docs/, the package or benchmarks/README.md cites the project's
  internal working-copy documents: users do not have them; the physics page's "Sources"
  names the published works. The documentation speaks of the package's layers and
  subpackages, never of the project's own shorthand for them.
"""

from __future__ import annotations

import ast
import os
import re
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
from conftest import ROOT

README = ROOT / "README.md"
DOCS = ROOT / "docs"
HOW_TO = DOCS / "how-to"
NO_TEST = "<!-- no-test -->"
FILE = re.compile(r"^<!-- file: ([\w.-]+) -->$")
SHELL_FENCES = ("```sh", "```bash")
"""The fences of the shell blocks the suite runs; a synopsis (``rotor analyze LOG [--json]``)
is a ```text block, shown and never run."""


@dataclass(frozen=True)
class Block:
    """A block of a page to run: ``kind`` "python" (run in the page's namespace), "sh" (each
    command run in the page's folder) or "file" (``source`` written to ``file`` there);
    ``line`` is the page's line of its first line of code."""

    line: int
    source: str
    kind: str
    file: str | None = None


def _previous(lines: list[str], i: int) -> str:
    return next((ln.strip() for ln in reversed(lines[:i]) if ln.strip()), "")


def blocks(text: str, name: str = "README.md") -> list[Block]:
    """Every block to run, in page order: a ```python or ```sh block not marked
    ``<!-- no-test -->``, or a ```toml block marked ``<!-- file: NAME -->`` (its text is
    written to NAME)."""
    lines = text.splitlines()
    out, i = [], 0
    while i < len(lines):
        fence = lines[i].strip()
        if fence in ("```python", "```toml", *SHELL_FENCES):
            j = i + 1
            while j < len(lines) and lines[j].strip() != "```":
                j += 1
            assert j < len(lines), f"{name}:{i + 1}: a {fence} block that never ends"
            previous = _previous(lines, i)
            body = "\n".join(lines[i + 1 : j])
            if fence == "```python" and previous != NO_TEST:
                out.append(Block(i + 2, body, "python"))
            elif fence in SHELL_FENCES and previous != NO_TEST:
                out.append(Block(i + 2, body, "sh"))
            elif fence == "```toml" and (m := FILE.match(previous)):
                out.append(Block(i + 2, body + "\n", "file", m.group(1)))
            i = j
        i += 1
    return out


def python_blocks(text: str) -> list[tuple[int, str]]:
    """(first line number, source) of every ```python block not marked ``<!-- no-test -->``."""
    return [(b.line, b.source) for b in blocks(text) if b.kind == "python"]


def shell_commands(source: str, first_line: int = 1) -> list[tuple[int, str]]:
    """(line number, command) of each command of a shell block: continuation lines joined,
    comments and blank lines dropped."""
    out, buf, start = [], "", None
    for n, raw in enumerate(source.splitlines(), first_line):
        line = raw.strip()
        if not buf and (not line or line.startswith("#")):
            continue
        start = n if not buf else start
        if line.endswith("\\"):
            buf += line[:-1].strip() + " "
            continue
        command = (buf + line).split(" #")[0].strip()
        buf = ""
        if command:
            out.append((start, command))
    return out


def run_command(command: str) -> tuple[int, str, str]:
    """Run one command of a shell block in the working directory: (exit status, stdout,
    stderr). ``rotor …`` runs in this process through :func:`rotor.cli.app.main` (the
    compiled kernels of the pages' Python blocks and of the commands before it are reused),
    with a leading ``cat FILE |`` as its standard input and a trailing ``> FILE`` as its
    standard output; any other command runs in ``bash``, with the virtualenv's ``rotor``
    first on the PATH."""
    import contextlib
    import io
    import shlex
    import subprocess
    import sys

    words = shlex.split(command)
    stdin = stdout = None
    if len(words) > 3 and words[0] == "cat" and words[2] == "|":
        stdin, words = words[1], words[3:]
    if len(words) > 2 and words[-2] == ">":
        stdout, words = words[-1], words[:-2]
    if words[0] != "rotor" or any(w in ("|", ">", ">>", "<", "&&", ";") for w in words):
        env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
        done = subprocess.run(["bash", "-c", command], capture_output=True, text=True, env=env, timeout=600)
        return done.returncode, done.stdout, done.stderr
    from rotor.cli.app import main

    out, err = io.StringIO(), io.StringIO()
    saved = sys.stdin
    try:
        with contextlib.ExitStack() as stack:
            if stdin is not None:
                sys.stdin = stack.enter_context(open(stdin, encoding="utf-8"))  # noqa: SIM115
            stack.enter_context(contextlib.redirect_stdout(out))
            stack.enter_context(contextlib.redirect_stderr(err))
            try:
                rc = main(words[1:])
            except SystemExit as e:  # argparse's own usage errors
                rc = 0 if e.code is None else int(e.code)
    finally:
        sys.stdin = saved
    if stdout is not None:
        Path(stdout).write_text(out.getvalue(), encoding="utf-8")
    return rc, out.getvalue(), err.getvalue()


def _other_pages() -> list[Path]:
    """The pages of docs/ outside the tutorial and the guides that hold a block to run."""
    return [
        p
        for p in sorted(DOCS.rglob("*.md"))
        if p.parent != HOW_TO and p.name != "getting-started.md" and blocks(p.read_text(encoding="utf-8"), str(p))
    ]


PAGES = [
    README,
    DOCS / "getting-started.md",
    *sorted(p for p in HOW_TO.glob("*.md") if p.name != "index.md"),
    *_other_pages(),
]


def _id(path: Path) -> str:
    return path.relative_to(ROOT).as_posix()


_RUN: dict[Path, dict] = {}
OUTPUTS = "__commands__"
"""The namespace's key of what each shell command printed: {command: (stdout, stderr)}."""


_RAN: dict[str, tuple[int, str, str, dict[str, bytes]]] = {}
"""The commands run so far that read no file of their page (presets only): their exit
status, output and the files they wrote (path relative to the page's folder: content)."""


def _files() -> dict[str, float]:
    return {p.as_posix(): p.stat().st_mtime for p in Path().rglob("*") if p.is_file()}


def run_once(command: str) -> tuple[int, str, str]:
    """:func:`run_command`, except that a command which reads no file of the page's folder
    (its engine a preset, say) and ran on an earlier page as written is not run again:
    its output is the same, and the files it wrote then are written here (a page may read
    them)."""
    import shlex

    reads_a_file = any(Path(w).exists() for w in shlex.split(command)[1:] if not w.startswith("-"))
    if not reads_a_file and command in _RAN:
        rc, out, err, written = _RAN[command]
        for rel, content in written.items():
            Path(rel).parent.mkdir(parents=True, exist_ok=True)
            Path(rel).write_bytes(content)
        return rc, out, err
    before = _files()
    rc, out, err = run_command(command)
    if not reads_a_file:
        after = _files()
        written = {rel: Path(rel).read_bytes() for rel, mtime in after.items() if before.get(rel) != mtime}
        _RAN[command] = (rc, out, err, written)
    return rc, out, err


def run_block(block: Block, path: Path, ns: dict) -> None:
    """Run one block of the page ``path`` in the working directory: a Python block in the
    namespace ``ns``, each command of a shell block (its output kept in ``ns[OUTPUTS]``),
    a file block written; a failure names the page's line."""
    name = _id(path)
    if block.kind == "file":
        Path(block.file).write_text(block.source, encoding="utf-8")
    elif block.kind == "sh":
        for line, command in shell_commands(block.source, block.line):
            rc, out, err = run_once(command)
            if rc != 0:
                tail = "\n".join((err or out).strip().splitlines()[-5:])
                raise AssertionError(f"{name}:{line}: `{command}` exits with {rc}:\n{tail}")
            ns[OUTPUTS][command] = (out, err)
    else:
        # padded so that a traceback names the page's own line
        code = compile("\n" * (block.line - 1) + block.source, str(path), "exec")
        try:
            exec(code, ns)
        except Exception as e:
            raise AssertionError(f"{name}: the python block at line {block.line} fails: {e!r}") from e


def run_page(path: Path, tmp_path_factory) -> dict:
    """Run every block of ``path`` in order in one namespace, in a temporary working
    directory of its own; the namespace, computed once per session."""
    if path in _RUN:
        return _RUN[path]
    folder = tmp_path_factory.mktemp(path.stem)
    old = os.getcwd()
    os.chdir(folder)
    ns: dict = {"__name__": "__docs__", OUTPUTS: {}}
    try:
        for block in blocks(path.read_text(encoding="utf-8"), _id(path)):
            try:
                run_block(block, path, ns)
            finally:
                plt.close("all")
    finally:
        os.chdir(old)
    _RUN[path] = ns
    return ns


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    """``page("how-to/x.md")`` or ``page("README.md")``: that page's namespace after its blocks ran."""

    def get(name: str) -> dict:
        path = README if name == "README.md" else DOCS / name
        return run_page(path, tmp_path_factory)

    return get


def test_blocks_are_found():
    readme = blocks(README.read_text(encoding="utf-8"))
    assert len(readme) >= 3
    assert len(PAGES) >= 9
    for path in PAGES:
        for b in blocks(path.read_text(encoding="utf-8"), _id(path)):
            if b.kind == "python":
                ast.parse(b.source, f"{_id(path)}:{b.line}")


@pytest.mark.parametrize("path", PAGES, ids=_id)
def test_page_blocks_run(path, tmp_path_factory):
    ns = run_page(path, tmp_path_factory)
    assert ns[OUTPUTS] or "rotor" in ns


def test_readme_figures(page):
    """Figures the README's comments quote."""
    ns = page("README.md")
    ss, a, ident, mis = ns["ss"], ns["a"], ns["ident"], ns["mis"]
    assert float(ss.delta) == pytest.approx(0.006665, abs=0.000005)  # "δ = 0.006665"
    assert float(ss.load_torque_Nm) == pytest.approx(1131.9, abs=0.05)  # "1131.9 N·m"
    assert np.allclose(a.mean_rpm, 3000.0, atol=0.05)  # "3000.0 rpm"
    assert 0.06605 <= np.min(a.delta) and np.max(a.delta) <= 0.06635  # "δ 0.0661…0.0663"
    assert ident.misfires() == [(6, 3)]  # "[(6, 3)]"
    fired = np.asarray(mis.imep_pa) > 0
    assert np.max(np.abs(np.asarray(ident.imep_pa)[fired] / np.asarray(mis.imep_pa)[fired] - 1)) < 1e-6


def test_wheel_log_figures(page):
    ns = page("how-to/read-a-wheel-log.md")
    a, four = ns["a"], ns["four"]
    assert np.allclose(a.mean_rpm, 3000.0, atol=0.05)  # "3000.0 rpm"
    assert 0.06605 <= np.min(a.delta) and np.max(a.delta) <= 0.06635  # "δ 0.0661…0.0663"
    assert float(np.mean(four.delta)) == pytest.approx(0.0176, abs=0.0005)  # "its δ, 0.0176"
    assert float(np.mean(four.delta)) / 0.006665 == pytest.approx(2.6, abs=0.1)  # "2.6 times"
    assert four.to_json_dict()["firing_revolution_parity"] == 1  # "firing=1"


def test_calibration_figures(page):
    ns = page("how-to/calibrate-a-bench.md")
    idle = ns["idle"]
    measured = ns["rotor"].measured_imep(ns["tue"], ns["analysis_with_pressure"], ns["cal"].pressure_gain_pa)
    assert float(np.mean(idle.imep_pa)) / 1e5 == pytest.approx(1.07, abs=0.005)  # "1.07 bar from the speed"
    assert float(np.mean(measured)) / 1e5 == pytest.approx(1.02, abs=0.005)  # "against 1.02 bar measured"


def test_diagnosis_figures(page):
    ns = page("how-to/diagnose-from-speed.md")
    mis, ident = ns["mis"], ns["ident"]
    fired = np.asarray(mis.imep_pa) > 0
    assert np.array_equal(np.asarray(ident.misfire), ~fired) and (~fired).sum() == 1  # "the one misfire"
    assert ident.misfires() == [(6, 3)]  # "[(6, 3)]"
    assert np.max(np.abs(np.asarray(ident.imep_pa)[fired] / np.asarray(mis.imep_pa)[fired] - 1)) < 1e-8
    m, run = ns["m"], ns["run"]
    assert m.torque.shape[0] == 6 and run is not None


def test_simulation_figures(page):
    import json

    ns = page("how-to/simulate-and-record.md")
    out, _ = ns[OUTPUTS]["rotor simulate 4chn15 --cycles 50 --load 3000 --json"]
    stall = json.loads(out)
    assert stall["stalled"] and stall["stall_cycle"] == 4  # "stall_cycle": 4
    assert stall["stall_angle_deg"] == pytest.approx(530.4, abs=0.05)  # "stall_angle_deg": 530.4


def test_monitor_figures(page):
    ns = page("how-to/monitor-misfires.md")
    assert [(v.cycle, v.cylinder) for v in ns["verdicts"] if v.misfire] == [(7, 2), (15, 4)]  # "[(7, 2), (15, 4)]"


def test_bearing_figures(page):
    ns = page("how-to/bearing-loads-and-balance.md")
    loads, bal = ns["loads"], ns["bal"]
    k = int(np.argmax(loads.pin_q_N[:, 0]))
    assert loads.angle_deg[k] == 370.0 and loads.pin_q_N[k, 0] / 1e3 == pytest.approx(
        96.23, abs=0.005
    )  # "96.23 kN at 370°"
    assert float(np.mean(loads.pin_q_N[:, 0])) / 1e3 == pytest.approx(21.0, abs=0.1)  # "mean 21.0 kN"
    orders = bal.to_json_dict()["orders"]
    assert orders[1]["free_force_N"] == pytest.approx(18568, abs=0.5)  # "free_force_N 18568"
    assert (
        orders[0]["free_force_N"] < 1e-6 and max(o["free_moment_Nm"] for o in orders) < 1e-6
    )  # "order 1 and all moments 0"


def test_sweep_figures(page):
    ns = page("how-to/sweeps-and-bulk.md")
    assert bool(ns["sweep"].converged.all())
    assert float(ns["jax"].grad(ns["delta"])(10.2)) == pytest.approx(-6.378e-4, rel=1e-3)  # "−6.378e-4"
    assert len(ns["results"]) == 3


def test_torsion_figures(page):
    ns = page("how-to/torsional-vibration.md")
    f = np.asarray(ns["rotor"].torsional_modes(ns["chain"]).natural_frequencies_hz)
    assert f == pytest.approx([176.08], abs=0.01)  # "[176.08] Hz"


# --- the command lines the pages show --------------------------------------------------


def command_lines(text: str) -> list[tuple[int, str]]:
    """(line number, command) of every ``rotor …`` line of the ```sh blocks, continuation
    lines joined, comments, a leading ``cat FILE |`` and a trailing ``> FILE`` dropped;
    synopsis lines (with ``[`` or ``…``) are left out."""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        if lines[i].strip() in ("```sh", "```bash", "```console"):
            j, buf = i + 1, ""
            while lines[j].strip() != "```":
                line = lines[j].strip()
                if line.endswith("\\"):
                    buf += line[:-1].strip() + " "
                else:
                    out.append((j + 1, (buf + line).split(" #")[0].strip()))
                    buf = ""
                j += 1
            i = j
        i += 1
    found = []
    for n, line in out:
        if line.startswith("cat ") and "|" in line:
            line = line.split("|", 1)[1].strip()
        line = line.split(" > ")[0]
        if line.startswith("rotor ") and "[" not in line and "…" not in line:
            found.append((n, line))
    return found


@pytest.mark.parametrize("path", PAGES, ids=_id)
def test_command_lines_parse(path):
    """Every ``rotor …`` command a page shows names a real command with options it takes
    (parsed by the ``rotor`` parser itself; not run)."""
    import contextlib
    import io
    import shlex

    from rotor.cli.app import build_parser

    for n, line in command_lines(path.read_text(encoding="utf-8")):
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err):
                build_parser().parse_args(shlex.split(line)[1:])
        except SystemExit:
            pytest.fail(f"{_id(path)}:{n}: {line}\n{err.getvalue().strip()}")


def test_command_lines_are_found():
    text = (
        "```sh\nrotor steady 4chn15 \\\n    --rpm 1250   # a comment\ncat x | rotor monitor - > y\nrotor a [--b]\n```\n"
    )
    assert command_lines(text) == [(3, "rotor steady 4chn15 --rpm 1250"), (4, "rotor monitor -")]
    assert sum(len(command_lines(p.read_text(encoding="utf-8"))) for p in PAGES) >= 30


# --- the README as a landing page ------------------------------------------------------


def test_readme_is_a_landing_page():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 300
    assert "make demo" in text and "make test" in text
    for target in re.findall(r"\]\(((?:docs|notebooks|benchmarks)/[^)#\s]+)", text):
        assert (ROOT / target).exists(), f"README.md links to {target}, which does not exist"
    for image in re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", text):
        assert (ROOT / image).is_file(), f"README.md shows {image}, which does not exist"
    for guide in HOW_TO.glob("*.md"):
        if guide.name != "index.md":
            assert f"](docs/how-to/{guide.name})" in text, f"README.md does not link the how-to guide {guide.name}"


# --- words the documentation does not use ------------------------------------------------

# The words are spelled with character classes so that this file passes its own checks.
PROCESS = re.compile(r"s[e]eds? ?0\d\d|\bi[s]sue #?\d+|\brevie[w] fix", re.IGNORECASE)
"""Words that say how the code came to be (numbered work items, working-copy documents,
rounds of checking), not what it does."""
INTERNAL = re.compile(
    r"\bground\b|\bground floor\b|\bhouse\b|\brooms?\b|\bi[s]sue \d+|\bi[s]sue's\b|\.\./shared|\brevie[w]\b",
    re.IGNORECASE,
)


def _texts():
    yield README
    yield ROOT / "benchmarks" / "README.md"
    yield from sorted(DOCS.rglob("*.md"))
    for path in sorted((ROOT / "rotor").rglob("*")):
        if path.is_file() and path.suffix in {".py", ".toml", ".json", ".md", ".txt", ".csv"}:
            yield path
    yield ROOT / "Makefile"
    yield from sorted((ROOT / "benchmarks").glob("*.py"))
    yield from sorted((ROOT / "tests").rglob("*.py"))


def test_no_process_words():
    """The README, the docs, the package, the tests, the benchmarks and the Makefile say what
    the code does and cite the published sources, not the project's working-copy documents
    or how a piece came to be."""
    found = [
        f"{path.relative_to(ROOT)}:{n}: {line.strip()[:100]}"
        for path in _texts()
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if PROCESS.search(line)
    ]
    assert not found, "process words:\n" + "\n".join(found)


def test_documentation_speaks_to_users():
    """README.md and docs/ say "base layer", "layer" and "subpackage", cite published works,
    and point to no internal notes, paths outside the repository or rounds of checking."""
    found = []
    for path in (README, *sorted(DOCS.rglob("*.md"))):
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if INTERNAL.search(line):
                found.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()[:100]}")
    assert not found, "words for the project, not for users:\n" + "\n".join(found)


def test_docstring_vocabulary_is_translated_for_the_site():
    """The API pages render the package's docstrings through docs/griffe_rotor.py, which says
    "base layer" and "subpackage" where a docstring uses the project's shorthand."""
    import importlib
    import importlib.util

    spec = importlib.util.spec_from_file_location("docs_griffe_rotor", DOCS / "griffe_rotor.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    for mod in ("errors", "results", "units", "cycles", "fileio", "engine", "dynamics", "logs", "design", "torsion"):
        doc = module.markdown(importlib.import_module(f"rotor.{mod}").__doc__ or "")
        assert not INTERNAL.search(doc), (mod, INTERNAL.search(doc))


def test_a_block_marked_no_test_is_left_out():
    """The marker works only on the line right above the fence: a marked block is not run."""
    text = "a\n\n<!-- no-test -->\n```python\nraise SystemExit\n```\n\n```python\nx = 1\n```\n"
    assert [src for _, src in python_blocks(text)] == ["x = 1"]
    assert len(python_blocks(text.replace("<!-- no-test -->\n", ""))) == 2


def test_a_file_block_is_written():
    text = "<!-- file: e.toml -->\n```toml\na = 1\n```\n\n```toml\nb = 2\n```\n"
    assert blocks(text) == [Block(3, "a = 1\n", "file", "e.toml")]


def test_a_shell_block_is_run_command_by_command():
    text = "```sh\nrotor a \\\n    --b 1   # c\n# a comment\n\nls > x\n```\n\n```text\nrotor LOG [--json]\n```\n"
    (block,) = blocks(text)
    assert block.kind == "sh"
    assert shell_commands(block.source, block.line) == [(2, "rotor a --b 1"), (6, "ls > x")]
    assert blocks(text.replace("```sh", "<!-- no-test -->\n```sh")) == []


def test_a_shell_command_runs_and_redirects(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert run_command("rotor presets > presets.txt")[0] == 0
    assert "4chn15" in (tmp_path / "presets.txt").read_text(encoding="utf-8")
    rc, out, _ = run_command("cat presets.txt | wc -l")
    assert rc == 0 and int(out) >= 4
    assert run_command("rotor table no-such-engine")[0] == 2


@pytest.mark.parametrize("path", PAGES, ids=_id)
def test_every_marker_sits_on_a_block(path):
    lines = path.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        if line.strip() == NO_TEST:
            after = next(ln.strip() for ln in lines[i + 1 :] if ln.strip())
            assert after in ("```python", *SHELL_FENCES), f"{_id(path)}:{i + 1}: {NO_TEST} is not right above a block"
        if FILE.match(line.strip()):
            after = next(ln.strip() for ln in lines[i + 1 :] if ln.strip())
            assert after == "```toml", f"{_id(path)}:{i + 1}: a file marker is not right above a toml block"
