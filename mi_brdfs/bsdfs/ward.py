r"""
``ward`` — Ward: Lambert diffuse + anisotropic Gaussian specular
================================================================

.. parameters::

Roughness values below ``ALPHA_MIN`` = 1e-4 (0 included) are clamped to it,
as in ``cook_torrance``. As in Mitsuba's ``roughconductor``, ``traverse``
exposes ``alpha`` when the roughness was given isotropically (or not at all)
and ``alpha_u`` / ``alpha_v`` when either of those was given (the other then
keeps its default).

With w_r the viewer (``si.wi``), d the light (``wo``), n, t, b the shading
frame (z, x, y) and h the half vector of d and w_r, the lecture's specular
term, in its dot-product form

.. math::

    f_s = m_S\,\frac{\exp\!\Big(-\big((h\cdot t / a_t)^2 + (h\cdot b / a_b)^2\big)
                     / (h\cdot n)^2\Big)}
               {4\pi\,a_t a_b \sqrt{(\omega_r\cdot n) / (d\cdot n)}}

and in its angle form (δ: angle of h with n, φ: angle of h's projection on the
tb-plane with t; θ_i of the light, θ_r of the viewer)

.. math::

    f_s = m_S\,\frac{\exp\!\big(-\tan^2\delta\,(\cos^2\phi / a_t^2
                                               + \sin^2\phi / a_b^2)\big)}
               {4\pi\,a_t a_b \sqrt{\cos\theta_i \cos\theta_r}}\,\cos\theta_i

(h need not be normalised: the exponent is a ratio.) ``eval`` returns

.. math::

    \text{scanline:}\quad &\operatorname{clamp}_{[0,1]}\big(m_D \max(0, d\cdot n)\big)
        + \operatorname{clamp}_{[0,1]}(f_s) \\
    \text{hdr:}\quad &\frac{m_D}{\pi}\,(d\cdot n) + f_s

f_s is already the radiometric Ward BRDF times cos theta_o = d·n,
m_S exp(...) / (4 pi a_t a_b sqrt((w_r·n)(d·n))) · (d·n), so the hdr mode is the
same value unclamped; it is reciprocal. Its directional albedo (measured and
printed by the project's Ward test, m_S = 1) is at most 1 up to 89 deg for
alpha <= 0.5 (0.99 at normal incidence for alpha = 0.05, 0.59 for 0.5) and
falls roughly as cos(theta_r) for narrow lobes; the 1/sqrt(w_r·n) factor then
makes it diverge as C/sqrt(cos theta_r) within a fraction of a degree of the
horizon (above 1 beyond 89.78 deg for alpha = 0.5, 89.9991 deg for 0.05).
At grazing angles the cosines are kept away from 0 by ``TINY`` (values and
gradients stay finite); a viewer or light below the surface gets no reflection.

Sampling: cosine hemisphere for the diffuse lobe; for the specular lobe
Walter's (2005, "Notes on the Ward BRDF") half-vector sampling. With
psi = 2 pi u_1 and s = sqrt(-log(1 - u_2)) (1 - u_2 > 0: no log of 0),

.. math::

    h = \operatorname{normalize}(a_t\, s \cos\psi,\; a_b\, s \sin\psi,\; 1),

i.e. tan phi_h = (a_b / a_t) tan psi in the quadrant of psi and
tan²delta = -log(1 - u_2) / (cos²phi_h / a_t² + sin²phi_h / a_b²). Its density
over half vectors is (phi has density 1 / (2 pi a_t a_b A(phi)), and given phi,
tan²delta is exponential with rate A(phi) = cos²phi/a_t² + sin²phi/a_b²)

.. math::

    p_h(h) = \frac{\exp\!\big(-\tan^2\delta\; A(\phi)\big)}{\pi\, a_t a_b \cos^3\delta},

and wo = reflect(w_r, h) has p(wo) = p_h(h) / (4 wo·h). The lobe is picked in
proportion to mean(m_D) (pi·mean(m_D) in scanline mode) vs mean(m_S).

**Energy compensation** (``energy_compensation``): the reciprocal lobe of
Kulla & Conty 2017 / Turquin 2019 (:mod:`mi_brdfs.bsdfs.compensation`) returns
what the lobe loses below the horizon (g = 1 - E), so that the specular lobe
reflects m_S at every incident angle (m_S scales it linearly). E is
tabulated from the hdr lobe over (cos θ, α) when isotropic and (cos θ,
sin²φ, α_u, α_v) when anisotropic, α to ∞, smooth (C2) in the roughness;
where Ward's own albedo exceeds 1 (within a fraction of a degree of the
horizon) E is clamped to 1: nothing is added there.

.. code-block:: xml

    <bsdf type="ward">
        <rgb name="diffuse_reflectance" value="0.1, 0.1, 0.3"/>
        <rgb name="specular_reflectance" value="0.6, 0.6, 0.6"/>
        <float name="alpha_u" value="0.3"/>
        <float name="alpha_v" value="0.05"/>
    </bsdf>
"""
from __future__ import annotations

