"""Looking at a BSDF: its values in the plane of incidence, over the hemisphere,
and its directional albedo; the small scenes that show one (a sphere, a
textured plane); its methods called on many direction pairs and the Dr.Jit
variables a traced call creates (the bench times them, the fit counts them);
and fitting a texture to renders by gradient descent. Used by the validation
report, the benchmarks, the fit, the notebooks and the tests."""
from __future__ import annotations

import contextlib
import io
import math

import numpy as np

import drjit as dr
import mitsuba as mi

from .._jit import from_numpy


def _si(theta_i_deg: float, phi_i_deg: float = 180.0):
    """A surface interaction whose viewer is at theta_i (opaque: one kernel for all angles)."""
    t, p = math.radians(theta_i_deg), math.radians(phi_i_deg)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(dr.opaque(mi.Float, math.sin(t) * math.cos(p)),
                        dr.opaque(mi.Float, math.sin(t) * math.sin(p)),
                        dr.opaque(mi.Float, math.cos(t)))
    si.uv = mi.Point2f(0.5, 0.5)
    return si


def eval_at_viewer(bsdf, theta_i_deg: float, wo: np.ndarray, phi_i_deg: float = 180.0) -> np.ndarray:
    """eval(wi, wo) (f·cos theta_o, per channel) for the viewer at theta_i and an (N, 3) array wo."""
    value = bsdf.eval(mi.BSDFContext(), _si(theta_i_deg, phi_i_deg),
                      from_numpy(mi.Vector3f, wo.T))
    return np.array(value).T


def plane_of_incidence(bsdf, theta_i_deg: float, n: int = 359):
    """(theta_o in radians, signed: > 0 on the mirror side; eval channel mean)
    for directions wo in the plane of incidence. The viewer is at -theta_i."""
    theta_o = np.radians(np.linspace(-89.5, 89.5, n))
    wo = np.stack([np.sin(theta_o), np.zeros(n), np.cos(theta_o)], axis=1)
    return theta_o, eval_at_viewer(bsdf, theta_i_deg, wo).mean(axis=1)


def hemisphere(bsdf, theta_i_deg: float, n: int = 96):
    """eval channel mean on an (n, 4n) grid of (theta_o, phi_o): for 3-D lobe plots.
    Returns theta, phi (radians, 2-D grids) and the values."""
    theta = np.linspace(0, math.pi / 2, n)
    phi = np.linspace(0, 2 * math.pi, 4 * n)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    wo = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    return t, p, eval_at_viewer(bsdf, theta_i_deg, wo).mean(axis=1).reshape(t.shape)


def directional_albedo(bsdf, angles, strata: tuple[int, int] = (512, 2048), seed: int = 7,
                       channel=max) -> np.ndarray:
    """E(theta_i) = integral of eval(wi, wo) dwo for each angle (degrees), by
    stratified jittered uniform-hemisphere quadrature: independent of the
    plugin's own sampling. ``channel`` reduces the three channels (max by default)."""
    nu, nv = strata
    rng = np.random.default_rng(seed)
    u = ((np.arange(nu)[:, None] + rng.random((nu, nv))) / nu).ravel()
    v = ((np.arange(nv)[None, :] + rng.random((nu, nv))) / nv).ravel()
    s = np.sqrt(np.maximum(0.0, 1.0 - u * u))
    wo = from_numpy(mi.Vector3f, (s * np.cos(2 * np.pi * v), s * np.sin(2 * np.pi * v), u))
    out = []
    for theta in angles:
        value = bsdf.eval(mi.BSDFContext(), _si(theta, 0.0), wo)
        e = [float(dr.sum(mi.Float64(value[c]))[0]) * 2 * np.pi / (nu * nv) for c in range(3)]
        out.append(channel(e))
    return np.array(out)


