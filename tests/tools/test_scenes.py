"""Every bundled scene renders through mi-brdfs, in both modes, by path and by name;
errors are one line."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest


from mi_brdfs.render import exr
from mi_brdfs.tools import cli

SCENES = Path(__file__).resolve().parents[2] / "scenes"
ALL = sorted(p.stem for p in SCENES.glob("*.xml"))


@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("mode", ["hdr", "scanline"])
def test_every_scene_renders_in_both_modes(tmp_path, name, mode):
    out, png = tmp_path / "x.exr", tmp_path / "x.png"
    code = cli.main(["render", str(SCENES / f"{name}.xml"), "-D", f"mode={mode}", "-D", "res=24",
                     "--spp", "2", "--passes", "2", "-q", "-o", str(out), "-o", str(png)])
    assert code == 0
    assert sorted(os.listdir(tmp_path)) == ["x.exr", "x.png"]     # no temporary left over
    image = exr.read_exr(str(out))
    assert image.shape == (24, 24, 3) and np.isfinite(image).all() and image.max() > 0.01
    if mode == "scanline":
        assert image.max() <= 1.0


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "mi_brdfs", *args], capture_output=True, text=True)


def bad_scene(tmp_path, body):
    path = tmp_path / "bad.xml"
    path.write_text(f'<scene version="3.0.0">{body}</scene>')
    return str(path)


ERRORS = {
    "missing scene": (lambda t: ["render", str(t / "nope.xml")], "scene not found"),
    "xml error": (lambda t: ["render", bad_scene(t, "<bsdf type='lambert'>")], "Parsing of XML"),
    "unknown plugin": (lambda t: ["render", bad_scene(t, "<bsdf type='phongy'/>")],
                       'Plugin "phongy" not found'),
    "unknown parameter": (lambda t: ["render", bad_scene(t, "<bsdf type='lambert'><float name='zz' value='1'/></bsdf>")],
                          'unreferenced property in bsdf plugin of type "lambert": - float "zz"'),
    "bad value": (lambda t: ["render", str(SCENES / "lambert.xml"), "-D", "mode=scanline",
                             "-D", "res=bad"], "-D res=bad is invalid; valid: an integer >= 1"),
    "bad scene value": (lambda t: ["render", bad_scene(t, "<integrator type='path'>"
                                   "<integer name='max_depth' value='x'/></integrator>")],
                        'could not parse integer value "x"'),
    "bad parameter value": (lambda t: ["render", bad_scene(t, "<bsdf type='cook_torrance'><float name='k' value='2'/></bsdf>")],
                            "cook_torrance: parameter 'k' = 2.0 is invalid; valid: [0, 1]"),
    "unwritable output": (lambda t: ["render", str(SCENES / "lambert.xml"), "-o", str(t / "no" / "x.exr")],
                          "/no does not exist"),
    "bad define": (lambda t: ["render", str(SCENES / "lambert.xml"), "-D", "mode"], "-D expects key=value"),
    "bad tonemap": (lambda t: ["render", str(SCENES / "lambert.xml"), "--png", str(t / "a.png"),
                               "--tonemap", "drago"], "argument --tonemap: invalid choice: 'drago'"),
    "scene is a folder": (lambda t: ["render", str(t)], "is a folder"),
    "unknown scene name": (lambda t: ["render", "nosuchscene"], "blinn, cook_torrance, course"),
}


@pytest.mark.parametrize("case", ERRORS)
def test_errors_are_one_line_and_exit_non_zero(tmp_path, case):
    args, expected = ERRORS[case]
    work = tmp_path / "work"
    work.mkdir()
    os.chdir(work)
    run = run_cli(*args(tmp_path))
    assert run.returncode == 1, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mi-brdfs render: error: "), run.stderr
    assert expected in lines[0]
    assert "Traceback" not in run.stderr
    assert not os.listdir(work)          # nothing written


def test_traceback_flag_shows_the_traceback(tmp_path):
    run = run_cli("render", str(tmp_path / "nope.xml"), "--traceback")
    assert run.returncode != 0 and "Traceback" in run.stderr and "CLIError" in run.stderr


def test_bundled_scene_by_name_from_another_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = cli.main(["render", "lambert", "-D", "res=16", "--spp", "2", "-q"])
    assert code == 0
    assert sorted(os.listdir(tmp_path)) == ["lambert.exr"]     # here, not in the package
    assert not (SCENES / "lambert.exr").exists()


def test_scenes_lists_every_bundled_scene(capsys):
    assert cli.main(["scenes"]) == 0
    listed = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert listed == ALL and "course" in listed


def test_scenes_path_from_python():
    import mi_brdfs
    found = mi_brdfs.scenes.path("course")
    assert os.path.isabs(found) and found == mi_brdfs.scenes.path("course.xml")
    assert Path(found).read_text() == (SCENES / "course.xml").read_text()
    with pytest.raises(ValueError, match="no bundled scene 'nope'; bundled scenes: .*blinn, "):
        mi_brdfs.scenes.path("nope")
