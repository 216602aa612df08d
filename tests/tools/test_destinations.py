"""No command deletes what it did not write: report folders are new, empty or a
previous report of ours; an existing file or a folder of other files is refused
before any work, with one line, and every user file is kept. Files and folders
get the modes the umask gives."""
import hashlib
import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mi_brdfs.render import exr
from mi_brdfs.tools import destinations


def run(*args, cwd=None, umask=None):
    return subprocess.run([sys.executable, "-m", "mi_brdfs", *args], capture_output=True,
                          text=True, cwd=cwd,
                          preexec_fn=(lambda: os.umask(umask)) if umask is not None else None)


def snapshot(folder: Path) -> dict[str, str]:
    """Every file under folder (hidden ones too) with its content's hash."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture
def renders(tmp_path):
    """A user's folder: two renders and their notes."""
    folder = tmp_path / "renders"
    folder.mkdir()
    rng = np.random.default_rng(0)
    r = rng.uniform(0, 1, size=(8, 8, 3))
    exr.write_exr(str(folder / "ref.exr"), r)
    exr.write_exr(str(folder / "test.exr"), r * 1.1)
    (folder / "notes.txt").write_text("what I tried\n")
    return folder


def one_line_error(out, command):
    assert out.returncode == 1, (out.stdout, out.stderr)
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"mi-brdfs {command}: error: "), out.stderr
    return lines[0]


def test_compare_into_the_folder_of_its_inputs_keeps_everything(renders):
    before = snapshot(renders.parent)
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"), "-o", str(renders))
    assert "holds the input" in one_line_error(out, "compare")
    assert snapshot(renders.parent) == before


def test_compare_into_a_folder_of_other_files_keeps_everything(renders, tmp_path):
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine\n")
    before = snapshot(tmp_path)
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"), "-o", str(other))
    assert "not an mi-brdfs report" in one_line_error(out, "compare")
    assert snapshot(tmp_path) == before


def test_compare_onto_an_existing_file_keeps_it(renders, tmp_path):
    existing = tmp_path / "existing.exr"
    exr.write_exr(str(existing), np.ones((2, 2, 3)))
    before = snapshot(tmp_path)
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"), "-o", str(existing))
    assert "is an existing file" in one_line_error(out, "compare")
    assert snapshot(tmp_path) == before
    assert sorted(os.listdir(tmp_path)) == ["existing.exr", "renders"]     # nothing set aside


def test_validate_into_a_folder_of_other_files_keeps_everything(tmp_path):
    folder = tmp_path / "results"
    folder.mkdir()
    (folder / "thesis.tex").write_text("chapter 1\n")
    (folder / "index.html").write_text("my page\n")
    before = snapshot(tmp_path)
    out = run("validate", "--quick", "-o", str(folder))
    assert "not an mi-brdfs report" in one_line_error(out, "validate")
    assert snapshot(tmp_path) == before


def test_a_previous_report_is_replaced_and_only_its_own_files_go(renders, tmp_path):
    rep = tmp_path / "rep"
    ref, test = str(renders / "ref.exr"), str(renders / "test.exr")
    assert run("compare", ref, test, test, "-o", str(rep)).returncode == 0
    first = set(os.listdir(rep))
    assert "test1_difference.png" in first and destinations.MARKER in first
    listed = json.loads((rep / destinations.MARKER).read_text())["files"]
    assert set(listed) | {destinations.MARKER} == first
    assert run("compare", ref, test, "-o", str(rep)).returncode == 0        # replaced
    second = set(os.listdir(rep))
    assert "test1_difference.png" not in second and "test0_difference.png" in second
    assert sorted(p for p in os.listdir(tmp_path) if p.startswith(".tmp")) == []
    # A file of the user's inside the report: the folder is no longer ours alone.
    (rep / "my_notes.txt").write_text("keep me\n")
    before = snapshot(tmp_path)
    out = run("compare", ref, test, "-o", str(rep))
    assert "my_notes.txt" in one_line_error(out, "compare")
    assert snapshot(tmp_path) == before


