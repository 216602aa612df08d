"""mi-brdfs render: outputs by extension (EXR with every film channel and its
metadata, PNG, JPEG), Mitsuba's flags, every number checked (one line, exit 1,
never a signal), the default output beside the scene, progress in a pipe."""
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from mi_brdfs.render import imagefile
from mi_brdfs.tools import cli, progress

SCENES = Path(__file__).resolve().parents[2] / "scenes"

AOV_SCENE = """<scene version="3.0.0">
    <default name="spp" value="4"/>
    <integrator type="aov">
        <string name="aovs" value="dd.y:depth,nn:sh_normal"/>
        <integrator type="path" name="image"/>
    </integrator>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film>
    </sensor>
    <shape type="sphere"><bsdf type="lambert"/></shape>
    <emitter type="constant"/>
</scene>
"""


def run(*args, cwd=None, timeout=None):
    return subprocess.run([sys.executable, "-m", "mi_brdfs", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=timeout)


def test_outputs_by_extension(tmp_path):
    scene = tmp_path / "aov.xml"
    scene.write_text(AOV_SCENE)
    exr_path, png, jpg = tmp_path / "x.exr", tmp_path / "x.png", tmp_path / "x.jpg"
    code = cli.main(["render", str(scene), "-q", "--seed", "3", "--passes", "2",
                     "-o", str(exr_path), "-o", str(png), "-o", str(jpg)])
    assert code == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert jpg.read_bytes()[:2] == b"\xff\xd8"
    assert exr_path.read_bytes()[:4] == b"\x76\x2f\x31\x01"
    with OpenEXR.File(str(exr_path)) as f:
        header, channels = dict(f.header()), f.channels()
        names = set(channels)
        depth = np.asarray(channels["dd.y.T"].pixels)
        normal_z = np.asarray(channels["nn.Z"].pixels)
    assert names == {"RGB", "dd.y.T", "nn.X", "nn.Y", "nn.Z"}
    # The unit sphere seen from 4 away: depth 3 at its front, up to sqrt(15) at the rim.
    centre = depth[5:7, 7:9]
    assert 2.95 < centre.min() and centre.max() < 3.2 and depth.max() < 15 ** 0.5 + 0.01
    assert normal_z.max() > 0.95
    assert header["scene"] == str(scene) and header["spp"] == "4" and header["seed"] == "3"
    assert header["variant"] == "llvm_ad_rgb" and header["passes"] == "2"
    assert header["mi_brdfs"] == "0.1.0" and header["mitsuba"].startswith("3.")


@pytest.mark.parametrize("spp, passes, ran", [(16, 32, "1," * 15 + "1"), (10, 4, "3,3,2,2"),
                                             (4, 1, "4")])
def test_metadata_records_the_passes_that_ran(tmp_path, spp, passes, ran):
    """More passes than samples: one sample per pass, as many passes as samples."""
    out = tmp_path / "x.exr"
    assert cli.main(["render", "lambert", "-D", "res=8", "--spp", str(spp), "--passes",
                     str(passes), "-q", "-o", str(out)]) == 0
    with OpenEXR.File(str(out)) as f:
        header = dict(f.header())
    assert header["pass_spp"] == ran
    assert header["passes"] == str(len(ran.split(","))) and header["spp"] == str(spp)


def test_channel_names_of_mitsubas_aov_integrator():
    film = ["R", "G", "B", "img.R", "img.G", "img.B", "img.A", "dd.y.T", "nn.X", "nn.Y", "nn.Z"]
    assert imagefile.channel_names(film, 7) == ["R", "G", "B", "dd.y.T", "nn.X", "nn.Y", "nn.Z"]
    assert imagefile.channel_names(["R", "G", "B", "dd.y.T"], 1) == ["dd.y.T"]   # no nested image
    mono = ["Y", "img.R", "img.G", "img.B", "img.A", "dd.y.T", "nn.X", "nn.Y", "nn.Z"]
    assert imagefile.channel_names(mono, 5) == ["Y", "dd.y.T", "nn.X", "nn.Y", "nn.Z"]
    assert imagefile.channel_names(["R", "G", "B"], 3) == ["R", "G", "B"]
    assert imagefile.channel_names(["R", "G", "B"], 5) == ["C0", "C1", "C2", "C3", "C4"]


def test_png_of_a_render_without_colour_is_refused():
    with pytest.raises(ValueError, match="no R, G, B channels"):
        imagefile.rgb_of(np.zeros((2, 2, 1)), ["dd.y.T"])


def test_default_output_is_beside_the_scene(tmp_path):
    (tmp_path / "scenes").mkdir()
    (tmp_path / "elsewhere").mkdir()
    scene = tmp_path / "scenes" / "mine.xml"
    scene.write_text((SCENES / "lambert.xml").read_text())
    out = run("render", str(scene), "-D", "res=8", "--spp", "1", "-q", cwd=tmp_path / "elsewhere")
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "scenes" / "mine.exr").exists()
    assert os.listdir(tmp_path / "elsewhere") == []


