"""The bundled scenes (``mi_brdfs.scenes``): the XML files beside this module.

In the source tree they live in ``scenes/``; setuptools' ``package-dir`` maps
that folder to this package, so a plain install carries them and
``mi-brdfs render course`` finds one by name from any folder.
"""
from __future__ import annotations

from pathlib import Path

DIRECTORY = Path(__file__).resolve().parent


def names() -> list[str]:
    """The bundled scenes' names (file names without ``.xml``), sorted."""
    return sorted(p.stem for p in DIRECTORY.glob("*.xml"))


def path(name: str) -> Path | None:
    """The file of the bundled scene ``name`` (``course`` or ``course.xml``), or None."""
    stem = name[:-4] if name.endswith(".xml") else name
    return DIRECTORY / f"{stem}.xml" if stem in names() else None
