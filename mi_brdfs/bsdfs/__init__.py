"""The course's BRDF models as Mitsuba BSDF plugins, one module per model.

- the models, in the lecture's order: :mod:`.lambert`, :mod:`.oren_nayar`,
  :mod:`.toon` (diffuse), :mod:`.phong`, :mod:`.blinn`, :mod:`.ward`,
  :mod:`.cook_torrance` (specular), and beside them :mod:`.ashikhmin_shirley`
  (anisotropic Phong, Ashikhmin & Shirley 2000); each declares what runs of it
  (:mod:`.cases`);
- what every plugin does alike: :mod:`.base` (the ``mi.BSDF`` glue: loading,
  parameters, ``traverse``, the lobes a scene requires, and the load-time
  hooks a model implements), :mod:`.mixture` (every traced step of the BSDF
  interface over the lobes, and the traced hooks), :mod:`.params` (declaring,
  reading and checking parameters), :mod:`.compensation` (the
  multiple-scattering lobe and its tables, shipped in ``data/``);
- the shared formulas: :mod:`.microfacet` (the distribution: D, G, sampling),
  :mod:`.fresnel` (F), :mod:`.powercos` (power-cosine lobes in float32),
  :mod:`.grid` (tabulated functions).
"""
from __future__ import annotations

from . import cases
from .ashikhmin_shirley import AshikhminShirley
from .base import register_plugin
from .blinn import Blinn
from .cook_torrance import CookTorrance
from .lambert import Lambert
from .oren_nayar import OrenNayar
from .phong import Phong
from .toon import Toon
from .ward import Ward

# The registry, in the lecture's order: diffuse models, then specular ones.
# Everything else derives from it and from each model's own module: the
# package's exports, the plugins registered with Mitsuba, the cases the tests,
# the validation report, the bench and the fit run (each model's cases()),
# the documentation (tests/bsdfs/test_registry.py says where a model is missing).
PLUGINS = (Lambert, OrenNayar, Toon, Phong, Blinn, Ward, CookTorrance, AshikhminShirley)
BY_NAME = {cls.name: cls for cls in PLUGINS}     # plugin name -> class
cases.use(BY_NAME)                               # every model's cases (cases.ALL, cases.of)

__all__ = ["PLUGINS", "BY_NAME", *(cls.__name__ for cls in PLUGINS)]


def register() -> None:
    """Register every BSDF plugin for the active variant."""
    for cls in PLUGINS:
        register_plugin(cls)