def test_an_empty_folder_takes_the_report(renders, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"), "-o", str(empty))
    assert out.returncode == 0, out.stderr
    assert (empty / "index.html").exists()


def test_a_marker_that_lists_other_files_does_not_delete_them(tmp_path):
    """A folder whose marker claims a file the folder does not hold as ours:
    only what the marker lists may go, and a foreign file blocks the write."""
    folder = tmp_path / "rep"
    folder.mkdir()
    (folder / destinations.MARKER).write_text(json.dumps({"command": "compare", "files": ["a.png"]}))
    (folder / "b.txt").write_text("user\n")
    with pytest.raises(destinations.OutputError, match="b.txt"):
        destinations.check_report_dir(str(folder))
    assert (folder / "b.txt").read_text() == "user\n"


@pytest.mark.parametrize("umask, file_mode, dir_mode", [(0o022, 0o644, 0o755),
                                                         (0o027, 0o640, 0o750)])
def test_modes_follow_the_umask(renders, tmp_path, umask, file_mode, dir_mode):
    rep, image = tmp_path / "rep", tmp_path / "x.png"
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"), "-o", str(rep),
              umask=umask)
    assert out.returncode == 0, out.stderr
    assert stat.S_IMODE(rep.stat().st_mode) == dir_mode
    for p in rep.iterdir():
        assert stat.S_IMODE(p.stat().st_mode) == file_mode, p.name
    out = run("render", "lambert", "-D", "res=8", "--spp", "1", "-q", "-o", str(image),
              "-o", str(tmp_path / "x.exr"), umask=umask)
    assert out.returncode == 0, out.stderr
    for p in (image, tmp_path / "x.exr"):
        assert stat.S_IMODE(p.stat().st_mode) == file_mode, p.name


def test_unwritable_targets_are_found_before_any_work(renders, tmp_path):
    """As root, os.access says every folder is writable; /proc takes no new file
    even for root, so only trying to create one finds out."""
    out = run("render", "course", "-o", "/proc/course.exr")
    assert "cannot write in /proc" in one_line_error(out, "render")
    assert out.stdout == ""                      # no render summary: nothing was rendered
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"),
              "-o", "/proc/report")
    assert "cannot write in /proc" in one_line_error(out, "compare")
    with pytest.raises(destinations.OutputError, match="does not exist"):
        destinations.check_output_file(str(tmp_path / "missing" / "x.exr"))
    with pytest.raises(destinations.OutputError, match="is a folder"):
        destinations.check_output_file(str(tmp_path))


def test_an_interrupted_report_leaves_the_target_as_it_was(tmp_path):
    target = tmp_path / "rep"
    with pytest.raises(KeyboardInterrupt):
        with destinations.report_dir(str(target), "compare") as tmp:
            Path(tmp, "index.html").write_text("half")
            raise KeyboardInterrupt
    assert os.listdir(tmp_path) == []


def test_a_report_with_subfolders_is_replaced_and_nothing_else_goes(tmp_path):
    """A report may hold subfolders (the bench's fit sweep): its marker lists
    their files; replacing it removes those files and the emptied subfolders,
    and a user's file added in a subfolder makes the folder foreign."""
    target = tmp_path / "report"
    for round_ in range(2):
        with destinations.report_dir(str(target), "test") as tmp:
            os.makedirs(os.path.join(tmp, "trade", "fits"))
            for name in ("a.txt", "trade/b.txt", f"trade/fits/c{round_}.xml"):
                with open(os.path.join(tmp, name), "w") as f:
                    f.write(name)
    listed = json.loads((target / destinations.MARKER).read_text())["files"]
    assert listed == ["a.txt", "trade/b.txt", "trade/fits/c1.xml"]
    assert not (target / "trade" / "fits" / "c0.xml").exists()       # the old report's own
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp")]
    (target / "trade" / "mine.txt").write_text("the user's")
    with pytest.raises(destinations.OutputError, match="trade/mine.txt"):
        destinations.check_report_dir(str(target))
    assert (target / "trade" / "mine.txt").read_text() == "the user's"
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / destinations.MARKER).write_text(json.dumps({"command": "x", "files": ["../outside.txt"]}))
    assert destinations.previous_report(str(bad)) is None


