"""The course's BRDF models as Mitsuba BSDF plugins, one module per model.

- :mod:`.base` — what every plugin does alike (parameters, modes, lobes, sampling);
- the models, in the lecture's order: :mod:`.lambert`, :mod:`.oren_nayar`,
  :mod:`.toon` (diffuse), :mod:`.phong`, :mod:`.blinn`, :mod:`.ward`,
  :mod:`.cook_torrance` (specular);
- the shared formulas: :mod:`.microfacet` (D, F, G), :mod:`.powercos`
  (power-cosine lobes in float32), :mod:`.energy` (energy compensation and
  its albedo tables, shipped in ``data/``), :mod:`.grid` (tabulated functions).
"""
from __future__ import annotations

from .base import register_plugin
from .blinn import Blinn
from .cook_torrance import CookTorrance
from .lambert import Lambert
from .oren_nayar import OrenNayar
from .phong import Phong
from .toon import Toon
from .ward import Ward

# The registry, in the lecture's order: diffuse models, then specular ones.
# Everything else derives from it: the package's exports, the plugins
# registered with Mitsuba, the catalog's entries (tools/catalog.py), the lobe
# plots, the bench's models and the tests (tests/bsdfs/test_registry.py says
# where a model is missing).
PLUGINS = (Lambert, OrenNayar, Toon, Phong, Blinn, Ward, CookTorrance)
BY_NAME = {cls.name: cls for cls in PLUGINS}     # plugin name -> class

__all__ = ["PLUGINS", "BY_NAME", *(cls.__name__ for cls in PLUGINS)]


def register() -> None:
    """Register every BSDF plugin for the active variant."""
    for cls in PLUGINS:
        register_plugin(cls)
