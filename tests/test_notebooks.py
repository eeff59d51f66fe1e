"""The notebooks run: their code cells are executed in order (no Jupyter needed)."""

import json

import matplotlib
import pytest

from conftest import ROOT

NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path):
    import matplotlib.pyplot as plt

    matplotlib.use("Agg")
    nb = json.loads(path.read_text())
    scope = {}
    for cell in nb["cells"]:
        if cell["cell_type"] == "code":
            exec(compile("".join(cell["source"]), f"{path.name}", "exec"), scope)
    plt.close("all")
