r"""
``toon`` — toon (cel) shading: stepped diffuse and specular colours
===================================================================

.. parameters::

The lecture's model, with d the light (``wo``), ω_r the viewer (``si.wi``), n
the normal and c = ω_r·r (phong) or n·h (blinn)

.. math::

    f_\text{diffuse} &= \begin{cases} m_{D1} & d\cdot n \ge t_D \\
                                      m_{D2} & \text{otherwise (lights behind included)}
                        \end{cases} \qquad
    f_\text{specular} = \begin{cases} m_{S1} & c \ge t_S \\
                                       m_{S2} & \text{otherwise}
                         \end{cases}
        \quad (d\cdot n > 0;\ 0 \text{ for lights behind})

and ``eval`` returns

.. math::

    \text{scanline:}\quad &\operatorname{clamp}_{[0,1]}(f_\text{diffuse})
        + \operatorname{clamp}_{[0,1]}(f_\text{specular}) \\
    \text{hdr:}\quad &\frac{f_\text{diffuse} + f_\text{specular}}{2\pi}

The toon colours are already the shaded result (they replace Lambert's
m_D·clamp(d·n)), so there is no cos θ_o factor in either mode. The hdr mode
is normalised so that a toon surface reflects at most its brightest colours.
Derivation: ``eval`` is integrated over the light directions d in the white
furnace, and a lobe that is a constant colour c over a solid angle Ω of the
hemisphere reflects c·Ω·N, N the normalisation. The largest Ω is the whole
hemisphere, 2π, so N = 1/(2π) makes each lobe's albedo at most its brightest
colour (per channel, the larger of m_D1 and m_D2 for the diffuse bands, of
m_S1 and m_S2 for the highlight), and a white diffuse-only toon (m_D1 = m_D2 = 1, m_S = 0)
reflects exactly 1 at every angle (the white furnace of its cases). The flat
bands stay flat: N is a constant, not a cosine. The scanline mode is the
lecture's formula, unchanged. The cartoon's dark side is m_D2, also for lights below
the surface (``lit_from_behind()``); the specular is 0 for them, and a viewer
below the surface gets nothing. A cosine exactly equal to its threshold takes
the first colour (>=, as in the lecture).

Smooth transitions (the lecture's "small gradients"): with w = ``smoothness``
> 0 a step becomes m_2 + (m_1 - m_2)·S((c - t)/w + 1/2), S(x) = x²(3 - 2x) on
[0, 1] (clamped). The band is symmetric about t, so at w small enough the
integral of the colour over the hemisphere is that of the hard step.

Ramps (the lecture's 1-D textures f_mD(d·n), f_mS(c), for more than two
colours): any Mitsuba texture, normally a ``bitmap`` one pixel high whose left
edge is the cosine -1 and right edge +1 — looked up at uv = ((cos + 1)/2, 0.5).
Use ``wrap_mode`` ``clamp``; ``filter_type`` ``nearest`` gives hard bands,
``bilinear`` smooth ones; ``raw`` true keeps the colours as stored.

Sampling. Diffuse: the uniform hemisphere (not the cosine hemisphere of the
other diffuse lobes: the toon colour carries no cos theta_o, so cosine sampling
would give weights 1/cos theta_o of infinite variance: fireflies). Specular: a
uniform cone that covers the highlight — around the mirror direction of ω_r
with cos(half-angle) = t_S - w/2 (phong), or of half vectors around n with
cos = max(t_S - w/2, 0), reflected (blinn) — mixed, when m_S2 is not black,
with the uniform hemisphere for the m_S2 part (the whole hemisphere alone with
a specular ramp). The mixture's density is exact; the cone's 1 - cos is kept
>= ``CONE_MIN`` = 1e-4 (a highlight threshold of 1 has no area). Lobes are
picked by their hemispherical integrals. Both lobes are smooth (diffuse and
glossy flags), so integrators sample the lights for them.

.. code-block:: xml

    <bsdf type="toon">
        <rgb name="diffuse_reflectance" value="0.9, 0.5, 0.2"/>
        <rgb name="diffuse_shade" value="0.3, 0.1, 0.05"/>
        <float name="specular_threshold" value="0.95"/>
        <string name="specular_model" value="blinn"/>
        <float name="smoothness" value="0.05"/>
        <string name="mode" value="scanline"/>
    </bsdf>

    <bsdf type="toon">    <!-- a three-tone diffuse ramp -->
        <texture name="diffuse_ramp" type="bitmap">
            <string name="filename" value="ramp.png"/>   <!-- e.g. 3 x 1 pixels -->
            <string name="filter_type" value="nearest"/>
            <string name="wrap_mode" value="clamp"/>
        </texture>
    </bsdf>
"""
from __future__ import annotations