from typing import NamedTuple

import drjit as dr
import mitsuba as mi

from . import compensation, lambert, microfacet as mf
from .base import BRDF
from .cases import THETAS_LOW, Cases, Chi2, Furnace, Pictures, preserves, rgb
from .grid import Axis
from .mixture import Float, Scaled, Spectrum, mean
from .params import Option, Param, Reader

ALPHA_MIN = 1e-4      # smallest roughness used (0 is clamped here)
TINY = 1e-18          # keeps cosines away from 0 (TINY² is still a normal float32)
EXP_CUTOFF = 100.0    # exponents beyond -EXP_CUTOFF give 0 (exp(-100) < 4e-44)
H_MIN = 1e-12         # smallest h·n (normalised h) at which p_h is evaluated

FORMULAS = ("vectors", "angles")


# ----------------------------------------------------------------------------
#  The formulas (local directions: wi = w_r the viewer, wo = d the light)
# ----------------------------------------------------------------------------

def _lobe_support(h, alpha_t, alpha_b):
    """((h·t/a_t)² + (h·b/a_b)², (h·n)², valid) for a unit half vector h.

    ``valid`` marks where exp(-ratio) is not 0 in float32; elsewhere the two
    terms are benign stand-ins (0 and 1), so that no 0/0 or overflow reaches
    the gradients through an unselected branch.
    """
    num = dr.square(h.x / alpha_t) + dr.square(h.y / alpha_b)
    hn2 = dr.square(h.z)
    valid = (h.z > TINY) & (num < EXP_CUTOFF * hn2)
    return dr.select(valid, num, 0.0), dr.select(valid, hn2, 1.0), valid


def _sqrt_cos_ratio(cos_i, cos_o):
    """sqrt((d·n) / (w_r·n)) = 1 / sqrt((w_r·n) / (d·n)), 0 below the surface;
    as sqrt(d·n) / sqrt(w_r·n), exact for cosines down to the smallest float."""
    ok = (cos_i > 0) & (cos_o > 0)
    return dr.select(ok, dr.sqrt(dr.select(ok, cos_o, 1.0)) / dr.sqrt(dr.select(ok, cos_i, 1.0)),
                     0.0)


def specular_vectors(wi, wo, alpha_t, alpha_b):
    """The lecture's dot-product form of f_s / m_S (= the eval value, both modes)."""
    h = mf.half_vector(wi, wo)        # the exponent is a ratio: any scale, but |wi + wo|² underflows
    num, hn2, valid = _lobe_support(h, alpha_t, alpha_b)
    e = dr.select(valid, dr.exp(-num / hn2), 0.0)
    norm = 4.0 * dr.pi * alpha_t * alpha_b
    return e / norm * _sqrt_cos_ratio(mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo))