BAD_NUMBERS = {
    "--spp -3": (["--spp", "-3"], "argument --spp: invalid value -3; valid: an integer from 1"),
    "--spp 0": (["--spp", "0"], "argument --spp: invalid value 0"),
    "--spp x": (["--spp", "x"], "argument --spp: invalid value 'x'"),
    "--passes 0": (["--passes", "0"], "argument --passes: invalid value 0"),
    "--seed -1": (["--seed", "-1"], "argument --seed: invalid value -1"),
    "--seed too big": (["--seed", "4294967295"], "--seed 4294967295 is invalid with 8 passes"),
    "--exposure nan": (["--exposure", "nan"], "argument --exposure: invalid value nan"),
    "--exposure 1e9": (["--exposure", "1e9"], "valid: a number from -100 to 100"),
    "-D res=0": (["-D", "res=0"], "-D res=0 is invalid; valid: an integer >= 1"),
    "-D res=-3": (["-D", "res=-3"], "-D res=-3 is invalid"),
    "-D spp=abc": (["-D", "spp=abc"], "-D spp=abc is invalid"),
    "-t 0": (["-t", "0"], "argument -t/--threads: invalid value 0"),
    "-m nope": (["-m", "nope"], "-m nope is not a Mitsuba variant here; valid: scalar_rgb"),
    "-o x.tiff": (["-o", "x.tiff"], "-o x.tiff: unknown extension '.tiff'"),
    "-D mode=foo": (["-D", "mode=foo"], "-D mode=foo is invalid for the bundled scene "
                                        "lambert; valid: scanline, hdr"),
}


@pytest.mark.parametrize("case", BAD_NUMBERS)
def test_bad_numbers_are_one_line(tmp_path, monkeypatch, capsys, case):
    args, message = BAD_NUMBERS[case]
    monkeypatch.chdir(tmp_path)
    try:
        code = cli.main(["render", "lambert", "-D", "res=8", *args])
    except SystemExit as exit:          # argparse's own checks
        code = exit.code
    assert code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mi-brdfs render: error: "), err
    assert message in err[0]
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("how", ["define", "scene"])
def test_zero_spp_is_an_error_not_a_signal(tmp_path, how):
    """A sample count of 0 used to kill the process with SIGFPE (exit 136)."""
    if how == "define":
        out = run("render", str(SCENES / "lambert.xml"), "-D", "spp=0", "-o", str(tmp_path / "x.exr"))
        message = "-D spp=0 is invalid; valid: an integer >= 1"
    else:
        scene = tmp_path / "zero.xml"
        scene.write_text((SCENES / "lambert.xml").read_text().replace('value="$spp"', 'value="0"'))
        out = run("render", str(scene), "-o", str(tmp_path / "x.exr"))
        message = "the scene's sample count is 0 (from its sampler); valid: an integer >= 1"
    assert out.returncode == 1, (out.returncode, out.stderr)
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], out.stderr
    assert not (tmp_path / "x.exr").exists()