from typing import NamedTuple

import math

import drjit as dr
import mitsuba as mi

from . import microfacet as mf
from .base import BRDF
from .cases import Cases, Chi2, Furnace, Pictures, ramp, rgb
from .mixture import Float, Spectrum, mean
from .params import Option, Param, Reader

SPECULAR_MODELS = ("phong", "blinn")
CONE_MIN = 1e-4            # smallest 1 - cos(half-angle) of the sampling cone
RAMP_V = 0.5               # the ramp textures' v coordinate


# ----------------------------------------------------------------------------
#  The formulas (local directions: wi = ω_r the viewer, wo = d the light)
# ----------------------------------------------------------------------------

def clamp(x, lo, hi):
    """NaN-free clamp (dr.clip propagates NaN)."""
    return dr.fmin(dr.fmax(x, lo), hi)


def step_weight(c, t, w):
    """Weight of the first colour: [c >= t] (w = 0), or the smoothstep over
    [t - w/2, t + w/2]. The division uses a stand-in where w = 0, so no 0/0
    reaches the gradients."""
    hard = dr.select(c >= t, 1.0, 0.0)
    x = clamp((c - t) / dr.select(w > 0, w, 1.0) + 0.5, 0.0, 1.0)
    return dr.select(w > 0, dr.square(x) * (3.0 - 2.0 * x), hard)


def two_tone(c, t, w, m_1, m_2):
    """m_1 where c >= t, m_2 below, blended over the band of width w."""
    return m_2 + (m_1 - m_2) * step_weight(c, t, w)


def specular_cosine(wi, wo, model: str):
    """The lecture's ω_r·r with r = 2(d·n)n - d (the same as d·reflect(ω_r)),
    or n·h with h = normalize(d + ω_r)."""
    if model == "blinn":
        return mi.Frame3f.cos_theta(mf.half_vector(wi, wo))
    return dr.dot(wo, mi.reflect(wi))


def ramp_uv(c):
    """Where a ramp texture is looked up for the cosine c: ((c + 1)/2, 1/2)."""
    return mi.Point2f(clamp(0.5 * (c + 1.0), 0.0, 1.0), RAMP_V)


# ----------------------------------------------------------------------------
#  Sampling: uniform cones and the uniform hemisphere
# ----------------------------------------------------------------------------

def cone_opening(t_lo, model: str):
    """1 - cos(half-angle) of the cone that covers c >= t_lo: around the mirror
    direction for phong (up to the whole sphere, 2), of half vectors around n
    for blinn (up to the hemisphere, 1)."""
    cos_max = clamp(t_lo, -1.0 if model == "phong" else 0.0, 1.0 - CONE_MIN)
    return 1.0 - cos_max


def square_to_cone(sample2, k):
    """Uniform direction in the cone 1 - cos θ <= k around +z (no cancellation
    in sin θ = sqrt(u k (2 - u k)))."""
    uk = sample2.x * k
    cos_t = 1.0 - uk
    sin_t = dr.safe_sqrt(uk * (2.0 - uk))            # safe: a finite derivative at 0
    s, c = dr.sincos(2.0 * dr.pi * sample2.y)
    return mi.Vector3f(c * sin_t, s * sin_t, cos_t)


