"""Plain-Python plugin classes bound onto the active variant's Mitsuba base class.

Mitsuba's classes differ per variant (``mi.BSDF`` of ``llvm_ad_rgb`` is not that
of ``scalar_rgb``) and nanobind allows a single base, so each plain-Python
class of a plugin hierarchy is re-created on top of the variant's base class
the first time it is registered for that variant. Used by the BSDFs
(:mod:`mi_brdfs.bsdfs`) and the integrators (:mod:`mi_brdfs.render`).

Zero-argument ``super()`` works in the re-created classes: a method that uses
it refers to its class through a closure cell (``__class__``), which the copy
gets anew, holding the re-created class.
"""
from __future__ import annotations

import types

import mitsuba as mi

_bound: dict[tuple[str, type], type] = {}


def _rebind(value, old: type, new: type):
    """``value`` (a class attribute) for the class ``new`` re-created from ``old``:
    a function whose ``__class__`` cell holds ``old`` is copied with a fresh
    cell holding ``new`` (also inside a staticmethod, classmethod or property)."""
    if isinstance(value, (staticmethod, classmethod)):
        return type(value)(_rebind(value.__func__, old, new))
    if isinstance(value, property):
        return property(*(f if f is None else _rebind(f, old, new)
                          for f in (value.fget, value.fset, value.fdel)), value.__doc__)
    if not isinstance(value, types.FunctionType) or "__class__" not in value.__code__.co_freevars:
        return value
    cells = tuple(types.CellType(new) if name == "__class__" and cell.cell_contents is old
                  else cell for name, cell in zip(value.__code__.co_freevars, value.__closure__))
    copy = types.FunctionType(value.__code__, value.__globals__, value.__name__,
                              value.__defaults__, cells)
    copy.__kwdefaults__, copy.__dict__ = value.__kwdefaults__, dict(value.__dict__)
    copy.__doc__, copy.__qualname__ = value.__doc__, value.__qualname__
    return copy


def bind(cls: type, root: str = "BSDF") -> type:
    """The class ``cls`` rebuilt on top of the active variant's ``mi.<root>``."""
    key = (mi.variant(), cls)
    if key not in _bound:
        base = getattr(mi, root) if cls.__base__ is object else bind(cls.__base__, root)
        body = {k: v for k, v in vars(cls).items() if k not in ("__dict__", "__weakref__")}
        new = type(cls.__name__, (base,), body)
        for name, value in body.items():
            rebound = _rebind(value, cls, new)
            if rebound is not value:
                setattr(new, name, rebound)
        _bound[key] = new
    return _bound[key]


def create(plugin: str, values: dict):
    """A Mitsuba plugin made from flat ``values`` by the plugin manager, as
    the scene loader makes each object: for use inside a plugin's constructor.

    Not ``mi.load_dict`` there: Mitsuba loads a scene's objects in worker
    threads (``parallel=True``, the default of ``mi.load_file`` and
    ``mi.load_dict``), and a nested call of the loader from one of them
    corrupted another thread's object now and then (measured: 5 of 60 fresh
    processes loading scenes/course.xml failed in a C++ plugin, "failed to
    instantiate film plugin of type hdrfilm: basic_string::_M_create" or
    std::bad_alloc; 0 of 80 with this function; 0 of 80 with built-in
    plugins only, or with a bare Python BSDF)."""
    props = mi.Properties(plugin)
    for key, value in values.items():
        props[key] = value
    return mi.PluginManager.instance().create_object(props)
