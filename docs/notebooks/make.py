"""Regenerate the notebook pictures of the README (docs/notebooks/NAME.png).

    python docs/notebooks/make.py [NAME ...]     # full sizes; MI_BRDFS_QUICK=1 for small

Each notebook is executed top to bottom (as tests/test_notebooks.py does) and
one of its figures, chosen below, is written beside this script.
"""
import base64
import os
import sys
from pathlib import Path

import nbformat
from nbclient import NotebookClient

HERE = Path(__file__).resolve().parent
NOTEBOOKS = HERE.parent.parent / "notebooks"
FIGURE = {                      # which figure (index among the notebook's PNG outputs)
    "01_models": 0,             # every model in both modes
    "02_lobes": "energy",       # the compensated albedo curves (the cell that draws them)
    "03_validation": 0,
    "04_speed_vs_accuracy": 0,
    "05_fit_with_gradients": -1,   # the texture recovery
    "06_which_model": 0,        # the Pareto fronts
}


def pngs(cells):
    return [o["data"]["image/png"] for c in cells for o in c.get("outputs", [])
            if "image/png" in o.get("data", {})]


def main(names):
    for name in names or FIGURE:
        nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
        NotebookClient(nb, timeout=3600, kernel_name="python3",
                       resources={"metadata": {"path": str(NOTEBOOKS)}}).execute()
        which = FIGURE[name]
        if isinstance(which, str):      # the first figure of the cell that mentions it
            cells = [c for c in nb.cells if c.cell_type == "code" and which in c.source]
            image = pngs(cells)[0]
        else:
            image = pngs(nb.cells)[which]
        target = HERE / f"{name}.png"
        tmp = target.with_suffix(".png.tmp")
        tmp.write_bytes(base64.b64decode(image))
        os.replace(tmp, target)
        print(f"{target.relative_to(HERE.parent.parent)}")


if __name__ == "__main__":
    main(sys.argv[1:])
