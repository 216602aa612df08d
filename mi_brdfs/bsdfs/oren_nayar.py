r"""
``oren_nayar`` — Oren-Nayar rough diffuse reflection
====================================================

.. parameters::

With d the light (``wo``), ω_r the viewer (``si.wi``) and n the normal, the
lecture's model

.. math::

    \theta_i &= \arccos(d\cdot n), \quad \theta_r = \arccos(\omega_r\cdot n), \quad
        \alpha = \max(\theta_i, \theta_r), \quad \beta = \min(\theta_i, \theta_r) \\
    A &= 1 - 0.5\,\frac{\sigma^2}{\sigma^2 + 0.33}, \quad
        B = 0.45\,\frac{\sigma^2}{\sigma^2 + 0.09} \\
    v_i &= \operatorname{normalize}\big(d - (d\cdot n)\,n\big), \quad
        v_r = \operatorname{normalize}\big(\omega_r - (\omega_r\cdot n)\,n\big), \quad
        G = \max(0, v_i\cdot v_r)

and ``eval`` returns

.. math::

    \text{scanline:}\quad \texttt{eval} &= f_r = \operatorname{clamp}_{[0,1]}\big(
        m_D \max(0, d\cdot n)\,(A + B\,G \sin\alpha \tan\beta)\big) \\
    \text{hdr:}\quad \texttt{eval} &= f_r \cos\theta_o, \qquad
        f_r = \frac{m_D}{\pi}\,(A + B\,G \sin\alpha \tan\beta)

(scanline: the lecture's L(A + B G sin α tan β) with L = m_D·clamp(d·n),
clamped per channel to [0, 1]; hdr: the same divided by π and unclamped, i.e.
Oren and Nayar's qualitative model, reciprocal in d and ω_r). σ = 0 gives
A = 1, B = 0: Lambert, bit for bit the m_D/π·cos θ_o of Mitsuba's ``diffuse``.

Degenerate cases. G: when d or ω_r is along n its projection has length 0; G
is then 0 (the factor sin α tan β is 0 there anyway, since β = 0). tan β: β is
kept below ``BETA_MAX`` = π/2 - 1e-6, so tan β <= ~1e6 (no Inf when both
directions graze the surface); eval stays bounded since tan β·cos θ_o <= 1.

The white-furnace albedo of the hdr model is not 1: at σ = 0 it is 1; it falls
with σ (0.56 at normal incidence for σ = π/2, where only A remains), and for
small σ at grazing incidence the qualitative model slightly exceeds 1 (about
1.014 at σ = 0.2, 88°). This is the model's, not the plugin's.

``method="table"``. As the lecture suggests, the σ-dependent factors stay
analytic (A and B, so σ may be a texture and may change without rebuilding)
and only the geometric factor T(p, q) = sin α tan β, a function of p = d·n and
q = ω_r·n alone, is tabulated on a uniform ``table_resolution`` × ``table_resolution`` grid over
[0, 1]² and bilinearly interpolated::

    f_r = m_D/π · (A + B G T~(d·n, ω_r·n))          (hdr; scanline likewise)

T is symmetric, so the table model stays reciprocal. T is infinite at
p = q = 0 (tan 90°); that node holds the value of its neighbours (cos β =
1/(R-1)), so T~(p, q)·p stays <= ~1. The interpolation error is largest where
both directions graze the surface (there T = sin α sin β / max(p, q) has a
kink along p = q whose slope grows as 1/max(p, q)), and near the normal it
falls only as sqrt(h) (the sqrt(1 - cos²) in sin α and tan β).
The project's Oren-Nayar test prints it; at the default 64 nodes, σ = π/2,
m_D = 1 (hdr eval <= 0.32): RMS 2e-4 over the hemisphere, at most 0.003 (3 %)
where both cosines are >= 0.1, 0.04 where both directions graze. (The table buys nothing on a CPU: sin α tan β is also
sqrt(1-p²)·sqrt(1-q²)/max(p, q) without acos; it is the lecture's GPU trick.)

Sampling: cosine hemisphere (the base's diffuse lobe). With ``reflectance`` 0
the plugin has no lobe. A viewer or light below the surface gets no reflection.

**Energy compensation** (``energy_compensation``, ``method="exact"`` only):
the energy-preserving Oren-Nayar model EON (Portsmouth, Kutz & Hill, JCGT
2025): Fujii's Oren-Nayar (FON) plus its analytic multiple-scattering lobe,
the diffuse lobe of OpenPBR, MaterialX and Cycles; a white surface reflects 1
at every angle. Its roughness is r = B(σ)/A(σ) (the lecture's A, B: the ratio
of the retro-reflective term to the Lambertian one, Fujii's mixing ratio), so
σ in [0, π/2] maps to r in [0, 0.776] and σ = 0 stays Lambert. Its colour
enters as the paper defines it, per bounce (ρ_ms = m_D² E_avg /
(1 - m_D (1 - E_avg))), not linearly: the one exception to linear colours.

.. code-block:: xml

    <bsdf type="oren_nayar">
        <rgb name="reflectance" value="0.7, 0.45, 0.3"/>
        <float name="sigma" value="0.5"/>
        <string name="method" value="table"/>
        <string name="mode" value="scanline"/>
    </bsdf>
"""
from __future__ import annotations