def test_a_report_inside_a_report_counts_with_its_own_files(tmp_path):
    """The bench's trade/ re-run by its own command: the files its new marker
    lists are a report's, not the user's, so the outer folder still takes a
    run, which removes them with the rest; a user's file there still makes
    the folder foreign, and a marker the outer report did not write in a
    subfolder of its own is not followed."""
    outer = tmp_path / "bench"
    with destinations.report_dir(str(outer), "bench") as tmp:
        with destinations.report_dir(os.path.join(tmp, "trade"), "fit") as inner:
            Path(inner, "old.json").write_text("1")
        Path(tmp, "README.md").write_text("r")
    with destinations.report_dir(str(outer / "trade"), "fit") as inner:      # the sweep again
        Path(inner, "new.json").write_text("2")
    assert not (outer / "trade" / "old.json").exists()
    destinations.check_report_dir(str(outer))                                # no foreign file
    (outer / "trade" / "mine.txt").write_text("the user's")
    with pytest.raises(destinations.OutputError, match="trade/mine.txt"):
        destinations.check_report_dir(str(outer))
    (outer / "trade" / "mine.txt").unlink()
    (outer / "other").mkdir()                                                 # not the outer's
    (outer / "other" / destinations.MARKER).write_text(
        json.dumps({"command": "x", "files": ["x.txt"]}))
    (outer / "other" / "x.txt").write_text("x")
    with pytest.raises(destinations.OutputError, match="other/"):
        destinations.check_report_dir(str(outer))
    (outer / "other" / "x.txt").unlink()
    (outer / "other" / destinations.MARKER).unlink()
    (outer / "other").rmdir()
    with destinations.report_dir(str(outer), "bench") as tmp:               # the bench again
        Path(tmp, "README.md").write_text("r2")
    assert sorted(os.listdir(outer)) == sorted(["README.md", destinations.MARKER])
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp")]


@pytest.mark.parametrize("spelling", ["elink", "elink/", "elink//", "./elink/"])
def test_a_link_is_refused_however_it_is_spelled(renders, tmp_path, spelling):
    """A symbolic link to an empty folder, with or without trailing slashes,
    relative: refused before any work (the report is not computed first)."""
    target = tmp_path / "empty"
    target.mkdir()
    (tmp_path / "elink").symlink_to(target)
    before = snapshot(tmp_path)
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"), "-o", spelling,
              cwd=tmp_path)
    assert "is a symbolic link" in one_line_error(out, "compare")
    assert snapshot(tmp_path) == before and not list(target.iterdir())


@pytest.mark.parametrize("spelling", ["fresh/", "./fresh//", "sub/../fresh/"])
def test_a_new_folder_with_a_trailing_slash_takes_the_report(renders, tmp_path, spelling):
    (tmp_path / "sub").mkdir()
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"), "-o", spelling,
              cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "fresh" / "index.html").is_file()


@pytest.mark.parametrize("spelling, why", [(".", "holds the input"), ("sub/..", "holds the input"),
                                           ("sub/../", "holds the input"),
                                           ("sub/.", "is a folder holding other files")])
def test_a_path_ending_in_dots_is_the_folder_it_names(renders, tmp_path, spelling, why):
    """``.`` and ``sub/..`` are the current folder, which holds the inputs;
    ``sub/.`` is ``sub``, which holds a user's file: each is refused as such."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "plan.txt").write_text("mine")
    before = snapshot(tmp_path)
    out = run("compare", str(renders / "ref.exr"), str(renders / "test.exr"), "-o", spelling,
              cwd=tmp_path)
    assert why in one_line_error(out, "compare")
    assert snapshot(tmp_path) == before
