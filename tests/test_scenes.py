"""The scenes load after `import mi_brdfs` and render through the mi-brdfs command."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mitsuba as mi

from mi_brdfs import cli

SCENES = Path(__file__).resolve().parent.parent / "scenes"


@pytest.mark.parametrize("name", ["lambert", "cook_torrance"])
@pytest.mark.parametrize("mode", ["hdr", "scanline"])
def test_scene_loads_and_renders(name, mode):
    scene = mi.load_file(str(SCENES / f"{name}.xml"), mode=mode, res="32", spp="4")
    image = np.array(mi.render(scene))
    assert image.shape == (32, 32, 3)
    assert np.isfinite(image).all() and image.max() > 0.05


def test_render_command_writes_exr_and_png(tmp_path):
    exr, png = tmp_path / "a.exr", tmp_path / "a.png"
    assert cli.main(["render", str(SCENES / "lambert.xml"), "-D", "res=24", "--spp", "2",
                     "-o", str(exr), "--png", str(png)]) == 0
    assert sorted(os.listdir(tmp_path)) == ["a.exr", "a.png"]     # no temporary left over
    back = np.array(mi.Bitmap(str(exr)))
    assert back.shape == (24, 24, 3) and back.max() > 0


def test_render_command_error_is_one_line(tmp_path):
    run = subprocess.run([sys.executable, "-m", "mi_brdfs", "render", str(SCENES / "lambert.xml"),
                          "-D", "mode=bright", "-o", str(tmp_path / "x.exr")],
                         capture_output=True, text=True)
    assert run.returncode == 1
    assert run.stderr.strip().count("\n") == 0
    assert "lambert: parameter 'mode' = 'bright' is invalid" in run.stderr
    assert not os.listdir(tmp_path)
