"""mi_brdfs: the classic BRDF models of the course lecture as Mitsuba 3 plugins.

``import mi_brdfs`` finds a working LLVM for Dr.Jit (see ``_llvm``), activates
the ``llvm_ad_rgb`` variant if no variant is active, and registers every plugin
(the BSDFs and the ``scanline`` and ``course`` integrators) for the active variant.
After switching variants, call ``mi_brdfs.register()``.

Layout: :mod:`mi_brdfs.bsdfs` (the plugins and their shared formulas),
:mod:`mi_brdfs.render` (integrator, passes, tone mapping, image I/O),
:mod:`mi_brdfs.tools` (the command line and its reports),
:mod:`mi_brdfs.scenes` (the bundled scenes: ``mi_brdfs.scenes.path("phong")``). The tools are also
reachable as ``mi_brdfs.compare``, ``.validate``, ``.bench`` and ``.analysis``
(imported on first use).
"""
import importlib

from . import _llvm

_llvm.configure()            # must precede the first `import drjit`

import mitsuba as mi         # noqa: E402

_llvm.check()

from . import bsdfs                       # noqa: E402
from .bsdfs import *                      # noqa: E402,F401,F403  (PLUGINS and every plugin class)
from .render import integrator            # noqa: E402
from . import scenes                      # noqa: E402  (the bundled scenes: scenes.path("phong"))

DEFAULT_VARIANT = "llvm_ad_rgb"
TOOLS = ("compare", "validate", "bench", "analysis", "cli")

__all__ = ["register", "scenes", "PLUGINS", "DEFAULT_VARIANT",
           *(cls.__name__ for cls in bsdfs.PLUGINS), *TOOLS]


def register() -> str:
    """Register every plugin for the active variant (activating the default if
    none is active); returns the variant."""
    if mi.variant() is None:
        mi.set_variant(DEFAULT_VARIANT)
    bsdfs.register()
    integrator.register()
    return mi.variant()


def __getattr__(name: str):
    """``mi_brdfs.compare`` and the other tools, imported on first use (their
    dependencies are not needed to use the plugins)."""
    if name in TOOLS:
        return importlib.import_module(f".tools.{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


register()
