r"""
``phong`` — Lambert diffuse + Phong specular reflection
=======================================================

.. parameters::

With w_r the viewer (``si.wi``), d the light (``wo``), n the normal and the
light's mirror direction r = 2 (d·n) n - d, cos(alpha) = w_r·r, ``eval`` returns

.. math::

    \text{scanline:}\quad &\operatorname{clamp}_{[0,1]}\big(m_D \max(0, d\cdot n)\big)
        + \operatorname{clamp}_{[0,1]}\big(m_S \max(0, \omega_r\cdot r)^\gamma\big) \\
    \text{hdr:}\quad &\Big(\frac{m_D}{\pi} + m_S\,\frac{\gamma + 2}{2\pi}
        \max(0, \omega_r\cdot r)^\gamma\Big)\,(d\cdot n)

The scanline form is the lecture's, each lobe clamped per colour channel to
[0, 1]; like the lecture's Phong term it does not carry clamp(d·n). The hdr
form is the energy-normalised *modified* Phong BRDF (Lewis 1994; Lafortune and
Willems 1994): at normal incidence r = n and alpha = theta_o, so the specular
albedo is m_S (gamma+2)/(2 pi) · integral cos^gamma(theta) cos(theta) dw = m_S
exactly, and it only decreases towards grazing incidence (the lobe tilts away
from the normal and the horizon cuts it; about m_S cos(theta_i) for narrow
lobes, measured by the project's white-furnace test of Phong): with
m_D + m_S <= 1 the surface never reflects more than it receives. w_r·r = d·r' (r' the viewer's mirror
direction) is symmetric in d and w_r, so the hdr BRDF is reciprocal.

clamp(w_r·r)^gamma is 0 wherever w_r·r <= 0, also for gamma = 0 (0^0 := 0, the
limit gamma -> 0+: the lobe is the hemisphere of light directions about r',
as the lecture's "zero when the angle is greater than 90°"; its hdr albedo is
m_S (1 + cos(theta_i))/2). It is evaluated without float32
cancellation for any gamma (:mod:`mi_brdfs.bsdfs.powercos`).

Sampling: cosine hemisphere for the diffuse lobe; for the specular lobe the
density (gamma + 1)/(2 pi) cos^gamma(alpha) about the viewer's mirror direction
r' = 2 (w_r·n) n - w_r. Samples below the surface are discarded (that part of
the lobe is lost, so the pdf over the hemisphere is the lobe density itself,
integrating to less than 1). The specular lobe is picked in proportion to its
albedo at normal incidence against the diffuse one: m_S vs m_D in hdr mode,
2 m_S/(gamma + 1) vs m_D in scanline mode (channel means). With m_D = 0 there
is no diffuse lobe, with m_S = 0 no specular one.

**Energy compensation** (``energy_compensation``): the reciprocal lobe of
Kulla & Conty 2017 / Turquin 2019 (:mod:`mi_brdfs.bsdfs.compensation`) returns
what the lobe loses below the horizon (g = 1 - E), so that the specular lobe
reflects m_S at every incident angle: m_S scales it linearly. E(μ, γ) is
tabulated from the hdr lobe above over cos θ and log(1 + γ), γ in [0, 1e8],
smooth (C2) in γ.

.. code-block:: xml

    <bsdf type="phong">
        <rgb name="diffuse_reflectance" value="0.6, 0.1, 0.1"/>
        <rgb name="specular_reflectance" value="0.4, 0.4, 0.4"/>
        <float name="exponent" value="200"/>
        <string name="mode" value="scanline"/>
    </bsdf>
"""
from __future__ import annotations

from functools import partial
from typing import Callable, NamedTuple

import drjit as dr
import mitsuba as mi

from . import compensation, lambert, powercos
from .base import BRDF
from .cases import Cases, Chi2, Furnace, Pictures, preserves, rgb
from .grid import Axis
from .mixture import Float, Scaled, Spectrum, mean
from .params import Param

MAX_EXPONENT = 1e8     # lobe ~1e-4 rad wide, still 1000x the float32 direction spacing


# ----------------------------------------------------------------------------
#  The formulas (local directions: wi = w_r the viewer, wo = d the light)
# ----------------------------------------------------------------------------