def polar_lobes(ax, bsdf, angles=(0, 30, 60, 80), title: str = "") -> None:
    """Draw eval in the plane of incidence on a matplotlib polar axis, one curve per angle."""
    for a in angles:
        theta_o, value = plane_of_incidence(bsdf, a)
        ax.plot(theta_o, value, label=rf"$\theta_i$ = {a}°")     # θ with a subscript i
    from matplotlib.ticker import MaxNLocator   # optional: the reports extra

    ax.set_theta_zero_location("N")
    ax.set_thetamin(-90)
    ax.set_thetamax(90)
    ax.set_thetagrids(range(-90, 91, 30), [f"{t}°" for t in range(-90, 91, 30)], fontsize=8)
    # A half disc has room for a few radial labels only: at most 3, none at 0
    # (more run into each other: "0.00.050.10...").
    ax.yaxis.set_major_locator(MaxNLocator(nbins=3, prune="lower"))
    ax.tick_params(axis="y", labelsize=7)
    ax.set_rlabel_position(-22.5)
    if title:
        ax.set_title(title, fontsize=10)


def camera(res: int, fov: float, origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0)) -> dict:
    """A perspective sensor looking from ``origin`` at ``target`` (y up), a
    square ``res`` × ``res`` film with a box filter and an independent sampler."""
    return {"type": "perspective", "fov": fov,
            "to_world": mi.ScalarTransform4f().look_at(origin=list(origin), target=list(target),
                                                       up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent"}}


def sphere_scene(bsdf: dict, res: int = 128, integrator: dict | None = None,
                 light=(2.0, 2.5, 3.0), intensity: float = 12.0, env: float = 0.0) -> dict:
    """A unit sphere seen from +z, lit by one point light (and an optional
    constant environment): the scene the notebooks use to show a BSDF."""
    mode = bsdf.get("mode", "hdr")
    d = {
        "type": "scene",
        "integrator": integrator or ({"type": "scanline"} if mode == "scanline"
                                     else {"type": "path", "max_depth": 2}),
        "sensor": camera(res, 32),
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "light": {"type": "point", "position": list(light),
                  "intensity": {"type": "rgb", "value": intensity}},
    }
    if env > 0:
        d["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": env}}
    return d


def render_sphere(bsdf: dict, res: int = 128, spp: int = 16, **scene_options) -> np.ndarray:
    """Render sphere_scene(bsdf) and return the linear RGB image (H, W, 3)."""
    scene = mi.load_dict(sphere_scene(bsdf, res, **scene_options))
    return np.array(mi.render(scene, spp=spp))[..., :3]


# ----------------------------------------------------------------------------
#  BSDF calls on many direction pairs: timed by the bench, counted by the fit
# ----------------------------------------------------------------------------

BSDF_METHODS = ("eval", "pdf", "eval_pdf", "sample")


def bsdf_inputs(lanes: int, seed: int = 1) -> dict:
    """Random viewer and light directions above the surface and random samples,
    evaluated (a kernel then holds the BSDF alone)."""
    rng = np.random.default_rng(seed)

    def hemisphere():
        v = rng.normal(size=(3, lanes))
        v /= np.linalg.norm(v, axis=0)
        v[2] = np.abs(v[2])
        return from_numpy(mi.Vector3f, v)
    si = dr.zeros(mi.SurfaceInteraction3f, lanes)
    si.wi = hemisphere()
    si.uv = from_numpy(mi.Point2f, rng.random((2, lanes), dtype=np.float32))
    x = {"ctx": mi.BSDFContext(), "si": si, "wo": hemisphere(),
         "sample1": from_numpy(mi.Float, rng.random(lanes, dtype=np.float32)),
         "sample2": from_numpy(mi.Point2f, rng.random((2, lanes), dtype=np.float32))}
    dr.eval(x["si"].wi, x["si"].uv, x["wo"], x["sample1"], x["sample2"])
    return x


def bsdf_call(bsdf, method: str, x: dict):
    """``bsdf.method`` (one of :data:`BSDF_METHODS`) on the inputs of :func:`bsdf_inputs`."""
    if method == "sample":
        return bsdf.sample(x["ctx"], x["si"], x["sample1"], x["sample2"])
    return getattr(bsdf, method)(x["ctx"], x["si"], x["wo"])


def variables_created(run) -> int:
    """The Dr.Jit variables ``run()`` creates while it is traced: the
    variable creations in Dr.Jit's trace log, less those that value numbering
    answered with an existing variable ("lvn hit"). Mitsuba's C++ built-ins
    are counted the same way."""
    log, level = io.StringIO(), dr.log_level()
    with contextlib.redirect_stdout(log):            # (Dr.Jit logs through Python's stdout)
        dr.set_log_level(dr.LogLevel.Trace)
        try:
            out = run()
        finally:
            dr.set_log_level(level)
    del out
    return sum(1 for line in log.getvalue().splitlines()
               if line.startswith("jit_var_new") and "[lvn hit]" not in line)


# ----------------------------------------------------------------------------
#  Inverse rendering: a texture fitted to renders
# ----------------------------------------------------------------------------

def bitmap(values) -> dict:
    """A ``bitmap`` texture of an (H, W) or (H, W, C) array: nearest texels,
    values as stored (no sRGB), clamped at the edges."""
    data = np.asarray(values, dtype=np.float32)
    return {"type": "bitmap", "bitmap": mi.Bitmap(data if data.ndim == 3 else data[..., None]),
            "raw": True, "filter_type": "nearest", "wrap_mode": "clamp"}


def plane_scene(bsdf: dict, light, res: int = 32) -> dict:
    """A square plane that fills the view from +z, lit by one point light at
    ``light``, rendered by the scan-line integrator without its clamp (direct
    light: deterministic for a fixed seed, and unbiased in hdr mode)."""
    return {"type": "scene",
            "integrator": {"type": "scanline", "clamp": False, "hide_emitters": True},
            "sensor": camera(res, 40, origin=(0.0, 0.0, 3.0)),
            "plane": {"type": "rectangle", "bsdf": bsdf,
                      "to_world": mi.ScalarTransform4f().scale(1.05)},
            "light": {"type": "point", "position": list(light),
                      "intensity": {"type": "rgb", "value": 2.0}}}


def fit_texture(truth: dict, start: dict, key: str, lights, steps: int, lr: float,
                lo: float, hi: float, res: int = 32, spp: int = 4, seed: int = 3):
    """Fit the parameter ``key`` of the BSDF ``start`` (e.g. a :func:`bitmap`'s
    ``plane.bsdf.alpha.data``) to renders of ``truth`` by Adam, one
    :func:`plane_scene` per light, clipping it to [lo, hi] after each step.
    The loss is the relative squared error summed over the lights, so a
    highlight does not outweigh the rest. Returns (the fitted values, the
    loss of each step).

    One scene per light, not one light moved through ``params`` between the
    renders of a step: Mitsuba 3.9 then computes the earlier renders'
    gradients with the last position (measured with its ``roughconductor``
    too). The step is not frozen (:class:`mi_brdfs.render.frozen.GradientStep`
    records one scene's render, loss and backward pass)."""
    references = [dr.detach(mi.render(mi.load_dict(plane_scene(truth, light, res)),
                                      spp=spp, seed=seed)) for light in lights]
    scenes = [mi.load_dict(plane_scene(start, light, res)) for light in lights]
    params = [mi.traverse(s) for s in scenes]
    opt = mi.ad.Adam(lr=lr)
    opt[key] = params[0][key]
    losses = []
    for _ in range(steps):
        loss = mi.Float(0.0)
        for scene, p, reference in zip(scenes, params, references):
            p.update(opt)                           # the one variable, in every scene
            image = mi.render(scene, p, spp=spp, seed=seed)
            loss += dr.mean(dr.square(image - reference) / dr.square(reference + 0.01), axis=None)
        dr.backward(loss)
        opt.step()
        opt[key] = dr.clip(opt[key], lo, hi)
        losses.append(float(np.array(loss).ravel()[0]))
    return np.array(opt[key]), np.array(losses)
