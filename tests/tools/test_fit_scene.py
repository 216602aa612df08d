"""mi-brdfs fit --scene: the scene's materials are found through references
and wrappers, a course material stays itself with no error, a glass is kept
and named, the simplified XML loads and renders from the report folder (its
mesh found), Mitsuba's Cornell box written as XML renders as its dictionary,
and bad input gets one line. Tiny renders and one model keep it fast."""
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

import mitsuba as mi

from mi_brdfs.tools import cli
from mi_brdfs.tools.fit import scenefit

ASSETS = Path(__file__).resolve().parents[1] / "scenes" / "assets"

SCENE = """<scene version="3.0.0">
    <default name="res" value="24"/>
    <integrator type="path"><integer name="max_depth" value="3"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 1, 6" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="$res"/><integer name="height" value="$res"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <emitter type="point"><point name="position" x="2" y="4" z="4"/><rgb name="intensity" value="30"/></emitter>
    <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
    <bsdf type="phong" id="course">
        <string name="mode" value="hdr"/>
        <rgb name="diffuse_reflectance" value="0.5, 0.2, 0.1"/>
        <float name="specular_reflectance" value="0.4"/>
        <float name="exponent" value="30"/>
    </bsdf>
    <shape type="obj">
        <string name="filename" value="assets/sphere.obj"/>
        <transform name="to_world"><translate x="-1.1"/></transform>
        <bsdf type="twosided"><ref id="course"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="1.1" y="0" z="0"/>
        <bsdf type="dielectric"/>
    </shape>
</scene>
"""


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """One tiny run: a course Phong material (through a twosided wrapper and a
    reference, on a mesh found by a relative path) and a glass."""
    folder = tmp_path_factory.mktemp("scene")
    (folder / "assets").mkdir()
    shutil.copy(ASSETS / "sphere.obj", folder / "assets" / "sphere.obj")
    (folder / "scene.xml").write_text(SCENE)
    out = folder / "out"
    result = scenefit.fit_scene(str(folder / "scene.xml"), str(out), model_names=["phong"],
                                res=24, spp=4, rounds=1)
    return folder, out, result


def test_a_course_material_keeps_itself_with_no_error(report):
    _, out, result = report
    row = next(r for r in result["materials"] if r["plugin"] == "phong")
    assert row["wrappers"] == ["twosided"] and row["label"] == "course: phong"
    assert row["pixels"] > 0.05                       # the mesh is seen: its pixels were found
    stand_in = row["stand_in"]
    assert stand_in["model"] == "phong" and stand_in["looks_same"]
    assert stand_in["flip_image"] < 1e-3 and stand_in["flip_pixels"] < 1e-3
    assert "became" not in row and "is no cheaper" in row["kept_because"]
    assert row["error"]["image"] < 1e-3 and row["error"]["pixels"] < 1e-3
    saved = json.loads((out / "scenefit.json").read_text())
    assert saved["materials"][0]["kept_because"] == row["kept_because"]


def test_a_dielectric_is_kept_and_named(report):
    _, out, result = report
    row = next(r for r in result["materials"] if r["plugin"] == "dielectric")
    assert row["kept_because"] == "dielectric transmits light; every course model only reflects"
    assert "tried" not in row
    assert "dielectric transmits light" in (out / "index.html").read_text()


def test_the_simplified_xml_loads_and_renders_from_the_report_folder(report, monkeypatch):
    folder, out, result = report
    written = out / result["simplified"]
    assert sorted(os.listdir(out)) == sorted([".mi-brdfs-report", "index.html", "original.png",
                                              "scenefit.json", "simplified.png",
                                              result["simplified"]])
    text = written.read_text()
    assert '"../assets/sphere.obj"' in text and "scenefit" not in text
    monkeypatch.chdir(folder.parent)        # file names are relative to the XML, not the cwd
    scene = mi.load_file(str(written))
    image = np.array(mi.render(scene, spp=4))
    assert image.shape[:2] == (24, 24) and np.isfinite(image).all() and image.mean() > 0


def test_materials_are_found_through_references_wrappers_and_lights():
    root = scenefit.ElementTree.fromstring("""<scene version="3.0.0">
        <bsdf type="diffuse" id="white"/>
        <bsdf type="roughconductor" id="metal"/>
        <shape type="sphere" id="a"><ref id="white"/></shape>
        <shape type="sphere" id="b"><bsdf type="twosided"><ref id="metal"/></bsdf></shape>
        <shape type="sphere" id="c"><bsdf type="bumpmap"><bsdf type="twosided">
            <ref id="white"/></bsdf><texture type="bitmap"/></bsdf></shape>
        <shape type="rectangle" id="light"><ref id="white"/><emitter type="area"/></shape>
        <shape type="sphere" id="d"/>
    </scene>""")
    found = scenefit.find_materials(root)
    assert [(m.label, m.shapes, m.wrappers, m.emitter) for m in found] == [
        ("white: diffuse", [0, 2], [], False),
        ("metal: roughconductor", [1], ["twosided"], False),
        ("light: diffuse", [3], [], True)]
    light = root.findall("shape")[3]
    assert light.find("bsdf").get("id") is None      # the light's own copy


