"""Every notebook runs top to bottom (small sizes: MI_BRDFS_QUICK=1), and each
committed .ipynb is its paired py:percent source, without outputs."""
from pathlib import Path

import jupytext
import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"
ALL = sorted(p.stem for p in NOTEBOOKS.glob("*.py"))


def test_there_are_six_notebooks():
    assert ALL == ["01_models", "02_lobes", "03_validation", "04_speed_vs_accuracy",
                   "05_fit_with_gradients", "06_which_model"]


@pytest.mark.parametrize("name", ALL)
def test_ipynb_matches_its_py_source_and_has_no_outputs(name):
    paired = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    source = jupytext.read(NOTEBOOKS / f"{name}.py")
    assert [c.source for c in paired.cells] == [c.source for c in source.cells], \
        f"run: jupytext --to ipynb notebooks/{name}.py"
    assert all(not c.get("outputs") for c in paired.cells)


@pytest.mark.parametrize("name", ALL)
def test_notebook_runs(name, monkeypatch):
    monkeypatch.setenv("MI_BRDFS_QUICK", "1")
    nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    NotebookClient(nb, timeout=900, kernel_name="python3",
                   resources={"metadata": {"path": str(NOTEBOOKS)}}).execute()
    errors = [o for c in nb.cells for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