from typing import NamedTuple

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from . import compensation
from .base import BRDF
from .cases import HALF_PI, Cases, Chi2, Furnace, Pictures, preserves, rgb
from .grid import Axis, Grid
from .mixture import Float, Scaled, Spectrum
from .params import Option, Param, Reader

METHODS = ("exact", "table")
SIGMA_MAX = 0.5 * math.pi          # σ in [0, π/2]
BETA_MAX = 0.5 * math.pi - 1e-6    # tan β <= tan(BETA_MAX) ~ 1e6 (grazing: no Inf)
PROJ_MIN = 1e-30                   # |projection|² product below which G is 0
TABLE_DEFAULT, TABLE_MIN, TABLE_MAX = 64, 2, 4096


# ----------------------------------------------------------------------------
#  The formulas (cos_o = d·n, the light; cos_i = ω_r·n, the viewer)
# ----------------------------------------------------------------------------

def a_b(sigma):
    """The lecture's A and B from σ (radians)."""
    s2 = dr.square(sigma)
    return 1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)


def g_azimuth(wi, wo):
    """G = max(0, v_i·v_r), v the normalised projections onto the tangent
    plane; 0 when a projection has length 0 (a direction along n)."""
    dot_xy = wi.x * wo.x + wi.y * wo.y
    len2 = (dr.square(wi.x) + dr.square(wi.y)) * (dr.square(wo.x) + dr.square(wo.y))
    return dr.fmax(dot_xy, 0.0) * dr.rsqrt(dr.fmax(len2, PROJ_MIN))


def sin_alpha_tan_beta(cos_i, cos_o):
    """sin α · tan β with the lecture's acos/sin/tan (β bounded below π/2)."""
    theta_i = dr.acos(dr.fmin(dr.fmax(cos_o, 0.0), 1.0))     # light
    theta_r = dr.acos(dr.fmin(dr.fmax(cos_i, 0.0), 1.0))     # viewer
    alpha = dr.maximum(theta_i, theta_r)
    beta = dr.fmin(dr.minimum(theta_i, theta_r), BETA_MAX)
    return dr.sin(alpha) * dr.tan(beta)


def oren_nayar(m_d, sigma, g, sa_tb, cos_o, mode: str):
    """eval of both modes: m_D·clamp(d·n)·(A + B G sin α tan β), /π in hdr
    (before the scanline clamp, which the base applies), as m_D times its shape."""
    a, b = a_b(sigma)
    scale = 1.0 if mode == "scanline" else dr.inv_pi
    return Scaled(m_d, scale * dr.fmax(cos_o, 0.0) * (a + b * g * sa_tb))


# ----------------------------------------------------------------------------
#  The lecture's table of sin α tan β over (d·n, ω_r·n)
# ----------------------------------------------------------------------------

def table_values(res: int) -> np.ndarray:
    """T(p, q) = sin α tan β at the nodes p_i = i/(res-1), q_j = j/(res-1),
    as a flat (res·res) float64 array (row i = p). T(0, 0) = ∞ is replaced by
    the value with cos β = 1/(res-1), that of its neighbours."""
    c = np.linspace(0.0, 1.0, res)
    p, q = np.meshgrid(c, c, indexing="ij")
    cos_a, cos_b = np.minimum(p, q), np.maximum(p, q)       # α is the larger angle
    sin_a = np.sqrt(1.0 - cos_a ** 2)
    tan_b = np.sqrt(1.0 - cos_b ** 2) / np.maximum(cos_b, 1.0 / (res - 1))
    return (sin_a * tan_b).ravel()


def table_grid(res: int) -> Grid:
    """The table as a :class:`.grid.Grid` over (p, q) = (d·n, ω_r·n)."""
    axes = (Axis("p", 0.0, 1.0, res), Axis("q", 0.0, 1.0, res))
    return Grid(axes, table_values(res).reshape(res, res))


# ----------------------------------------------------------------------------
#  The energy-preserving Oren-Nayar (EON), for energy_compensation
# ----------------------------------------------------------------------------

FON_C1 = 0.5 - 2.0 / (3.0 * math.pi)          # Fujii's A = 1/(1 + C1 r)
FON_C2 = 2.0 / 3.0 - 28.0 / (15.0 * math.pi)  # E_avg = A (1 + C2 r)


