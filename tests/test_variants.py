"""Plugin code is variant-agnostic: register() after a variant switch, then every
plugin loads, samples and renders in the mono and spectral variants too (the
same code runs on cuda_ad_rgb where a GPU exists). In a subprocess, so this
test's variant switches do not touch the others'."""
import subprocess
import sys
from pathlib import Path

SCENES = Path(__file__).resolve().parent.parent / "scenes"

CODE = f"""
import mi_brdfs, mitsuba as mi, drjit as dr, numpy as np
for variant in ["llvm_ad_mono", "llvm_ad_spectral", "llvm_ad_rgb"]:
    mi.set_variant(variant)
    mi_brdfs.register()
    for plugin in mi_brdfs.PLUGINS:
        bsdf = mi.load_dict({{"type": plugin.name}})
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(0.3, 0.0, 0.95)
        bs, weight = bsdf.sample(mi.BSDFContext(), si, 0.3, mi.Point2f(0.2, 0.6))
        assert np.isfinite(np.array(weight)).all(), (variant, plugin.name)
    image = np.array(mi.render(mi.load_file(r"{SCENES / 'course.xml'}", res="16", spp="2")))
    assert np.isfinite(image).all() and image.max() > 0.05, variant
    print(variant, "ok")
"""


def test_every_plugin_in_other_variants():
    run = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-3000:]
    for variant in ("llvm_ad_mono", "llvm_ad_spectral", "llvm_ad_rgb"):
        assert f"{variant} ok" in run.stdout, run.stdout
