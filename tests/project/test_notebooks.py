"""The notebooks run clean in a Jupyter kernel, in their quick form, and render their plots;
the committed copies hold their (full-form) outputs.

``make notebooks`` re-executes them in full and saves the outputs."""

import json

import pytest
from conftest import ROOT

NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
IDS = [p.name for p in NOTEBOOKS]
# the kernel uses the test session's compilation cache (tests/conftest.py: the kernel inherits
# $ROTOR_COMPILATION_CACHE), as the `rotor` command does: what the notebooks and the tests
# compile in common is compiled once; the notebooks themselves stay as a user runs them
KERNEL_STARTUP = "--IPKernelApp.exec_lines=import rotor; rotor.enable_compilation_cache()"


def _outputs(nb):
    return [o for c in nb["cells"] if c["cell_type"] == "code" for o in c.get("outputs", [])]


def _images(nb):
    return sum(1 for o in _outputs(nb) if "image/png" in o.get("data", {}))


def _errors(nb):
    return [f"{o.get('ename')}: {o.get('evalue')}" for o in _outputs(nb) if o.get("output_type") == "error"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_committed_with_outputs(path):
    nb = json.loads(path.read_text())
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert code and all(c.get("execution_count") for c in code), "every code cell executed (run `make notebooks`)"
    assert not _errors(nb)
    assert _images(nb) >= 1, "the saved notebook shows its figures"
    assert sum(1 for c in nb["cells"] if c["cell_type"] == "markdown") >= 3, "a story: prose between the cells"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_runs_in_quick_form(path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    from nbclient import NotebookClient

    monkeypatch.setenv("ROTOR_NOTEBOOK_QUICK", "1")
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    nb = nbformat.read(path, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            cell.outputs = []
    client = NotebookClient(
        nb,
        timeout=600,
        kernel_name="python3",
        allow_errors=False,
        resources={"metadata": {"path": str(path.parent)}},
        extra_arguments=[KERNEL_STARTUP],
    )
    client.execute()  # raises CellExecutionError with the cell and the traceback
    assert not _errors(nb)
    assert _images(nb) >= 1, "the figures are rendered"
