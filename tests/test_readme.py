"""README.md's code runs as written, and its text speaks to users.

- Every ```python block of README.md runs, in order, in one namespace (a later block may
  use names from an earlier one), in a temporary working directory, with matplotlib's
  Agg backend. A block right after an HTML comment ``<!-- no-test -->`` is skipped (use it
  only with a reason written next to it). A failure names the README's own line.
- A few figures the README's comments quote are checked against what the blocks computed.
- No text in README.md, the package or benchmarks/README.md cites the project's internal
  internal working-copy documents: users do not have them; the README's "Sources" section names the
  published works.
"""

import ast
import re

import matplotlib.pyplot as plt
import numpy as np
import pytest
from conftest import ROOT

README = ROOT / "README.md"
NO_TEST = "<!-- no-test -->"


def python_blocks(text: str) -> list[tuple[int, str]]:
    """(first line number, source) of every ```python block not marked ``<!-- no-test -->``."""
    lines = text.splitlines()
    blocks, i = [], 0
    while i < len(lines):
        if lines[i].strip() == "```python":
            j = i + 1
            while j < len(lines) and lines[j].strip() != "```":
                j += 1
            assert j < len(lines), f"README.md:{i + 1}: a ```python block that never ends"
            previous = next((ln.strip() for ln in reversed(lines[:i]) if ln.strip()), "")
            if previous != NO_TEST:
                blocks.append((i + 2, "\n".join(lines[i + 1 : j])))
            i = j
        i += 1
    return blocks


def test_blocks_are_found():
    blocks = python_blocks(README.read_text(encoding="utf-8"))
    assert len(blocks) >= 6
    for line, src in blocks:
        ast.parse(src, f"README.md:{line}")


@pytest.fixture(scope="module")
def namespace(tmp_path_factory):
    """Run every block in order in one namespace, in a temporary working directory."""
    import os

    folder = tmp_path_factory.mktemp("readme")
    old = os.getcwd()
    os.chdir(folder)
    ns: dict = {"__name__": "__readme__"}
    try:
        for line, src in python_blocks(README.read_text(encoding="utf-8")):
            # padded so that a traceback names the README's own line
            code = compile("\n" * (line - 1) + src, str(README), "exec")
            try:
                exec(code, ns)
            except Exception as e:
                raise AssertionError(f"README.md: the python block at line {line} fails: {e!r}") from e
            finally:
                plt.close("all")
    finally:
        os.chdir(old)
    return ns


def test_readme_python_blocks_run(namespace):
    assert "engine" in namespace and "design" in namespace


def test_readme_figures(namespace):
    """Figures the README's comments quote for the examples it added (the others are
    pinned by the tests and benchmarks the README names)."""
    ns = namespace
    a, four, ss = ns["a"], ns["four"], ns["ss"]
    assert np.allclose(a.mean_rpm, 3000.0, atol=0.05)  # "3000.0 rpm"
    assert 0.06605 <= np.min(a.delta) and np.max(a.delta) <= 0.06635  # "δ 0.0661…0.0663"
    assert float(np.mean(four.delta)) == pytest.approx(0.0176, abs=0.0005)  # "its δ, 0.0176"
    assert float(ss.delta) == pytest.approx(0.0067, abs=0.00005)  # "the engine's 0.0067"
    assert float(np.mean(four.delta)) / float(ss.delta) == pytest.approx(2.6, abs=0.05)  # "2.6 times"
    assert four.to_json_dict()["firing_revolution_parity"] == 1  # "firing=1"
    mis, ident = ns["mis"], ns["ident"]
    fired = np.asarray(mis.imep_pa) > 0
    assert np.array_equal(np.asarray(ident.misfire), ~fired) and (~fired).sum() == 1  # "the one misfire"
    assert np.max(np.abs(np.asarray(ident.imep_pa)[fired] / np.asarray(mis.imep_pa)[fired] - 1)) < 1e-8
    idle, measured = (
        ns["idle"],
        ns["rotor"].measured_imep(ns["tue"], ns["analysis_with_pressure"], ns["cal"].pressure_gain_pa),
    )
    assert float(np.mean(idle.imep_pa)) / 1e5 == pytest.approx(1.07, abs=0.005)  # "1.07 bar from the speed"
    assert float(np.mean(measured)) / 1e5 == pytest.approx(1.02, abs=0.005)  # "against 1.02 bar measured"
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


SEED = re.compile(r"seeds? 00", re.IGNORECASE)  # file names such as seed004_accuracy.py are not text


def _texts():
    yield README
    yield ROOT / "benchmarks" / "README.md"
    for path in sorted((ROOT / "rotor").rglob("*")):
        if path.is_file() and path.suffix in {".py", ".toml", ".json", ".md", ".txt", ".csv"}:
            yield path


def test_no_internal_seed_references():
    """Users do not have the project's internal working-copy documents: cite the published sources."""
    found = []
    for path in _texts():
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if SEED.search(line):
                found.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()[:100]}")
    assert not found, "internal working-copy references:\n" + "\n".join(found)


def test_a_block_marked_no_test_is_left_out():
    """The marker works only on the line right above the fence: a marked block is not run."""
    text = "a\n\n<!-- no-test -->\n```python\nraise SystemExit\n```\n\n```python\nx = 1\n```\n"
    assert [src for _, src in python_blocks(text)] == ["x = 1"]
    assert len(python_blocks(text.replace("<!-- no-test -->\n", ""))) == 2


def test_every_no_test_marker_in_the_readme_sits_on_a_block():
    lines = README.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        if line.strip() == NO_TEST:
            after = next(ln.strip() for ln in lines[i + 1 :] if ln.strip())
            assert after == "```python", f"README.md:{i + 1}: {NO_TEST} is not right above a python block"