def eon_roughness(sigma):
    """EON's roughness r from the lecture's σ: r = B(σ)/A(σ), the ratio of the
    retro-reflective term to the Lambertian one in the lecture's model (Fujii's
    mixing ratio σ'); σ in [0, π/2] maps to r in [0, 0.776]."""
    a, b = a_b(sigma)
    return b / a


def fon(m_d, r, wi, wo):
    """Fujii's Oren-Nayar (FON) in eval convention: m_D/π A (1 + r s/t) cos θ_o,
    s = ω_i·ω_o - μ_i μ_o, t = max(μ_i, μ_o) where s > 0 (else 1), A = 1/(1 + C1 r).
    Written as A (μ_o + r s μ_o/t) with μ_o/t <= 1: finite at grazing. As m_D
    times its shape."""
    mu_i, mu_o = dr.fmax(wi.z, 0.0), dr.fmax(wo.z, 0.0)
    s = wi.x * wo.x + wi.y * wo.y                      # = ω_i·ω_o - μ_i μ_o, exactly
    t = dr.fmax(mu_i, mu_o)
    ratio = dr.select(s > 0, mu_o / dr.select(t > 0, t, 1.0), mu_o)    # μ_o / t
    a = 1.0 / (1.0 + FON_C1 * r)
    return Scaled(m_d, dr.inv_pi * a * (mu_o + r * s * ratio))


def fon_albedo(mu, r):
    """E_FON(μ) = A + (B/π) G(μ), B = r A, with (Portsmouth et al. 2025)
    G = S (acos μ - S μ) + 2/3 ((S/μ)(1 - S³) - S), S = sqrt(1 - μ²);
    (S/μ)(1 - S³) written as S μ (1 + S + S²)/(1 + S) (finite at μ = 0)."""
    mu = dr.fmin(dr.fmax(mu, 0.0), 1.0)
    s = dr.safe_sqrt(1.0 - dr.square(mu))
    g = s * (dr.acos(mu) - s * mu) \
        + (2.0 / 3.0) * (s * mu * (1.0 + s + dr.square(s)) / (1.0 + s) - s)
    a = 1.0 / (1.0 + FON_C1 * r)
    return a * (1.0 + r * dr.inv_pi * g)


def fon_albedo_average(r):
    """The cosine-weighted average of E_FON: A (1 + C2 r)."""
    return (1.0 + FON_C2 * r) / (1.0 + FON_C1 * r)


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------

class Inputs(NamedTuple):
    """What one call evaluates at its point."""
    colour_d: Spectrum | None       # m_D, where the lobe is present
    sigma: Float                    # σ, the lecture's roughness
    r: Float                        # EON's roughness (energy compensation)