def test_a_scene_mitsuba_refuses_reads_without_its_source_prefix(tmp_path, monkeypatch, capsys):
    """Mitsuba's parser starts its messages with "[parser.cpp:NNN] ": the
    command's one line says what is wrong, not where in Mitsuba."""
    scene = tmp_path / "unknown.xml"
    scene.write_text((SCENES / "lambert.xml").read_text().replace('type="lambert"',
                                                                   'type="no_such_bsdf"', 1))
    monkeypatch.chdir(tmp_path)
    assert cli.main(["render", str(scene), "-D", "res=8"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no_such_bsdf" in err[0], err
    assert not re.search(r"\[\w+\.(cpp|h|py):\d+\]", err[0]), err[0]


def test_mitsuba_flags(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    out = run("--version")
    assert out.returncode == 0 and out.stdout.startswith("mi-brdfs 0.1.0 (Mitsuba 3.9")
    # -t 1 (one Dr.Jit thread) and an EXR output: mi.Bitmap's EXR writer would deadlock.
    out = run("render", "lambert", "-D", "res=8", "--spp", "1", "-q", "-o", "v.exr", "-v",
              "-t", "1", cwd=tmp_path, timeout=300)
    logs = out.stdout + out.stderr                 # Mitsuba's logger writes to stdout
    assert out.returncode == 0 and "INFO" in logs and "DEBUG" not in logs
    assert "1 spp in 1 passes, seed 0, variant llvm_ad_rgb, 1 threads" in out.stderr
    quiet = run("render", "lambert", "-D", "res=8", "--spp", "1", "-q", "-o", "v.exr",
                cwd=tmp_path)
    assert "INFO" not in quiet.stdout + quiet.stderr
    out = run("render", "lambert", "-D", "res=8", "--spp", "1", "-q", "-o", "v.exr", "-vv",
              cwd=tmp_path)
    assert out.returncode == 0 and "DEBUG" in out.stdout + out.stderr
    out = run("render", "lambert", "-D", "res=8", "--spp", "1", "-q", "-o", "s.png",
              "-m", "scalar_rgb", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "s.png").read_bytes()[:4] == b"\x89PNG"


def test_progress_in_a_pipe_is_plain_lines(tmp_path):
    out = run("render", "lambert", "-D", "res=8", "--spp", "4", "--passes", "4",
              "-o", str(tmp_path / "x.exr"))
    assert out.returncode == 0, out.stderr
    assert "\r" not in out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 5 and lines[-1].startswith("mi-brdfs render: 4/4 spp")
    assert lines[0] == ("mi-brdfs render: 0/4 spp, first pass (it also traces and compiles "
                        "the kernels)")              # progress shows from the start
    assert "ETA ?" in lines[1]                  # no estimate from the compiling pass alone
    quiet = run("render", "lambert", "-D", "res=8", "--spp", "4", "-q", "-o", str(tmp_path / "y.exr"))
    assert quiet.returncode == 0 and quiet.stderr == ""


def test_eta_leaves_out_the_first_pass():
    # First pass: 10 s of compilation + 1 s; then 1 s per pass of 8 spp.
    history = [(8, 11.0), (16, 12.0), (24, 13.0)]
    assert progress.eta(history[:1], 64) is None
    assert progress.eta(history[:2], 64) == pytest.approx(6.0)      # 48 spp at 8 spp/s
    assert progress.eta(history, 64) == pytest.approx(5.0)


class FakeTerminal:
    def __init__(self, tty):
        self.tty, self.text = tty, ""

    def isatty(self):
        return self.tty

    def write(self, s):
        self.text += s

    def flush(self):
        pass


@pytest.mark.parametrize("tty", [True, False])
def test_progress_bar_on_a_terminal_lines_elsewhere(tty):
    stream = FakeTerminal(tty)
    show = progress.Progress("mi-brdfs render", stream=stream)
    for done, elapsed in ((2, 5.0), (4, 5.5), (6, 6.0), (8, 6.5)):
        show(done, 8, elapsed)
    show.close()
    if tty:
        assert "\r" in stream.text and "8/8 spp" in stream.text and "ETA" in stream.text
    else:
        assert "\r" not in stream.text and len(stream.text.splitlines()) == 4
        assert stream.text.splitlines()[1].endswith("ETA 1.0 s")     # 4 spp left at 4 spp/s


def test_help_says_what_the_command_is_whole():
    """The description is a whole sentence (not a docstring's first line cut
    off), and the command works with docstrings stripped (python -OO)."""
    out = subprocess.run([sys.executable, "-OO", "-m", "mi_brdfs", "--help"], capture_output=True,
                         text=True)
    assert out.returncode == 0, out.stderr
    text = " ".join(out.stdout.split())
    assert cli.DESCRIPTION in text
    assert text.count(cli.DESCRIPTION.split(": ")[0]) == 1
