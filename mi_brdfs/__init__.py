"""mi_brdfs: the classic BRDF models of the course lecture as Mitsuba 3 plugins.

``import mi_brdfs`` finds a working LLVM for Dr.Jit (see ``_llvm``), activates
the ``llvm_ad_rgb`` variant if no variant is active, and registers every plugin
(the BSDFs and the ``scanline``/``hdr`` integrators) for the active variant. After switching variants, call ``mi_brdfs.register()``.
"""
from . import _llvm

_llvm.configure()            # must precede the first `import drjit`

import mitsuba as mi         # noqa: E402

_llvm.check()

from . import integrator, plugin   # noqa: E402
from .cook_torrance import CookTorrance   # noqa: E402
from .blinn import Blinn                  # noqa: E402
from .lambert import Lambert              # noqa: E402
from .oren_nayar import OrenNayar         # noqa: E402
from .phong import Phong                  # noqa: E402
from .toon import Toon                    # noqa: E402
from .ward import Ward                    # noqa: E402

# In the lecture's order: diffuse models, then specular ones.
PLUGINS = (Lambert, OrenNayar, Toon, Phong, Blinn, Ward, CookTorrance)
DEFAULT_VARIANT = "llvm_ad_rgb"

__all__ = ["register", "PLUGINS", "DEFAULT_VARIANT", "Lambert", "OrenNayar", "Toon", "Phong",
           "Blinn", "Ward", "CookTorrance"]


def register() -> str:
    """Register every plugin for the active variant (activating the default if
    none is active); returns the variant."""
    if mi.variant() is None:
        mi.set_variant(DEFAULT_VARIANT)
    for cls in PLUGINS:
        plugin.register_plugin(cls)
    integrator.register()
    return mi.variant()


register()
