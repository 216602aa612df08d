"""
``toon`` — toon (cel) shading: stepped diffuse and specular colours
===================================================================

.. list-table::
   :header-rows: 1

   * - Parameter
     - Type
     - Description
     - Default
   * - ``diffuse_reflectance``
     - float, rgb or texture (∂)
     - m_D1, the lit colour (d·n >= t_D). >= 0; above 1 allowed (scanline clamps).
     - 0.8
   * - ``diffuse_shade``
     - float, rgb or texture (∂)
     - m_D2, the shade colour (d·n < t_D, lights behind the surface included).
     - 0.2
   * - ``diffuse_threshold``
     - float or texture in [-1, 1] (∂)
     - t_D, compared with d·n.
     - 0.5
   * - ``specular_reflectance``
     - float, rgb or texture (∂)
     - m_S1, the highlight colour (cosine >= t_S).
     - 1.0
   * - ``specular_shade``
     - float, rgb or texture (∂)
     - m_S2, the colour outside the highlight (cosine < t_S).
     - 0.0
   * - ``specular_threshold``
     - float or texture in [-1, 1] (∂)
     - t_S, compared with the specular cosine.
     - 0.9
   * - ``specular_model``
     - string
     - ``"phong"``: the cosine is ω_r·r, r = 2(d·n)n - d; ``"blinn"``: n·h,
       h = normalize(d + ω_r). (The lecture's Phong / Blinn with γ = 1.)
     - ``"phong"``
   * - ``smoothness``
     - float in [0, 2] (∂)
     - width w of the transition band around each threshold: the colour goes
       from the second to the first over [t - w/2, t + w/2] with a smoothstep;
       0 gives the lecture's hard steps.
     - 0
   * - ``diffuse_ramp``
     - texture (∂), optional
     - replaces m_D1, m_D2 and t_D: the diffuse colour is the texture at
       uv = ((d·n + 1)/2, 0.5) (see *Ramps*).
     - none
   * - ``specular_ramp``
     - texture (∂), optional
     - replaces m_S1, m_S2 and t_S: the specular colour is the texture at
       uv = ((c + 1)/2, 0.5), c the specular cosine.
     - none
   * - ``mode``
     - string
     - ``"hdr"`` (unclamped) or ``"scanline"`` (the lecture's formula).
     - ``"hdr"``

The lecture's model, with d the light (``wo``), ω_r the viewer (``si.wi``), n
the normal and c = ω_r·r (phong) or n·h (blinn)::

    f_diffuse  = m_D1 if d·n >= t_D else m_D2          (every d, lights behind included)
    f_specular = m_S1 if c >= t_S else m_S2            (d·n > 0; 0 for lights behind)

and ``eval`` returns::

    scanline:  clamp01(f_diffuse) + clamp01(f_specular)
    hdr:       f_diffuse + f_specular

The toon colours are already the shaded result (they replace Lambert's
m_D·clamp(d·n)), so there is no cos θ_o factor in either mode: the hdr mode is
the scanline one without the [0, 1] clamps, a stylised model with no energy
claim (its white-furnace "albedo" is 3.77 for the defaults at normal incidence, see
``tests/bsdfs/test_toon.py``). The cartoon's dark side is m_D2, also for lights below
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

Sampling. Diffuse: the uniform hemisphere (the issue asked for the cosine
hemisphere, but the toon colour carries no cos theta_o, so cosine sampling
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

import drjit as dr
import mitsuba as mi

from . import microfacet as mf
from .base import BRDF, Reader, is_zero, mean

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
    sin_t = dr.sqrt(dr.fmax(uk * (2.0 - uk), 0.0))
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


class Toon(BRDF):
    name = "toon"

    def read(self, reader: Reader) -> None:
        props = reader.props
        self.specular_model = reader.choice("specular_model", "phong", SPECULAR_MODELS)
        self.m_diffuse_ramp = self.read_ramp(reader, "diffuse_ramp", DIFFUSE_STEP)
        self.m_specular_ramp = self.read_ramp(reader, "specular_ramp", SPECULAR_STEP)
        if self.m_diffuse_ramp is None:
            self.m_d1 = reader.texture("diffuse_reflectance", 0.8)              # m_D1
            self.m_d2 = reader.texture("diffuse_shade", 0.2)                    # m_D2
            self.m_td = reader.texture("diffuse_threshold", 0.5, -1.0, 1.0)     # t_D
        if self.m_specular_ramp is None:
            self.m_s1 = reader.texture("specular_reflectance", 1.0)             # m_S1
            self.m_s2 = reader.texture("specular_shade", 0.0)                   # m_S2
            self.m_ts = reader.texture("specular_threshold", 0.9, -1.0, 1.0)    # t_S
        both_ramps = self.m_diffuse_ramp is not None and self.m_specular_ramp is not None
        if both_ramps and "smoothness" in props:
            raise reader.error("smoothness", props["smoothness"],
                               "not with both diffuse_ramp and specular_ramp (no step to smooth)")
        self.m_smoothness = reader.scalar("smoothness", 0.0, 0.0, 2.0)         # band width w

    @staticmethod
    def read_ramp(reader: Reader, name: str, replaced: tuple[str, ...]):
        """The optional ramp texture; it replaces the lobe's two colours and threshold."""
        if name not in reader.props:
            return None
        for other in replaced:
            if other in reader.props:
                raise reader.error(other, reader.props[other],
                                   f"not with {name} (the ramp replaces the colours and threshold)")
        return reader.texture(name, 0.0)

    def traverse(self, cb):
        flags = mi.ParamFlags.Differentiable
        if self.m_diffuse_ramp is None:
            cb.put("diffuse_reflectance", self.m_d1, flags)
            cb.put("diffuse_shade", self.m_d2, flags)
            cb.put("diffuse_threshold", self.m_td, flags)
        else:
            cb.put("diffuse_ramp", self.m_diffuse_ramp, flags)
        if self.m_specular_ramp is None:
            cb.put("specular_reflectance", self.m_s1, flags)
            cb.put("specular_shade", self.m_s2, flags)
            cb.put("specular_threshold", self.m_ts, flags)
        else:
            cb.put("specular_ramp", self.m_specular_ramp, flags)
        cb.put("smoothness", self.m_smoothness, flags)

    # --- lobes ---------------------------------------------------------------
    def has_diffuse(self) -> bool:
        if self.m_diffuse_ramp is not None:
            return not is_zero(self.m_diffuse_ramp)
        return not (is_zero(self.m_d1) and is_zero(self.m_d2))

    def has_specular(self) -> bool:
        if self.m_specular_ramp is not None:
            return not is_zero(self.m_specular_ramp)
        return not (is_zero(self.m_s1) and is_zero(self.m_s2))

    def diffuse_sampling(self) -> str:
        # The toon diffuse value carries no cos theta_o: sample it uniformly
        # (cosine sampling would give weights 1/cos theta_o, infinite variance).
        return "uniform"

    def lit_from_behind(self) -> bool:
        return True          # the dark side (m_D2) faces lights below the surface

    def ramp(self, tex, si, c, active):
        lookup = mi.SurfaceInteraction3f(si)
        lookup.uv = ramp_uv(c)
        return tex.eval(lookup, active)

    def f_diffuse(self, si, cos_o, active):
        if self.m_diffuse_ramp is not None:
            return self.ramp(self.m_diffuse_ramp, si, cos_o, active)
        return two_tone(cos_o, self.m_td.eval_1(si, active), self.m_smoothness,
                        self.m_d1.eval(si, active), self.m_d2.eval(si, active))

    def f_specular(self, si, c, active):
        if self.m_specular_ramp is not None:
            return self.ramp(self.m_specular_ramp, si, c, active)
        return two_tone(c, self.m_ts.eval_1(si, active), self.m_smoothness,
                        self.m_s1.eval(si, active), self.m_s2.eval(si, active))

    def lobes(self, si, wo, active):
        cos_o = mi.Frame3f.cos_theta(wo)
        f_d = mi.Spectrum(0.0)
        f_s = mi.Spectrum(0.0)
        if self.diffuse:
            f_d = self.f_diffuse(si, cos_o, active)
        if self.specular:
            c = specular_cosine(si.wi, wo, self.specular_model)
            lit = active & (cos_o > 0)                  # no highlight from behind
            f_s = dr.select(lit, self.f_specular(si, c, lit), 0.0)
        return f_d, f_s

    # --- lobe selection: the lobes' hemispherical integrals (hdr values) -------
    def ramp_weight(self, tex, si, active):
        """2π times the ramp's mean at the cosines 0, 1/2 and 1."""
        total = mi.Float(0.0)
        for c in (0.0, 0.5, 1.0):
            total += mean(self.ramp(tex, si, mi.Float(c), active))
        return 2.0 * dr.pi * total / 3.0

    def cone_opening(self, si, active):
        t_lo = self.m_ts.eval_1(si, active) - 0.5 * self.m_smoothness
        return cone_opening(t_lo, self.specular_model)

    def cone_probability(self, si, active):
        """Probability of the highlight cone within the specular lobe (the rest:
        the uniform hemisphere, for m_S2 or a ramp)."""
        if self.m_specular_ramp is not None:
            return mi.Float(0.0)
        k = self.cone_opening(si, active)
        # solid angle of the highlight: the cone (phong), ~4x the half-vector cone (blinn)
        omega = 2.0 * dr.pi * k * (1.0 if self.specular_model == "phong" else 4.0)
        w_cone = mean(self.m_s1.eval(si, active)) * dr.fmin(omega, 2.0 * dr.pi)
        w_rest = mean(self.m_s2.eval(si, active)) * 2.0 * dr.pi
        total = w_cone + w_rest
        return dr.select(total > 0, w_cone / dr.select(total > 0, total, 1.0), 1.0)

    def selection_weights(self, si, active):
        if self.m_diffuse_ramp is not None:
            w_d = self.ramp_weight(self.m_diffuse_ramp, si, active)
        else:
            t = clamp(self.m_td.eval_1(si, active), 0.0, 1.0)
            w_d = 2.0 * dr.pi * (mean(self.m_d1.eval(si, active)) * (1.0 - t)
                                 + mean(self.m_d2.eval(si, active)) * t)
        if self.m_specular_ramp is not None:
            w_s = self.ramp_weight(self.m_specular_ramp, si, active)
        else:
            k = self.cone_opening(si, active)
            omega = dr.fmin(2.0 * dr.pi * k * (1.0 if self.specular_model == "phong" else 4.0),
                            2.0 * dr.pi)
            w_s = (mean(self.m_s1.eval(si, active)) * omega
                   + mean(self.m_s2.eval(si, active)) * 2.0 * dr.pi)
        return w_d, w_s

    # --- specular sampling: highlight cone + uniform hemisphere ----------------
    def sample_specular(self, si, sample2, active):
        q = self.cone_probability(si, active)
        in_cone = sample2.x < q
        # reuse sample2.x for the chosen part
        x = dr.select(in_cone, sample2.x / dr.select(q > 0, q, 1.0),
                      (sample2.x - q) / dr.select(q < 1, 1.0 - q, 1.0))
        u = mi.Point2f(clamp(x, 0.0, 1.0), sample2.y)
        wo_rest = mi.warp.square_to_uniform_hemisphere(u)
        if self.m_specular_ramp is not None:
            return wo_rest
        k = self.cone_opening(si, active)
        if self.specular_model == "blinn":
            h = square_to_cone(u, k)                                  # half vector
            wo_cone = mi.reflect(si.wi, h)
        else:
            wo_cone = mi.Frame3f(mi.reflect(si.wi)).to_world(square_to_cone(u, k))
        return dr.select(in_cone, wo_cone, wo_rest)

    def pdf_specular(self, si, wo, active):
        pdf_rest = dr.select(mi.Frame3f.cos_theta(wo) > 0, dr.inv_two_pi, 0.0)
        if self.m_specular_ramp is not None:
            return pdf_rest
        q = self.cone_probability(si, active)
        k = self.cone_opening(si, active)
        c = specular_cosine(si.wi, wo, self.specular_model)
        pdf_cone = cone_pdf(c, k)
        if self.specular_model == "blinn":
            h = mf.half_vector(si.wi, wo)
            o_dot_h = dr.dot(wo, h)
            pdf_cone = dr.select(o_dot_h > 0, pdf_cone / (4.0 * dr.fmax(o_dot_h, mf.TINY)), 0.0)
        return q * pdf_cone + (1.0 - q) * pdf_rest

    def describe(self) -> dict:
        fields = {"specular_model": self.specular_model, "smoothness": self.m_smoothness}
        if self.m_diffuse_ramp is None:
            fields.update(diffuse_reflectance=self.m_d1, diffuse_shade=self.m_d2,
                          diffuse_threshold=self.m_td)
        else:
            fields["diffuse_ramp"] = self.m_diffuse_ramp
        if self.m_specular_ramp is None:
            fields.update(specular_reflectance=self.m_s1, specular_shade=self.m_s2,
                          specular_threshold=self.m_ts)
        else:
            fields["specular_ramp"] = self.m_specular_ramp
        return fields
