r"""
``lambert`` — Lambert diffuse reflection
=========================================

.. parameters::

The lecture's BRDF for scan-line rendering, with d the light direction (``wo``)
and n the normal, returned as is by ``eval`` (it carries the cosine already);
in hdr mode the radiometric Lambert BRDF, times the cosine Mitsuba's ``eval``
includes:

.. math::

    \text{scanline:}\quad \texttt{eval} &= f_r =
        \operatorname{clamp}_{[0,1]}\big(m_D \max(0, d\cdot n)\big) \\
    \text{hdr:}\quad \texttt{eval} &= f_r \cos\theta_o, \qquad f_r = \frac{m_D}{\pi}

Sampling: cosine-weighted hemisphere. With ``reflectance`` 0 (a constant, not
differentiated, never updated) the plugin has no lobe at all. A viewer or light below the surface gets no reflection.

.. code-block:: xml

    <bsdf type="lambert">
        <rgb name="reflectance" value="0.8, 0.3, 0.2"/>
        <string name="mode" value="scanline"/>
    </bsdf>
"""
from __future__ import annotations

from typing import NamedTuple

import drjit as dr
import mitsuba as mi

from .base import BRDF
from .cases import Cases, Chi2, Furnace, Pictures, Twin, rgb
from .mixture import Scaled, Spectrum
from .params import Param


# ----------------------------------------------------------------------------
#  The formulas (cos_o = d·n, the light's cosine)
# ----------------------------------------------------------------------------

def eval_diffuse(m_d, cos_o, mode: str) -> Scaled:
    """The Lambert lobe in eval convention, as m_D times its shape: m_D·clamp(d·n)
    (scanline, the lecture's f_r) or m_D/pi·cos(theta_o) (hdr). Also the diffuse
    lobe of phong, blinn, ward and cook_torrance. In hdr mode, under the cosine
    sampling the base gives it, f/pdf is m_D: ``ratio`` 1, so a sample of this
    lobe alone weighs m_D exactly (as Mitsuba's ``diffuse``)."""
    if mode == "scanline":
        return Scaled(m_d, dr.fmax(cos_o, 0.0))
    return Scaled(m_d, dr.inv_pi * dr.fmax(cos_o, 0.0), 1.0)


def albedo(m_d, mode: str):
    """What eval_diffuse() reflects in all (hemispherical integral): m_D, or pi·m_D for the
    scan-line form, which has no 1/pi. The diffuse lobe's selection weight."""
    return m_d * (dr.pi if mode == "scanline" else 1.0)


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------

class Inputs(NamedTuple):
    """What one call evaluates at its point."""
    colour_d: Spectrum | None       # m_D, where the lobe is present


class Lambert(BRDF):
    __doc__ = __doc__                  # the module's documentation, for help()
    name = "lambert"
    PARAMS = (Param("reflectance", 0.5, doc="m_D, the diffuse colour; above 1 allowed "
                    "(scanline mode clamps the lobe to [0, 1])."),)

    def has_diffuse(self) -> bool:
        return not self.off("reflectance")

    def eval_textures(self, si, active) -> Inputs:
        return Inputs(self.colour("reflectance", "diffuse", si, active))

    def eval_diffuse(self, inp, si, wo):
        return eval_diffuse(inp.colour_d, mi.Frame3f.cos_theta(wo), self.options.mode)

    # --- what runs of it: the tests, the validation report, the bench, the pictures ---
    @classmethod
    def cases(cls) -> Cases:
        return Cases(
            chi2=[Chi2({"type": "lambert", "mode": m}, (0, 85), quick=m == "hdr")
                  for m in ("hdr", "scanline")],
            consistency=[{"type": "lambert"},
                         {"type": "lambert", "mode": "scanline", "reflectance": rgb([1.7, 0.6, 0.2])}],
            furnace=[Furnace("m_D = 1", {"type": "lambert", "reflectance": 1.0}, lo=1.0, hi=1.0,
                             tol=0.01)],
            extremes=[{"type": "lambert"}, {"type": "lambert", "reflectance": 0.0}],
            interior=[{"type": "lambert", "reflectance": 0.4}],
            lobe={"type": "lambert", "reflectance": 0.8},
            costs=[("lambert", {"type": "lambert", "reflectance": 0.6})],
            twins=[Twin("lambert vs diffuse", {"type": "lambert", "reflectance": 0.6},
                        {"type": "diffuse", "reflectance": 0.6},
                        floor={"type": "bench_floor_diffuse", "reflectance": 0.6},
                        spread=lambda t: {"reflectance": rgb([0.2 + 0.6 * t, 0.5, 0.8 - 0.6 * t])})],
            pictures=Pictures("reflectance", (0.2, 0.5, 0.8)),
            fits=[{"reflectance": [0.6, 0.35, 0.15]}, {"reflectance": [0.2, 0.5, 0.7]}],
            mitsuba=("diffuse",),
            checked="Mitsuba's `diffuse`, to float precision",
        )