def specular_angles(wi, wo, alpha_t, alpha_b):
    """The lecture's angle form of f_s / m_S: tan delta, cos phi, sin phi."""
    cos_r, cos_i = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
    h = mf.half_vector(wi, wo)
    _, _, valid = _lobe_support(h, alpha_t, alpha_b)
    # delta and phi from h (stand-ins where the lobe is 0, and phi's stand-in
    # at h = n, where atan2(0, 0) has no derivative and tan delta = 0 anyway)
    rho2 = dr.square(h.x) + dr.square(h.y)
    tilted = valid & (rho2 > dr.square(TINY) * dr.square(h.z))
    hx = dr.select(tilted, h.x, 1.0)
    hy = dr.select(tilted, h.y, 0.0)
    hz = dr.select(valid, h.z, 1.0)
    delta = dr.atan2(dr.safe_sqrt(dr.square(hx) + dr.square(hy)), hz)
    phi = dr.atan2(hy, hx)
    tan_delta = dr.tan(delta)
    sin_phi, cos_phi = dr.sincos(phi)
    a = dr.square(cos_phi / alpha_t) + dr.square(sin_phi / alpha_b)
    tan2_a = dr.select(tilted, dr.square(tan_delta) * a, 0.0)
    e = dr.select(valid, dr.exp(-tan2_a), 0.0)
    # / sqrt(cos θ_i cos θ_r) · cos θ_i, written sqrt(cos θ_i)/sqrt(cos θ_r) (no underflow)
    f = e / (4.0 * dr.pi * alpha_t * alpha_b) * _sqrt_cos_ratio(cos_r, cos_i)
    return f


def eval_specular(wi, wo, alpha_t, alpha_b, formula: str = "vectors"):
    """The specular lobe at wo per unit m_S (the eval value, both modes), by the
    lecture's dot-product form (``"vectors"``) or its angle form (``"angles"``)."""
    form = specular_vectors if formula == "vectors" else specular_angles
    return form(wi, wo, alpha_t, alpha_b)


# ----------------------------------------------------------------------------
#  Walter's half-vector sampling
# ----------------------------------------------------------------------------

def sample_half_vector(sample2, alpha_t, alpha_b):
    """A half vector h with density p_h (see pdf_half_vector)."""
    s = dr.sqrt(-dr.log(dr.fmax(1.0 - sample2.y, TINY)))     # tan delta · sqrt(A(phi))
    sin_psi, cos_psi = dr.sincos(2.0 * dr.pi * sample2.x)
    h = mi.Vector3f(alpha_t * s * cos_psi, alpha_b * s * sin_psi, 1.0)
    return dr.normalize(h)


def pdf_half_vector(h, alpha_t, alpha_b):
    """p_h(h) = exp(-tan²delta A(phi)) / (pi a_t a_b cos³delta), h normalised."""
    num, hn2, valid = _lobe_support(h, alpha_t, alpha_b)
    valid &= h.z > H_MIN
    cos3 = dr.select(valid, h.z, 1.0) * hn2
    p = dr.exp(-num / hn2) / (dr.pi * alpha_t * alpha_b * cos3)
    return dr.select(valid, p, 0.0)


def pdf_specular(wi, wo, alpha_t, alpha_b):
    """The density of :func:`sample_specular` at wo: p_h(h) / (4 wo·h)."""
    h = mf.half_vector(wi, wo)
    o_h = dr.dot(wo, h)
    p = pdf_half_vector(h, alpha_t, alpha_b) / (4.0 * dr.fmax(o_h, TINY))
    return dr.select(o_h > 0, p, 0.0)


def sample_specular(wi, sample2, alpha_t, alpha_b):
    """Sample h, the half vector, then reflect the viewer about it."""
    return mi.reflect(wi, sample_half_vector(sample2, alpha_t, alpha_b))


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------


# Energy compensation: E of the specular lobe (m_S = 1) over (mu, alpha) when
# isotropic, over (mu, sin²phi, alpha_u, alpha_v) when anisotropic; the
# roughness axes reach infinity (where E = 0), smooth (C1) in the roughness.
INF = float("inf")
ALPHA_AXIS = Axis("alpha", 0.0, INF, 33, "ratio", smooth=True)
ISOTROPIC_AXES = (Axis("mu", 0.0, 1.0, 33, "sqrt"), ALPHA_AXIS)
ANISOTROPIC_AXES = (Axis("mu", 0.0, 1.0, 25, "sqrt"), Axis("sin2phi", 0.0, 1.0, 9),
                    Axis("alpha_u", 0.0, INF, 25, "ratio", smooth=True),
                    Axis("alpha_v", 0.0, INF, 25, "ratio", smooth=True))


def _clamped(f):
    """f with its roughness arguments clamped to ALPHA_MIN, as the plugin does."""
    return lambda wi, x, *alphas: f(wi, x, *(dr.fmax(a, ALPHA_MIN) for a in alphas))


