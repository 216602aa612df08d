"""How much work a command does: one type for every command's sizes.

Each command that measures (``validate``, ``bench``, ``fit``) declares its
own fields in a subclass of :class:`Settings` and two instances of it:
``FULL`` (what the committed reports use) and ``QUICK`` (``--quick``: a smoke
test that every part runs, whose numbers are not measurements). A test or a
command that needs a variation takes ``FULL.replace(...)``; a report records
the settings it ran with as ``as_dict()``.
"""
from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class Settings:
    """A command's sizes (subclass with the fields, as a frozen dataclass)."""

    def replace(self, **changes) -> "Settings":
        """A copy with ``changes``; an unknown field is a TypeError."""
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)