def cone_pdf(c, k):
    """Density of square_to_cone() at a direction whose cosine to the axis is c."""
    return dr.select(c >= 1.0 - k, 1.0 / (2.0 * dr.pi * k), 0.0)


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------

DIFFUSE_STEP = ("diffuse_reflectance", "diffuse_shade", "diffuse_threshold")
SPECULAR_STEP = ("specular_reflectance", "specular_shade", "specular_threshold")
HDR_SCALE = 1.0 / (2.0 * math.pi)     # hdr: a constant colour c reflects c over the hemisphere



# What runs of the model (its cases(), at the end of the class) uses these.
TOON_RAMP = [[0.1, 0.1, 0.1], [0.4, 0.3, 0.2], [1.0, 0.9, 0.8]]
TOON_SPEC_RAMP = [[0.2, 0.2, 0.2]] * 3 + [[1.5, 1.5, 1.5]]


def _toon_chi2_configs() -> list[dict]:
    configs = []
    for m in ("phong", "blinn"):
        t = {"type": "toon", "specular_model": m}
        configs += [
            t,
            {**t, "smoothness": 0.2, "specular_shade": 0.3, "specular_threshold": 0.7},
            {**t, "specular_threshold": 0.97, "diffuse_reflectance": 0.0, "diffuse_shade": 0.0},
            {**t, "specular_threshold": 0.2, "smoothness": 1.0, "diffuse_reflectance": 0.0,
             "diffuse_shade": 0.0},
        ]
    configs.append({"type": "toon", "diffuse_ramp": ramp(TOON_RAMP),
                    "specular_ramp": ramp(TOON_SPEC_RAMP), "specular_model": "blinn"})
    configs.append({"type": "toon", "mode": "scanline", "diffuse_reflectance": rgb([1.5, 0.5, 0.2]),
                    "specular_reflectance": 3.0, "specular_threshold": 0.8})
    return configs


class Inputs(NamedTuple):
    """What one call evaluates at its point: the two-tone steps of the lobes
    present that have no ramp (None otherwise)."""
    colour_d1: Spectrum | None = None    # m_D1, the lit colour
    colour_d2: Spectrum | None = None    # m_D2, the shade
    t_d: Float | None = None             # t_D
    colour_s1: Spectrum | None = None    # m_S1, the highlight colour
    colour_s2: Spectrum | None = None    # m_S2, outside the highlight
    t_s: Float | None = None             # t_S
    k: Float | None = None               # the highlight cone's opening, 1 - cos
    omega: Float | None = None           # the highlight's solid angle