ISOTROPIC = compensation.AlbedoSpec(
    "ward/isotropic", ISOTROPIC_AXES,
    f=_clamped(lambda wi, wo, a: specular_vectors(wi, wo, a, a)),
    sample=_clamped(lambda wi, u, a: sample_specular(wi, u, a, a)),
    pdf=_clamped(lambda wi, wo, a: pdf_specular(wi, wo, a, a)))
ANISOTROPIC = compensation.AlbedoSpec(                  # 140,625 nodes: 128² samples (~1 min)
    "ward/anisotropic", ANISOTROPIC_AXES, f=_clamped(specular_vectors),
    sample=_clamped(sample_specular), pdf=_clamped(pdf_specular), samples=128)



# What runs of the model (its cases(), at the end of the class) uses these.
WARD_ALPHAS = [(1e-3, 0.5), (0.5, 1e-3), (0.0, 0.0), (1e-4, 1e-4), (1.0, 1.0), (0.2, 0.2)]


class Inputs(NamedTuple):
    """What one call evaluates at its point."""
    colour_d: Spectrum | None       # m_D, where the diffuse lobe is present
    colour_s: Spectrum | None       # m_S, where the specular lobe is present
    alpha_t: Float                  # the roughness along the tangent
    alpha_b: Float                  # ... and along the bitangent


