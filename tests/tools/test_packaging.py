"""Packaging as a user gets it: a wheel built from this checkout, installed into a
fresh virtual environment without the report extras, renders the bundled
``course`` scene from another folder; the plugins never import the report
dependencies; the wheel carries the scenes, py.typed and the licence."""
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
REPORT_MODULES = ("matplotlib", "scipy", "flip_evaluator")


def test_plugins_and_render_do_not_import_the_report_dependencies(tmp_path):
    code = f"""
import sys
import mi_brdfs, mitsuba as mi
from mi_brdfs.tools import cli
bsdf = mi.load_dict({{"type": "cook_torrance"}})
assert cli.main(["render", "lambert", "-D", "res=8", "--spp", "1", "-q",
                 "-o", r"{tmp_path / 'x.exr'}", "-o", r"{tmp_path / 'x.png'}"]) == 0
print(sorted(m for m in {REPORT_MODULES!r} if m in sys.modules))
"""
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip().splitlines()[-1] == "[]"


def source_tree(target: Path) -> Path:
    """A copy of the checkout's files (tracked and new, not ignored): what a
    user's clone holds, without this machine's virtualenv and build leftovers."""
    target.mkdir()
    try:
        names = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-co", "--exclude-standard"],
                               capture_output=True, text=True, check=True).stdout.splitlines()
    except (OSError, subprocess.CalledProcessError):
        shutil.copytree(ROOT, target, dirs_exist_ok=True, ignore=shutil.ignore_patterns(
            ".git", ".venv", "build", "dist", "*.egg-info", "__pycache__"))
        return target
    for name in names:
        if (ROOT / name).is_file():
            (target / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, target / name)
    return target


def run(args, **kwargs):
    out = subprocess.run(args, capture_output=True, text=True, timeout=900, **kwargs)
    assert out.returncode == 0, (args, out.stdout[-2000:], out.stderr[-3000:])
    return out


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    work = tmp_path_factory.mktemp("wheel")
    src = source_tree(work / "src")
    run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(work / "dist"),
         str(src)])
    return next((work / "dist").glob("mi_brdfs-*.whl"))


def test_wheel_contents(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    assert "mi_brdfs/py.typed" in names
    assert "mi_brdfs/scenes/course.xml" in names and "mi_brdfs/scenes/__init__.py" in names
    assert any(n.endswith("/LICENSE") for n in names)
    assert not [n for n in names if n.startswith(("tests/", "scenes/", "docs/"))]
    metadata = zipfile.ZipFile(wheel).read(
        next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
    requires = [line for line in metadata.splitlines() if line.startswith("Requires-Dist:")]
    core = [r for r in requires if "extra ==" not in r]
    assert not [r for r in core if any(m.split("_")[0] in r for m in ("matplotlib", "scipy",
                                                                      "flip-evaluator"))]
    assert any("extra == \"reports\"" in r and "scipy" in r for r in requires)


def test_building_leaves_nothing_git_would_show(wheel):
    """What pip leaves in the source folder while building (build/, the
    egg-info) is ignored by the checkout's .gitignore: a user's git status
    stays clean after pip install ."""
    src = wheel.parent.parent / "src"
    tracked = {name.split("/")[0] for name in subprocess.run(
        ["git", "-C", str(ROOT), "ls-files"], capture_output=True, text=True).stdout.split()}
    left = sorted(set(os.listdir(src)) - tracked)
    assert "build" in left                    # (what this test is about is there)
    run(["git", "-C", str(src), "init", "-q"])
    for name in left:
        ignored = subprocess.run(["git", "-C", str(src), "check-ignore", "-q", name])
        assert ignored.returncode == 0, f"{name} would show in git status"


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory):
    """A fresh virtual environment with the wheel (no report extras): its
    python, its mi-brdfs, and an environment without this checkout's paths."""
    venv = tmp_path_factory.mktemp("installed") / "venv"
    run([sys.executable, "-m", "venv", str(venv)])
    python, tool = venv / "bin" / "python", venv / "bin" / "mi-brdfs"
    run([str(python), "-m", "pip", "install", "-q", str(wheel)])
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "DRJIT_LIBLLVM_PATH")}
    return venv, python, tool, env


def test_wheel_in_a_fresh_venv_renders_course_from_another_folder(installed, tmp_path):
    venv, python, tool, env = installed
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = run([str(tool), "render", "course", "-D", "res=24", "--spp", "2", "-q",
               "-o", "course.exr", "-o", "course.png"], cwd=elsewhere, env=env)
    assert "course: 24x24, 2 spp" in out.stdout
    assert sorted(os.listdir(elsewhere)) == ["course.exr", "course.png"]
    listed = run([str(tool), "scenes"], cwd=elsewhere, env=env).stdout
    assert "course" in listed and str(venv) in listed        # the installed copy, not the checkout
    where = run([str(python), "-c", "import mi_brdfs, importlib.util as u; print(mi_brdfs.__file__);"
                 f"print([m for m in {REPORT_MODULES!r} if u.find_spec(m)])"],
                cwd=elsewhere, env=env).stdout.splitlines()
    assert where[0].startswith(str(venv)) and where[1] == "[]"   # plugins without the reports
    compare = subprocess.run([str(tool), "compare", "course.exr", "course.exr", "-o", "rep"],
                             capture_output=True, text=True, cwd=elsewhere, env=env, timeout=300)
    assert compare.returncode == 1
    lines = compare.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mi-brdfs compare: error: ")
    assert lines[0].endswith("is not installed; compare needs the report dependencies: "
                             "pip install 'mi_brdfs[reports]'")
    assert sorted(os.listdir(elsewhere)) == ["course.exr", "course.png"]     # nothing started


def readme_python_example() -> str:
    """The first Python block of the README's "From Python" section, verbatim."""
    text = (ROOT / "README.md").read_text()
    section = text[text.index("\n## From Python\n"):]
    start = section.index("```python\n") + len("```python\n")
    return section[start:section.index("\n```", start) + 1]


def test_readme_python_example_runs_as_written_from_another_folder(installed, tmp_path):
    """Pasted into a file in an empty folder and run with the installed package:
    it loads a bundled scene, renders it and writes the picture it names."""
    import mitsuba as mi

    _, python, _, env = installed
    code = readme_python_example()
    assert "mi_brdfs.scenes.path(" in code and "mi.render(" in code
    (tmp_path / "example.py").write_text(code)
    run([str(python), "example.py"], cwd=tmp_path, env=env)
    written = sorted(set(os.listdir(tmp_path)) - {"example.py"})
    assert written == ["phong.png"]
    image = np.array(mi.Bitmap(str(tmp_path / "phong.png")))
    assert image.shape == (128, 128, 3) and image.max() > 100 and image.mean() > 5