class Toon(BRDF):
    __doc__ = __doc__                  # the module's documentation, for help()
    name = "toon"
    reciprocal = False
    OPTIONS = (Option("specular_model", "phong", SPECULAR_MODELS, model=True,
                      doc='``"phong"``: the specular cosine is ω_r·r, r = 2(d·n)n - d; '
                          '``"blinn"``: n·h, h = normalize(d + ω_r) (the lecture\'s Phong '
                          "and Blinn with γ = 1)."),)
    PARAMS = (
        Param("diffuse_reflectance", 0.8, doc="m_D1, the lit colour (d·n >= t_D); above 1 "
              "allowed (scanline mode clamps)."),
        Param("diffuse_shade", 0.2, doc="m_D2, the shade colour (d·n < t_D, lights behind "
              "the surface included)."),
        Param("diffuse_threshold", 0.5, -1.0, 1.0, kind="scalar", role="shape",
              doc="t_D, compared with d·n."),
        Param("specular_reflectance", 1.0, doc="m_S1, the highlight colour (specular "
              "cosine >= t_S)."),
        Param("specular_shade", 0.0, doc="m_S2, the colour outside the highlight (cosine "
              "< t_S)."),
        Param("specular_threshold", 0.9, -1.0, 1.0, kind="scalar", role="shape",
              doc="t_S, compared with the specular cosine."),
        Param("smoothness", 0.0, 0.0, 2.0, kind="float", role="shape",
              doc="width w of the transition band around each threshold: the colour goes "
                  "from the second to the first over [t - w/2, t + w/2] with a smoothstep; "
                  "0 gives the lecture's hard steps."),
        Param("diffuse_ramp", 0.0, optional=True,
              doc="replaces m_D1, m_D2 and t_D: the diffuse colour is this texture at "
                  "uv = ((d·n + 1)/2, 0.5) (see *Ramps*)."),
        Param("specular_ramp", 0.0, optional=True,
              doc="replaces m_S1, m_S2 and t_S: the specular colour is this texture at "
                  "uv = ((c + 1)/2, 0.5), c the specular cosine."),
    )

    def read(self, reader: Reader) -> None:
        props = reader.props
        decl = {p.name: p for p in self.PARAMS}
        ramps = {}
        for ramp, replaced in (("diffuse_ramp", DIFFUSE_STEP), ("specular_ramp", SPECULAR_STEP)):
            ramps[ramp] = ramp in props
            for other in replaced:
                if ramps[ramp] and other in props:
                    raise reader.error(other, props[other], f"not with {ramp} (the ramp "
                                       "replaces the colours and threshold)")
            setattr(self, "m_" + ramp, None)
            for name in ((ramp,) if ramps[ramp] else replaced):
                self.read_param(reader, decl[name])
        if all(ramps.values()) and "smoothness" in props:
            raise reader.error("smoothness", props["smoothness"],
                               "not with both diffuse_ramp and specular_ramp (no step to smooth)")
        self.read_param(reader, decl["smoothness"])

    # --- lobes ---------------------------------------------------------------
    def has_diffuse(self) -> bool:
        if self.m_diffuse_ramp is not None:
            return not self.off("diffuse_ramp")
        return not (self.off("diffuse_reflectance") and self.off("diffuse_shade"))

    def has_specular(self) -> bool:
        if self.m_specular_ramp is not None:
            return not self.off("specular_ramp")
        return not (self.off("specular_reflectance") and self.off("specular_shade"))

    def diffuse_sampling(self) -> str:
        # The toon diffuse value carries no cos theta_o: sample it uniformly
        # (cosine sampling would give weights 1/cos theta_o, infinite variance).
        return "uniform"

    def lit_from_behind(self) -> bool:
        # The scan-line dark side (m_D2) faces lights below the surface; in a
        # path tracer the surface is opaque and light from below never reaches it.
        return self.options.mode == "scanline"

    def eval_textures(self, si, active) -> Inputs:
        steps, lobes = {}, self.state.plan.lobes
        if lobes.diffuse and self.m_diffuse_ramp is None:
            steps.update(colour_d1=self.m_diffuse_reflectance.eval(si, active),
                         colour_d2=self.m_diffuse_shade.eval(si, active),
                         t_d=self.m_diffuse_threshold.eval_1(si, active))
        if lobes.specular and self.m_specular_ramp is None:
            t_s = self.m_specular_threshold.eval_1(si, active)
            k = cone_opening(t_s - 0.5 * self.m_smoothness, self.options.specular_model)
            # solid angle of the highlight: the cone (phong), ~4x the half-vector cone (blinn)
            scale = 1.0 if self.options.specular_model == "phong" else 4.0
            steps.update(colour_s1=self.m_specular_reflectance.eval(si, active),
                         colour_s2=self.m_specular_shade.eval(si, active), t_s=t_s, k=k,
                         omega=dr.fmin(2.0 * dr.pi * k * scale, 2.0 * dr.pi))
        return Inputs(**steps)

    def ramp(self, tex, si, c):
        lookup = mi.SurfaceInteraction3f(si)
        lookup.uv = ramp_uv(c)
        return tex.eval(lookup)

    def scale(self):
        return 1.0 if self.options.mode == "scanline" else HDR_SCALE

    def eval_diffuse(self, inp, si, wo):
        cos_o = mi.Frame3f.cos_theta(wo)
        if self.m_diffuse_ramp is not None:
            colour = self.ramp(self.m_diffuse_ramp, si, cos_o)
        else:
            colour = two_tone(cos_o, inp.t_d, self.m_smoothness, inp.colour_d1, inp.colour_d2)
        return colour * self.scale()

    def eval_specular(self, inp, si, wo):
        c = specular_cosine(si.wi, wo, self.options.specular_model)
        if self.m_specular_ramp is not None:
            colour = self.ramp(self.m_specular_ramp, si, c)
        else:
            colour = two_tone(c, inp.t_s, self.m_smoothness, inp.colour_s1, inp.colour_s2)
        lit = mi.Frame3f.cos_theta(wo) > 0               # no highlight from behind
        return dr.select(lit, colour * self.scale(), 0.0)

    # --- lobe selection: the lobes' hemispherical integrals ------------------------
    def ramp_weight(self, tex, si):
        """2π times the ramp's mean at the cosines 0, 1/2 and 1."""
        total = mi.Float(0.0)
        for c in (0.0, 0.5, 1.0):
            total += mean(self.ramp(tex, si, mi.Float(c)))
        return 2.0 * dr.pi * total / 3.0

    def cone_probability(self, inp):
        """Probability of the highlight cone within the specular lobe (the rest:
        the uniform hemisphere, for m_S2 or a ramp)."""
        if self.m_specular_ramp is not None:
            return mi.Float(0.0)
        w_cone = mean(inp.colour_s1) * inp.omega
        w_rest = mean(inp.colour_s2) * 2.0 * dr.pi
        total = w_cone + w_rest
        return dr.select(total > 0, w_cone / dr.select(total > 0, total, 1.0), 1.0)

    def selection_weights(self, inp, si):
        w_d = w_s = mi.Float(0.0)
        lobes = self.state.plan.lobes
        if lobes.diffuse:
            if self.m_diffuse_ramp is not None:
                w_d = self.ramp_weight(self.m_diffuse_ramp, si)
            else:
                t = clamp(inp.t_d, 0.0, 1.0)
                w_d = 2.0 * dr.pi * (mean(inp.colour_d1) * (1.0 - t) + mean(inp.colour_d2) * t)
        if lobes.specular:
            if self.m_specular_ramp is not None:
                w_s = self.ramp_weight(self.m_specular_ramp, si)
            else:
                w_s = mean(inp.colour_s1) * inp.omega + mean(inp.colour_s2) * 2.0 * dr.pi
        return w_d, w_s

    # --- specular sampling: highlight cone + uniform hemisphere -------------------
    def sample_specular(self, inp, si, sample2):
        q = self.cone_probability(inp)
        in_cone = sample2.x < q
        # reuse sample2.x for the chosen part
        x = dr.select(in_cone, sample2.x / dr.select(q > 0, q, 1.0),
                      (sample2.x - q) / dr.select(q < 1, 1.0 - q, 1.0))
        u = mi.Point2f(clamp(x, 0.0, 1.0), sample2.y)
        wo_rest = mi.warp.square_to_uniform_hemisphere(u)
        if self.m_specular_ramp is not None:
            return wo_rest
        if self.options.specular_model == "blinn":
            h = square_to_cone(u, inp.k)                                  # half vector
            wo_cone = mi.reflect(si.wi, h)
        else:
            wo_cone = mi.Frame3f(mi.reflect(si.wi)).to_world(square_to_cone(u, inp.k))
        return dr.select(in_cone, wo_cone, wo_rest)

    def pdf_specular(self, inp, si, wo):
        pdf_rest = dr.select(mi.Frame3f.cos_theta(wo) > 0, dr.inv_two_pi, 0.0)
        if self.m_specular_ramp is not None:
            return pdf_rest
        q = self.cone_probability(inp)
        c = specular_cosine(si.wi, wo, self.options.specular_model)
        pdf_cone = cone_pdf(c, inp.k)
        if self.options.specular_model == "blinn":
            h = mf.half_vector(si.wi, wo)
            o_dot_h = dr.dot(wo, h)
            pdf_cone = dr.select(o_dot_h > 0, pdf_cone / (4.0 * dr.fmax(o_dot_h, mf.TINY)), 0.0)
        return q * pdf_cone + (1.0 - q) * pdf_rest

    # --- what runs of it: the tests, the validation report, the bench, the pictures ---
    @classmethod
    def cases(cls) -> Cases:
        t = {"type": "toon"}
        chi2_configs = _toon_chi2_configs()
        return Cases(
            chi2=[Chi2(c, (0, 30, 60, 85), ires=32,
                       quick=c == {**t, "specular_model": "phong"} or "diffuse_ramp" in c)
                  for c in chi2_configs],
            consistency=chi2_configs + [{**t, "specular_threshold": 1.0},
                                        {**t, "smoothness": 2.0, "specular_shade": 0.1}],
            furnace=[
                # hdr: each lobe reflects at most its brightest colour (here 0.8 + 1)
                Furnace("defaults", dict(t), hi=1.8),
                Furnace("defaults, blinn", {**t, "specular_model": "blinn"}, hi=1.8),
                Furnace("white diffuse only: exactly 1", {**t, "diffuse_reflectance": 1.0,
                                                          "diffuse_shade": 1.0,
                                                          "specular_reflectance": 0.0},
                        lo=1.0, hi=1.0, tol=0.01),
            ],
            extremes=[dict(t, specular_model=m, mode=mode, smoothness=w, diffuse_threshold=td,
                           specular_threshold=ts, specular_shade=ss)
                      for m in ("phong", "blinn") for mode in ("hdr", "scanline") for w in (0.0, 2.0)
                      for td, ts in ((0.5, 0.9), (-1.0, 1.0), (1.0, -1.0), (0.0, 0.0))
                      for ss in (0.0, 0.4)],
            interior=[dict(t, specular_model=m, diffuse_reflectance=0.7, diffuse_shade=0.25,
                           diffuse_threshold=0.4, specular_reflectance=0.9, specular_shade=0.1,
                           specular_threshold=0.6, smoothness=0.3) for m in ("phong", "blinn")],
            negative=({**t, "diffuse_reflectance": 0.0, "diffuse_shade": 0.0,
                       "specular_threshold": 0.95},
                      {**t, "diffuse_reflectance": 0.0, "diffuse_shade": 0.0,
                       "specular_threshold": 0.94}, 30),
            lobe_width=0.6,
            lobe={**t, "smoothness": 0.1},
            costs=[("toon", dict(t)),
                   ("toon with ramps", {**t, "diffuse_ramp": ramp([[0.1] * 3, [0.1] * 3,
                                                                        [0.4] * 3, [0.8] * 3]),
                                        "specular_ramp": ramp([[0.0] * 3] * 7 + [[1.0] * 3])})],
            # a lit colour of the course scene's: the white highlight shows on it
            pictures=Pictures("specular_threshold", (0.5, 0.8, 0.95),
                              {"diffuse_reflectance": [0.3, 0.7, 0.9],
                               "diffuse_shade": [0.08, 0.2, 0.35]}),
            fits=[{"diffuse_reflectance": [0.8, 0.5, 0.3], "diffuse_shade": [0.2, 0.1, 0.1],
                   "diffuse_threshold": 0.4, "specular_reflectance": [0.9, 0.9, 0.8],
                   "specular_shade": [0.05, 0.05, 0.1], "specular_threshold": 0.85,
                   "smoothness": 0.3},
                  {"diffuse_reflectance": [0.3, 0.6, 0.8], "diffuse_shade": [0.1, 0.2, 0.3],
                   "diffuse_threshold": 0.1, "specular_reflectance": [0.7, 0.6, 0.5],
                   "specular_shade": [0.02, 0.04, 0.06], "specular_threshold": 0.95,
                   "smoothness": 0.15}],
            # its hdr mode reflects the scan-line colours / 2π: +log2(2π) EV on the README
            hdr_exposure=round(math.log2(2.0 * math.pi), 2),
            mitsuba=("diffuse",),
            checked="the lecture's step functions",
        )