def test_includes_are_inlined_with_their_file_names_found():
    """The studio test scene includes its camera and its materials (the file
    named by a parameter); a texture the included file names relative to the
    main scene's folder, as Mitsuba finds it, stays so; a textured material
    is kept."""
    studio = ASSETS.parent / "studio.xml"
    root, params = scenefit.read_scene(str(studio), {"mode": "hdr"})
    assert root.find("include") is None and root.find("sensor") is not None
    names = sorted(e.get("value") for e in root.iter("string") if e.get("name") == "filename")
    assert {"assets/checker.png", "assets/sphere.obj", "assets/torus.ply"} <= set(names)
    assert all(n.startswith("assets/") for n in names), names
    found = scenefit.find_materials(root)
    assert [(m.label, m.shapes, m.wrappers) for m in found] == [
        ("matte: lambert", [1], ["twosided"]), ("glossy: cook_torrance", [2, 3], [])]
    target = scenefit.T.Target("matte", "matte", xml=scenefit.target_xml(found[0], root, params))
    assert scenefit.kept_reason(found[0], target, scenefit._named(root)) == \
        "a texture drives its parameters; the fit fits constant parameters"


def test_the_cornell_box_as_xml_renders_as_its_dictionary(tmp_path):
    path = tmp_path / "cbox.xml"
    scenefit.write_cornell_box(str(path))
    d = mi.cornell_box()
    d["sensor"]["film"]["width"] = d["sensor"]["film"]["height"] = 16
    from_dict = np.array(mi.render(mi.load_dict(d), spp=8, seed=3))
    from_xml = np.array(mi.render(_small(path), spp=8, seed=3))
    assert np.allclose(from_xml, from_dict, rtol=1e-3, atol=1e-4)


def _small(path):
    text = path.read_text().replace('name="width" value="256"', 'name="width" value="16"')
    return mi.load_string(text.replace('name="height" value="256"', 'name="height" value="16"'))


@pytest.mark.parametrize("args, message", [
    (["--scene", "missing.xml"], "scene not found: missing.xml"),
    (["--scene", "BSDF"], "its root is <bsdf>, not <scene>; give a Mitsuba scene file"),
    (["--scene", "NOTXML"], "not well-formed XML"),
    (["--scene", "SCENE", "diffuse:"], "give TARGETs or --scene, not both"),
    (["--scene", "SCENE", "--models", "nosuch"], "--models: unknown model 'nosuch'"),
    (["diffuse:", "-D", "res=8"], "-D is for --scene"),
    ([], "give a TARGET"),
])
def test_bad_input_gets_one_line(tmp_path, capsys, args, message):
    (tmp_path / "bsdf.xml").write_text('<bsdf type="diffuse" version="3.0.0"/>')
    (tmp_path / "notxml.xml").write_text("<scene")
    (tmp_path / "scene.xml").write_text(SCENE)
    names = {"BSDF": "bsdf.xml", "NOTXML": "notxml.xml", "SCENE": "scene.xml"}
    args = [str(tmp_path / names[a]) if a in names else a for a in args]
    code = cli.main(["fit", *args, "-o", str(tmp_path / "r")])
    err = capsys.readouterr().err.strip()
    assert code == 1 and len(err.splitlines()) == 1 and err.startswith("mi-brdfs fit: error: ")
    assert message in err
    assert not (tmp_path / "r").exists()


def test_an_output_that_is_a_file_is_refused_and_kept(tmp_path, capsys):
    (tmp_path / "scene.xml").write_text(SCENE)
    (tmp_path / "r").write_text("mine")
    code = cli.main(["fit", "--scene", str(tmp_path / "scene.xml"), "-o", str(tmp_path / "r")])
    err = capsys.readouterr().err.strip()
    assert code == 1 and len(err.splitlines()) == 1 and "is an existing file" in err
    assert (tmp_path / "r").read_text() == "mine"


ROOT = Path(__file__).resolve().parents[2]
COMMITTED = ROOT / "docs" / "scene-fit"


@pytest.mark.parametrize("name", ["cornell-box", "course", "several"])
def test_the_guide_reads_the_committed_scene_reports(name):
    """The fit guide's table of the three committed scene reports gives their
    figures; each report's page has its pictures and its simplified scene."""
    result = json.loads((COMMITTED / name / "scenefit.json").read_text(encoding="utf-8"))
    guide = (ROOT / "docs" / "guide" / "fit.md").read_text(encoding="utf-8")
    row = next(line for line in guide.splitlines() if f"scene-fit/{name}/index.html" in line)
    assert f"{result['replaced']} of {len(result['materials'])}" in row
    assert f"FLIP {result['flip_image']:.3f} (seed noise {result['noise_flip_image']:.3f})" in row
    t = result["timing"]
    if t:
        assert f"{t['time_per_sample_ratio']:.2f}×" in row
        assert f"{t['time_to_noise_ratio']:.2f}×" in row
        assert f"load {t['load_average']:.1f}" in row
    for file in ("index.html", "original.png", "simplified.png", result["simplified"]):
        assert (COMMITTED / name / file).exists(), file


def test_the_command_without_jobs_fits_on_the_default_processes(tmp_path, capsys):
    """`mi-brdfs fit --scene` with no -j: the fits run on the default number
    of local processes (once, None reached the process pool and the command
    ended in "'>' not supported between 'NoneType' and 'int'")."""
    (tmp_path / "assets").mkdir()
    shutil.copy(ASSETS / "sphere.obj", tmp_path / "assets" / "sphere.obj")
    (tmp_path / "scene.xml").write_text(SCENE)
    code = cli.main(["fit", "--scene", str(tmp_path / "scene.xml"), "--quick", "--quiet",
                     "--models", "lambert", "-o", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 0, err
    saved = json.loads((tmp_path / "r" / "scenefit.json").read_text())
    assert [r["plugin"] for r in saved["materials"]] == ["phong", "dielectric"]