class Ward(BRDF):
    __doc__ = __doc__                  # the module's documentation, for help()
    name = "ward"
    OPTIONS = (Option("formula", "vectors", FORMULAS,
                      doc='``"vectors"``: the lecture\'s efficient dot-product form; '
                          '``"angles"``: its angle form (tan δ, cos φ, sin φ). Equal to '
                          "float32 precision; the choice is pure speed."),)
    PARAMS = (
        Param("diffuse_reflectance", 0.5, doc="m_D, the Lambert colour; above 1 allowed "
              "(scanline mode clamps)."),
        Param("specular_reflectance", 0.2, doc="m_S, the specular colour."),
        Param("alpha", 0.1, kind="scalar", role="shape", upper=1.0, discontinuous=True,
              doc="isotropic roughness: sets both alpha_u and alpha_v. Giving it together "
                  "with ``alpha_u`` or ``alpha_v`` is an error."),
        Param("alpha_u", 0.1, kind="scalar", role="shape", upper=1.0, discontinuous=True,
              doc="α_t, the roughness along the tangent t: Mitsuba's shading-frame ``s`` "
                  "axis (local x, along dp/du), so the highlight follows the surface's UV "
                  "parametrisation."),
        Param("alpha_v", 0.1, kind="scalar", role="shape", upper=1.0, discontinuous=True,
              doc="α_b, the roughness along the bitangent b (local y)."),
    )

    def read(self, reader: Reader) -> None:
        props = reader.props
        self.anisotropic = "alpha_u" in props or "alpha_v" in props
        if self.anisotropic and "alpha" in props:
            raise reader.error("alpha", props["alpha"],
                               "either alpha or alpha_u/alpha_v, not both")
        roughness = ("alpha_u", "alpha_v") if self.anisotropic else ("alpha",)
        for p in self.PARAMS:
            if p.name in roughness or not p.name.startswith("alpha"):
                self.read_param(reader, p)

    @classmethod
    def tables(cls) -> list[compensation.AlbedoSpec]:
        return [ISOTROPIC, ANISOTROPIC]

    # --- lobes ---------------------------------------------------------------
    def has_diffuse(self) -> bool:
        return not self.off("diffuse_reflectance")

    def has_specular(self) -> bool:
        return not self.off("specular_reflectance")

    def eval_textures(self, si, active) -> Inputs:
        if self.anisotropic:
            alpha_t = dr.fmax(self.m_alpha_u.eval_1(si, active), ALPHA_MIN)
            alpha_b = dr.fmax(self.m_alpha_v.eval_1(si, active), ALPHA_MIN)
        else:
            alpha_t = alpha_b = dr.fmax(self.m_alpha.eval_1(si, active), ALPHA_MIN)
        return Inputs(self.colour("diffuse_reflectance", "diffuse", si, active),
                      self.colour("specular_reflectance", "specular", si, active),
                      alpha_t, alpha_b)

    def eval_diffuse(self, inp, si, wo):
        return lambert.eval_diffuse(inp.colour_d, mi.Frame3f.cos_theta(wo), self.options.mode)

    def eval_specular(self, inp, si, wo):
        return Scaled(inp.colour_s, eval_specular(si.wi, wo, inp.alpha_t, inp.alpha_b,
                                                  self.options.formula))

    def sample_specular(self, inp, si, sample2):
        return sample_specular(si.wi, sample2, inp.alpha_t, inp.alpha_b)

    def pdf_specular(self, inp, si, wo):
        return pdf_specular(si.wi, wo, inp.alpha_t, inp.alpha_b)

    def selection_weights(self, inp, si):
        lobes = self.state.plan.lobes
        w_d = lambert.albedo(mean(inp.colour_d), self.options.mode) if lobes.diffuse \
            else mi.Float(0.0)
        w_s = mean(inp.colour_s) if lobes.specular else mi.Float(0.0)
        return w_d, w_s

    # --- energy compensation: what the lobe loses below the horizon ---------------
    def compensation(self) -> compensation.Compensation:
        if self.anisotropic:
            return compensation.Tabulated(compensation.complement(ANISOTROPIC),
                                          parameters=lambda inp: (inp.alpha_t, inp.alpha_b),
                                          sources=("alpha_u", "alpha_v"),
                                          colour=lambda inp: inp.colour_s)
        return compensation.Tabulated(compensation.complement(ISOTROPIC),
                                      parameters=lambda inp: (inp.alpha_t,), sources=("alpha",),
                                      colour=lambda inp: inp.colour_s)

    # --- what runs of it: the tests, the validation report, the bench, the pictures ---
    @classmethod
    def cases(cls) -> Cases:
        w = {"type": "ward"}
        # viewers at azimuth 30°, not along t or b: the anisotropic lobe is asymmetric
        chi2 = [Chi2({**w, "alpha_u": at, "alpha_v": ab, "diffuse_reflectance": m_d},
                     (0, 30, 60, 85), phi=30.0,
                     quick=(at, ab, m_d) in ((0.05, 0.3, 0.5), (0.05, 0.05, 0.0)))
                for at, ab in ((0.1, 0.1), (0.05, 0.3), (0.3, 0.05), (0.5, 0.5), (0.05, 0.05))
                for m_d in (0.0, 0.5)]
        chi2 += [Chi2({**w, "alpha_u": 0.15, "alpha_v": 0.04, "mode": "scanline",
                       "formula": "angles", "diffuse_reflectance": rgb([0.9, 0.2, 0.1]),
                       "specular_reflectance": rgb([1.5, 0.5, 0.5])}, (45,), phi=30.0),
                 Chi2({**w, "alpha": 0.2, "formula": "angles"}, (75,), phi=30.0),
                 Chi2({**w, "alpha_u": 0.1, "alpha_v": 0.3, "energy_compensation": True,
                       "diffuse_reflectance": 0.2}, (0, 60), phi=30.0)]
        white = {**w, "diffuse_reflectance": 0.0, "specular_reflectance": 1.0}
        return Cases(
            chi2=chi2,
            consistency=[dict(w), {**w, "alpha_u": 0.05, "alpha_v": 0.4, "diffuse_reflectance": 0.0},
                         {**w, "alpha_u": 1e-3, "alpha_v": 0.5, "formula": "angles"},
                         {**w, "alpha": 0.7, "diffuse_reflectance": 0.3, "specular_reflectance": 0.7},
                         {**w, "mode": "scanline", "alpha_u": 0.2, "alpha_v": 0.05,
                          "diffuse_reflectance": rgb([1.5, 0.3, 0.0]),
                          "specular_reflectance": rgb([0.9, 0.9, 2.0])},
                         {**w, "alpha_u": 0.05, "alpha_v": 0.3, "energy_compensation": True}],
            furnace=[Furnace("m_S = 1, α 0.2 × 0.2", {**white, "alpha": 0.2},
                             thetas=THETAS_LOW + (80, 85, 88)),
                     Furnace("m_S = 1, α 0.05 × 0.3", {**white, "alpha_u": 0.05, "alpha_v": 0.3},
                             thetas=THETAS_LOW + (80, 85, 88), phis=(0.0, 90.0))]
            + [preserves(f"compensated, α {label}", {**white, **alpha, "energy_compensation": True},
                         phis=(0.0, 90.0) if "alpha_u" in alpha else (0.0,))
               for label, alpha in (("0.05", {"alpha": 0.05}), ("0.3", {"alpha": 0.3}),
                                    ("0.05 × 0.3", {"alpha_u": 0.05, "alpha_v": 0.3}),
                                    ("2 (beyond 1)", {"alpha": 2.0}),
                                    ("0.3 × 3 (beyond 1)", {"alpha_u": 0.3, "alpha_v": 3.0}))]
            + [preserves("compensated, m_S = 0.5, α 0.3: reflects 0.5",
                         {**white, "specular_reflectance": 0.5, "alpha": 0.3,
                          "energy_compensation": True}, value=0.5)],
            extremes=[{**w, "alpha_u": at, "alpha_v": ab, "mode": mode, "formula": formula,
                       "diffuse_reflectance": m_d, "specular_reflectance": 1.0}
                      for at, ab in WARD_ALPHAS for mode in ("hdr", "scanline")
                      for formula in ("vectors", "angles") for m_d in (0.0, 0.5)]
            + [{**w, "alpha_u": at, "alpha_v": ab, "energy_compensation": True}
               for at, ab in WARD_ALPHAS],
            interior=[{**w, "alpha_u": 0.15, "alpha_v": 0.3, "diffuse_reflectance": 0.5,
                       "specular_reflectance": 0.7, "formula": f} for f in ("vectors", "angles")]
            + [{**w, "alpha": 0.2, "diffuse_reflectance": 0.5, "specular_reflectance": 0.7},
               {**w, "alpha_u": 0.15, "alpha_v": 0.3, "diffuse_reflectance": 0.5,
                "specular_reflectance": 0.7, "energy_compensation": True}],
            negative=({**w, "alpha_u": 0.05, "alpha_v": 0.3, "diffuse_reflectance": 0.0},
                      {**w, "alpha_u": 0.05, "alpha_v": 0.315, "diffuse_reflectance": 0.0}, 45),
            negative_phi=30.0,
            lobe_width=0.3,
            reciprocity=[{**w, "alpha_u": 0.05, "alpha_v": 0.3, "formula": f,
                          "diffuse_reflectance": rgb([0.5, 0.2, 0.1])} for f in ("vectors", "angles")]
            + [{**w, "alpha": 0.3, "energy_compensation": True}],
            lobe={**w, "diffuse_reflectance": 0.3, "specular_reflectance": 0.6, "alpha_u": 0.1,
                  "alpha_v": 0.3},
            costs=[(f"ward {f}", {**w, "alpha_u": 0.1, "alpha_v": 0.3, "formula": f})
                   for f in ("vectors", "angles")],
            energy=[("ward", {**w, "alpha": 0.3}), ("ward anisotropic",
                                                    {**w, "alpha_u": 0.05, "alpha_v": 0.3})],
            sampling=[("ward anisotropic 0.05 x 0.3",
                       {**w, "alpha_u": 0.05, "alpha_v": 0.3, "diffuse_reflectance": 0.0,
                        "specular_reflectance": 0.9},
                       [("lobe", {}), ("cosine", {"sampling": "cosine"})])],
            lobes_off=[("ward m_D=0 vs ward m_D=0.5",
                        {**w, "diffuse_reflectance": 0.0, "alpha_u": 0.1, "alpha_v": 0.3},
                        {**w, "diffuse_reflectance": 0.5, "alpha_u": 0.1, "alpha_v": 0.3})],
            pictures=Pictures("alpha_v", (0.05, 0.15, 0.4), {"alpha_u": 0.05,
                                                             "diffuse_reflectance": 0.3}),
            fits=[{"diffuse_reflectance": [0.5, 0.3, 0.2],
                   "specular_reflectance": [0.3, 0.3, 0.25], "alpha": 0.15},
                  {"diffuse_reflectance": [0.1, 0.3, 0.5],
                   "specular_reflectance": [0.5, 0.4, 0.2], "alpha": 0.4}],
            anisotropic=[("ward/anisotropic", {"alpha_u": 0.1, "alpha_v": 0.1})],
            mitsuba=("roughconductor", "roughplastic"),
            checked="reciprocity; its two forms agree",
        )
