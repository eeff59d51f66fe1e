"""The notebooks run clean in their quick form and render their plots; the committed copies
hold their (full-form) outputs.

Each runs its cells in IPython's shell in the test's own process, as a Jupyter kernel runs
them (the same IPython, ``%matplotlib inline`` and rich display), sharing what the tests
before it compiled and traced; one runs in a real Jupyter kernel, the way a reader opens
them. ``make notebooks`` re-executes them all in kernels, in full, and saves the outputs."""

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


KERNEL_NOTEBOOK = "misfire_monitor.ipynb"
"""The notebook that also runs in a Jupyter kernel (the quickest)."""


def _quick_form(path):
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(path, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            cell.outputs = []
    return nb


def _run_in_this_process(nb, name):
    """Run ``nb``'s code cells (of notebook ``name``) in IPython's shell here, with matplotlib's
    inline backend (as in a kernel), each cell's rich outputs put into the cell; the first
    cell that raises fails the test with its traceback. matplotlib's settings and backend
    are restored after."""
    import matplotlib
    import matplotlib.pyplot as plt
    import nbformat
    from IPython.core.interactiveshell import InteractiveShell
    from IPython.utils.capture import capture_output

    shell = InteractiveShell.instance()
    shell.enable_gui = lambda gui=None: None  # no GUI event loop to start: figures are inline
    shell.colors = "nocolor"  # a traceback in the failure message without terminal escapes
    shell.reset(new_session=True)
    with matplotlib.rc_context():
        try:
            shell.enable_matplotlib("inline")
            for i, cell in enumerate(c for c in nb.cells if c.cell_type == "code"):
                with capture_output() as cap:
                    result = shell.run_cell(cell.source, store_history=False, cell_id=str(i))
                cell.outputs = [nbformat.v4.new_output("display_data", data=o.data) for o in cap.outputs]
                if not result.success:
                    pytest.fail(f"code cell {i + 1} of {name}: {cap.stdout[-3000:]}{cap.stderr[-2000:]}")
        finally:
            plt.close("all")
            plt.switch_backend("Agg")
    return nb


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_runs_in_quick_form(path, monkeypatch):
    monkeypatch.setenv("ROTOR_NOTEBOOK_QUICK", "1")
    monkeypatch.chdir(path.parent)
    nb = _run_in_this_process(_quick_form(path), path.name)
    assert not _errors(nb)
    assert _images(nb) >= 1, "the figures are rendered"


def test_a_notebook_runs_in_a_jupyter_kernel(monkeypatch):
    nb = _quick_form(ROOT / "notebooks" / KERNEL_NOTEBOOK)
    from nbclient import NotebookClient

    monkeypatch.setenv("ROTOR_NOTEBOOK_QUICK", "1")
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    client = NotebookClient(
        nb,
        timeout=600,
        kernel_name="python3",
        allow_errors=False,
        resources={"metadata": {"path": str(ROOT / "notebooks")}},
        extra_arguments=[KERNEL_STARTUP],
    )
    client.execute()  # raises CellExecutionError with the cell and the traceback
    assert not _errors(nb)
    assert _images(nb) >= 1, "the figures are rendered"