def mirror(v):
    """2 (v·n) n - v in the local frame (n = +z): exact in floating point."""
    return mi.Vector3f(-v.x, -v.y, v.z)


def cos_alpha(wi, wo):
    """(cos alpha, 1 - cos alpha) with cos alpha = w_r·r = d·r', r and r' the
    mirror directions of d and w_r (1 - cos alpha accurate near the highlight)."""
    return powercos.cos_versin(wo, mirror(wi))


def eval_specular(wi, wo, gamma, mode: str):
    """The specular lobe at wo: the lecture's clamp(w_r·r)^gamma (scanline), or
    the normalised (gamma + 2)/(2 pi) · clamp(w_r·r)^gamma · cos(theta_o) (hdr)."""
    cos_a, versin_a = cos_alpha(wi, wo)
    lobe = powercos.pow_cos(cos_a, versin_a, gamma)
    if mode == "scanline":
        return lobe
    cos_o = dr.fmax(mi.Frame3f.cos_theta(wo), 0.0)
    return (gamma + 2.0) * dr.inv_two_pi * lobe * cos_o


def specular_weight(gamma, mode: str):
    """The specular lobe's albedo at normal incidence per unit m_S, relative to a
    diffuse lobe's (1 per unit m_D): 1 in hdr mode, 2/(gamma+1) in scanline mode
    (integral of cos^gamma over the hemisphere, 2 pi/(gamma+1), over pi)."""
    return 1.0 if mode == "hdr" else 2.0 / (gamma + 1.0)


def sample_specular(wi, sample2, gamma):
    """A light direction with density (gamma+1)/(2 pi) cos^gamma(alpha) about r'."""
    return mi.Frame3f(mirror(wi)).to_world(powercos.sample(sample2, gamma))


def pdf_specular(wi, wo, gamma):
    """The density of :func:`sample_specular` at wo (per solid angle)."""
    cos_a, versin_a = cos_alpha(wi, wo)
    return powercos.pdf(cos_a, versin_a, gamma)


class Formulas(NamedTuple):
    """The specular lobe's formulas a plugin of this family calls: Phong's
    (this module) or Blinn's (:mod:`.blinn`), with the same signatures."""
    eval: Callable       # eval_specular(wi, wo, gamma, mode)
    sample: Callable     # sample_specular(wi, sample2, gamma)
    pdf: Callable        # pdf_specular(wi, wo, gamma)
    weight: Callable     # specular_weight(gamma, mode)


class Inputs(NamedTuple):
    """What one call evaluates at its point."""
    colour_d: Spectrum | None       # m_D, where the diffuse lobe is present
    colour_s: Spectrum | None       # m_S, where the specular lobe is present
    gamma: Float                    # the exponent


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------

# Energy compensation: E(mu, gamma) of the hdr lobe (m_S = 1), over log(1 + gamma).
ALBEDO_AXES = (Axis("mu", 0.0, 1.0, 33, "sqrt"),
               Axis("exponent", 0.0, MAX_EXPONENT, 49, "log1p", smooth=True))


