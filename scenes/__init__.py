"""The bundled scenes (``mi_brdfs.scenes``): the XML files beside this module.

In the source tree they live in ``scenes/``; setuptools' ``package-dir`` maps
that folder to this package, so a plain install carries them, ``mi-brdfs
render course`` finds one by name from any folder, and so does Python::

    import mi_brdfs
    import mitsuba as mi

    scene = mi.load_file(mi_brdfs.scenes.path("phong"), mode="scanline")

``mi-brdfs scenes`` lists them, as :func:`names` does.
"""
from __future__ import annotations

from pathlib import Path

DIRECTORY = Path(__file__).resolve().parent


def names() -> list[str]:
    """The bundled scenes' names (file names without ``.xml``), sorted."""
    return sorted(p.stem for p in DIRECTORY.glob("*.xml"))


def path(name: str) -> str:
    """The absolute path of the bundled scene ``name`` (``"course"`` or
    ``"course.xml"``), as a string ``mi.load_file`` takes. ValueError for a
    name that is not a bundled scene, listing the ones there are."""
    stem = name[:-4] if name.endswith(".xml") else name
    if stem not in names():
        raise ValueError(f"no bundled scene {name!r}; bundled scenes: {', '.join(names())}")
    return str(DIRECTORY / f"{stem}.xml")