class OrenNayar(BRDF):
    __doc__ = __doc__                  # the module's documentation, for help()
    name = "oren_nayar"
    OPTIONS = (
        Option("method", "exact", METHODS,
               doc='``"exact"``: the lecture\'s formulas (acos, sin, tan) at every evaluation; '
                   '``"table"``: the lecture\'s faster variant, sin α·tan β looked up in a 2-D '
                   "table over (d·n, ω_r·n), bilinearly interpolated."),
        Option("table_resolution", TABLE_DEFAULT, lo=TABLE_MIN, hi=TABLE_MAX,
               doc='nodes per axis of the table (``method="table"`` only; built once, at '
                   "load time)."),
    )
    PARAMS = (
        Param("reflectance", 0.5, doc="m_D, the diffuse colour; above 1 allowed (scanline "
              "mode clamps the result to [0, 1])."),
        Param("sigma", 0.3, 0.0, SIGMA_MAX, kind="scalar", role="shape",
              doc="σ, the roughness in radians (the standard deviation of the facet slope "
                  "angle), up to π/2. σ = 0 is Lambert, exactly."),
    )

    def read(self, reader: Reader) -> None:
        super().read(reader)
        self.table = None                   # T(p, q) = sin α tan β
        if "table_resolution" in reader.props and self.options.method != "table":
            raise reader.error("table_resolution", reader.props["table_resolution"],
                               'only with method="table"')
        if self.options.method == "table":
            if self.options.energy_compensation:
                raise reader.error("method", "table", '"exact" with energy_compensation '
                                   "(EON has no table of the lecture's sin α tan β)")
            self.table = table_grid(self.options.table_resolution)

    def has_diffuse(self) -> bool:
        return not self.off("reflectance")

    def eval_textures(self, si, active) -> Inputs:
        sigma = self.m_sigma.eval_1(si, active)
        return Inputs(self.colour("reflectance", "diffuse", si, active), sigma,
                      eon_roughness(sigma))

    def eval_diffuse(self, inp, si, wo):
        if self.options.energy_compensation:       # EON: FON + the base's multiple scattering
            return fon(inp.colour_d, inp.r, si.wi, wo)
        cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
        if self.options.method == "table":
            sa_tb = self.table(cos_o, cos_i)
        else:
            sa_tb = sin_alpha_tan_beta(cos_i, cos_o)
        g = g_azimuth(si.wi, wo)
        return oren_nayar(inp.colour_d, inp.sigma, g, sa_tb, cos_o, self.options.mode)

    # --- energy compensation (EON) ------------------------------------------------
    def compensation(self) -> compensation.Compensation:
        # EON's rho_ms: rho enters as the paper defines it, not linearly
        return compensation.Analytic(
            albedo=lambda inp, v: 1.0 - fon_albedo(mi.Frame3f.cos_theta(v), inp.r),
            average=lambda inp: 1.0 - fon_albedo_average(inp.r),
            colour=lambda inp: compensation.ms_series(inp.colour_d, fon_albedo_average(inp.r)),
            lobe="diffuse")

    def describe(self) -> dict:
        fields = super().describe()
        if self.options.method != "table":
            del fields["table_resolution"]
        return fields

    # --- what runs of it: the tests, the validation report, the bench, the pictures ---
    @classmethod
    def cases(cls) -> Cases:
        on = {"type": "oren_nayar"}
        eon = {**on, "energy_compensation": True}
        return Cases(
            chi2=[Chi2({**on, "sigma": s, "method": m}, res=101, quick=s == 0.5)
                  for s, m in [(0.0, "exact"), (0.5, "table"), (HALF_PI, "exact")]]
            + [Chi2({**on, "sigma": 1.0, "mode": "scanline", "reflectance": rgb([2.0, 0.5, 0.1])},
                    (60,), res=101),
               Chi2({**eon, "sigma": 0.8, "reflectance": rgb([0.9, 0.5, 0.2])}, (0, 60), res=101)],
            consistency=[{**on, "sigma": 0.7}, {**on, "sigma": HALF_PI, "method": "table"},
                         {**on, "sigma": 0.4, "mode": "scanline", "reflectance": rgb([1.8, 0.6, 0.2])},
                         {**eon, "sigma": 1.2, "reflectance": rgb([0.9, 0.5, 0.2])}],
            furnace=[Furnace("σ = 0", {**on, "reflectance": 1.0, "sigma": 0.0}, lo=1.0, tol=0.01),
                     # the lecture's qualitative model: below 1 except near grazing at small σ
                     Furnace("σ = 0.2 (exceeds 1 near grazing: the model's own)",
                             {**on, "reflectance": 1.0, "sigma": 0.2}, hi=1.03),
                     Furnace("σ = π/2", {**on, "reflectance": 1.0, "sigma": HALF_PI})]
            + [preserves(f"EON, σ = {s:g}", {**eon, "reflectance": 1.0, "sigma": s})
               for s in (0.0, 0.2, 0.8, HALF_PI)],
            extremes=[{**on, "sigma": s, "method": m} for s in (0.0, HALF_PI)
                      for m in ("exact", "table")]
            + [{**eon, "sigma": s} for s in (0.0, HALF_PI)],
            interior=[{**on, "sigma": 0.4, "reflectance": 0.6, "method": m}
                      for m in ("exact", "table")]
            + [{**eon, "sigma": 0.4, "reflectance": 0.6}],
            reciprocity=[{**on, "sigma": s, "method": m, "reflectance": rgb([0.9, 0.5, 0.2])}
                         for m in ("exact", "table") for s in (0.3, 1.2)]
            + [{**eon, "sigma": s, "reflectance": rgb([0.9, 0.5, 0.2])} for s in (0.3, 1.2)],
            lobe={**on, "reflectance": 0.8, "sigma": 0.8},
            costs=[(f"oren_nayar {m}", {**on, "sigma": 0.5, "method": m}) for m in ("exact", "table")],
            energy=[("oren_nayar (EON)", {**on, "sigma": 0.8})],
            # the lecture's table against the exact formulas (the bench's oren_nayar group)
            variants=[("oren_nayar table vs exact", {**on, "sigma": 0.5, "reflectance": 0.8})],
            pictures=Pictures("sigma", (0.0, 0.5, 1.0, HALF_PI), {"reflectance": 0.8}),
            fits=[{"reflectance": [0.6, 0.35, 0.15], "sigma": 0.3},
                  {"reflectance": [0.2, 0.5, 0.7], "sigma": 0.8}],
            mitsuba=("diffuse", "principled"),
            checked="`diffuse` at σ = 0; EON's published listing",
        )