class Phong(BRDF):
    __doc__ = __doc__                  # the module's documentation, for help()
    # Also the base of blinn.Blinn, which differs only by its formulas
    # (SPECULAR) and its exponent's meaning.
    name = "phong"
    PARAMS = (
        Param("diffuse_reflectance", 0.5, doc="m_D, the diffuse colour; above 1 allowed "
              "(scanline mode clamps)."),
        Param("specular_reflectance", 0.5, doc="m_S, the specular colour. With the default "
              "m_D + m_S = 1 the hdr model reflects at most all the light it receives."),
        Param("exponent", 100.0, 0.0, MAX_EXPONENT, kind="scalar", role="shape",
              discontinuous=True,
              doc="γ, the specular power: the larger, the smaller and sharper the highlight "
                  "(the lecture: \"one or two hundreds\" in practice). γ = 0 is a uniform lobe "
                  "over the hemisphere about the mirror direction. The lobe is evaluated and "
                  "sampled to ~1e-6 at any γ (:mod:`mi_brdfs.bsdfs.powercos`); the bound "
                  "``MAX_EXPONENT`` = 1e8 (a lobe 1e-4 rad wide) keeps it well above the "
                  "spacing of float32 directions (~1e-7)."),
    )
    SPECULAR = Formulas(eval_specular, sample_specular, pdf_specular, specular_weight)

    @classmethod
    def tables(cls) -> list[compensation.AlbedoSpec]:
        lobe = cls.SPECULAR
        return [compensation.AlbedoSpec(cls.name, ALBEDO_AXES, f=partial(lobe.eval, mode="hdr"),
                                        sample=lobe.sample, pdf=lobe.pdf)]

    # --- lobes ---------------------------------------------------------------
    def has_diffuse(self) -> bool:
        return not self.off("diffuse_reflectance")

    def has_specular(self) -> bool:
        return not self.off("specular_reflectance")

    def eval_textures(self, si, active) -> Inputs:
        return Inputs(self.colour("diffuse_reflectance", "diffuse", si, active),
                      self.colour("specular_reflectance", "specular", si, active),
                      self.m_exponent.eval_1(si, active))

    def eval_diffuse(self, inp, si, wo):
        return lambert.eval_diffuse(inp.colour_d, mi.Frame3f.cos_theta(wo), self.options.mode)

    def eval_specular(self, inp, si, wo):
        return Scaled(inp.colour_s, self.SPECULAR.eval(si.wi, wo, inp.gamma, self.options.mode))

    def sample_specular(self, inp, si, sample2):
        return self.SPECULAR.sample(si.wi, sample2, inp.gamma)

    def pdf_specular(self, inp, si, wo):
        return self.SPECULAR.pdf(si.wi, wo, inp.gamma)

    def selection_weights(self, inp, si):
        lobes = self.state.plan.lobes
        w_d = mean(inp.colour_d) if lobes.diffuse else mi.Float(0.0)
        w_s = (mean(inp.colour_s) * self.SPECULAR.weight(inp.gamma, self.options.mode)
               if lobes.specular else mi.Float(0.0))
        return w_d, w_s

    # --- energy compensation: what the lobe loses below the horizon ---------------
    def compensation(self) -> compensation.Compensation:
        return compensation.Tabulated(compensation.complement(self.tables()[0]),
                                      parameters=lambda inp: (inp.gamma,),
                                      sources=("exponent",), colour=lambda inp: inp.colour_s)

    # --- what runs of it: the tests, the validation report, the bench, the pictures ---
    @classmethod
    def cases(cls) -> Cases:
        name = cls.name
        b = {"type": name}
        chi2 = [Chi2({**b, "exponent": g, "diffuse_reflectance": m_d}, (0, 30, 60, 85), ires=64,
                     quick=(g, m_d) in ((100.0, 0.5), (1e3, 0.0)))
                for g in (0.0, 1.0, 10.0, 100.0, 1e3) for m_d in (0.0, 0.5)]
        chi2 += [Chi2({**b, "exponent": 1e4, "diffuse_reflectance": 0.0}, (30, 60, 85), ires=64),
                 # scanline weights pick the lobes differently; coloured lobes
                 Chi2({**b, "mode": "scanline", "exponent": 10.0,
                       "diffuse_reflectance": rgb([1.5, 0.3, 0.0]),
                       "specular_reflectance": rgb([0.9, 0.9, 2.0])}, (45,), ires=64),
                 Chi2({**b, "mode": "scanline", "exponent": 200.0}, (70,), ires=64),
                 # a textured exponent (looked up at uv = 0.5, 0.5)
                 Chi2({**b, "exponent": {"type": "checkerboard", "color0": 5.0, "color1": 50.0}},
                      (20,), ires=64),
                 # the compensation lobe, sampled in proportion to its weight
                 Chi2({**b, "exponent": 20.0, "diffuse_reflectance": 0.2,
                       "energy_compensation": True}, (0, 60), ires=64)]
        white = {**b, "diffuse_reflectance": 0.0, "specular_reflectance": 1.0}
        return Cases(
            chi2=chi2,
            consistency=[{**b, "exponent": 0.0}, {**b, "exponent": 1.0},
                         {**b, "exponent": 50.0, "diffuse_reflectance": 0.0}, {**b, "exponent": 1e4},
                         {**b, "exponent": 1e6, "diffuse_reflectance": 0.0},
                         {**b, "mode": "scanline", "exponent": 30.0,
                          "diffuse_reflectance": rgb([1.5, 0.3, 0.0]),
                          "specular_reflectance": rgb([0.9, 0.9, 2.0])},
                         {**b, "specular_reflectance": 0.0},
                         {**b, "exponent": 8.0, "energy_compensation": True,
                          "specular_reflectance": rgb([0.9, 0.6, 0.3]), "diffuse_reflectance": 0.1}],
            furnace=[Furnace("m_D = 0, m_S = 1, γ = 1", {**white, "exponent": 1.0}),
                     Furnace("m_D = 0.5, m_S = 0.5, γ = 50",
                             {**b, "diffuse_reflectance": 0.5, "specular_reflectance": 0.5,
                              "exponent": 50.0})]
            + [preserves(f"compensated, γ = {g:g}", {**white, "exponent": g,
                                                      "energy_compensation": True},
                         points=2048 if g >= 1e3 else 1024)
               for g in (1.0, 10.0, 100.0, 1e4)]
            + [preserves(f"compensated, m_S = 0.5, γ = {g:g}: reflects 0.5",
                         {**white, "specular_reflectance": 0.5, "exponent": g,
                          "energy_compensation": True}, value=0.5) for g in (10.0, 100.0)],
            extremes=[{**b, "exponent": g, "mode": mode, "diffuse_reflectance": m_d,
                       "specular_reflectance": m_s}
                      for g in (0.0, 1.0, 1e4, 1e6, 1e8) for mode in ("hdr", "scanline")
                      for m_d, m_s in ((0.5, 0.5), (0.0, 1.0), (1.0, 0.0))]
            + [{**b, "exponent": g, "energy_compensation": True} for g in (0.0, 1e8)],
            interior=[{**b, "diffuse_reflectance": 0.4, "specular_reflectance": 0.6,
                       "exponent": 20.0},
                      {**b, "diffuse_reflectance": 0.4, "specular_reflectance": 0.6,
                       "exponent": 20.0, "energy_compensation": True}],
            negative=({**b, "diffuse_reflectance": 0.0, "exponent": 100.0},
                      {**b, "diffuse_reflectance": 0.0, "exponent": 110.0}, 30),
            lobe_width=0.25,
            reciprocity=[{**b, "diffuse_reflectance": rgb([1.4, 0.5, 0.2]), "exponent": g,
                          "specular_reflectance": rgb([0.9, 2.0, 0.3])}
                         for g in (0.0, 1.0, 30.0, 1e3)],
            lobe={**b, "diffuse_reflectance": 0.3, "specular_reflectance": 0.6, "exponent": 30},
            costs=[(name, {**b, "exponent": 50})],
            energy=[(name, {**b, "exponent": 10.0})],
            sampling=[(f"{name} gamma {g}", {**b, "exponent": g, "diffuse_reflectance": 0.0,
                                             "specular_reflectance": 0.9},
                       [("lobe", {}), ("cosine", {"sampling": "cosine"})])
                      for g in (10, 100, 1000)] if name == "phong" else [],
            lobes_off=[(f"{name} m_S=0 vs lambert",
                        {**b, "specular_reflectance": 0.0, "diffuse_reflectance": 0.6},
                        {"type": "lambert", "reflectance": 0.6})] if name == "phong" else [],
            pictures=Pictures("exponent", (10.0, 100.0, 1000.0), {"diffuse_reflectance": 0.3,
                                                                  "specular_reflectance": 0.6}),
            fits=[{"diffuse_reflectance": [0.5, 0.3, 0.2],
                   "specular_reflectance": [0.3, 0.3, 0.25], "exponent": 40.0},
                  {"diffuse_reflectance": [0.1, 0.3, 0.5],
                   "specular_reflectance": [0.5, 0.4, 0.2], "exponent": 400.0}],
            mitsuba=("plastic", "roughplastic"),
            checked="white furnace",
        )
