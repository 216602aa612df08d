"""Every plugin inside each of Mitsuba's adapters (``twosided``, ``mask``,
``bumpmap``, ``normalmap``, ``blendbsdf``), rendered inside ``dr.freeze``:
every frozen image is the plain render's, while values change between calls
and on another instance of the scene, and the function replays its
recording on both instances.

The scene is :func:`support.tiles_scene` with a tile per plugin and adapter,
35 in a row (the twosided ones turned over, so that their back is rendered),
textured where the adapter takes a texture (the bitmaps of
tests/scenes/assets), lit by point lights and a constant environment, and
rendered by the path tracer: the adapters' eval, pdf and sample of every
plugin are traced into one frozen kernel (virtual calls among the tiles).
"""
from __future__ import annotations

import gc
from pathlib import Path

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from mi_brdfs.bsdfs import BY_NAME
from mi_brdfs.render.frozen import warm_up
from support import (blend, floats, moved, neighbour, plugin_configs, tile, tiles_scene,
                     twosided)

ASSETS = Path(__file__).resolve().parents[1] / "scenes" / "assets"
SPP = 2


def bitmap(name: str, raw: bool = False) -> dict:
    return {"type": "bitmap", "filename": str(ASSETS / name), "raw": raw}


ADAPTERS = {
    # turned over: the back side is the one rendered
    "twosided": lambda config: twosided(moved(config), config),
    "mask": lambda config: {"type": "mask", "opacity": bitmap("mask.png"), "bsdf": config},
    "bumpmap": lambda config: {"type": "bumpmap", "height": bitmap("height.png", raw=True),
                               "bsdf": config},
    "normalmap": lambda config: {"type": "normalmap", "normalmap": bitmap("normals.png", raw=True),
                                 "bsdf": config},
    "blendbsdf": lambda config: blend(config, plugin_configs()[neighbour(config["type"])],
                                      weight=bitmap("weight.png")),
}


def scene_of() -> mi.Scene:
    """The tiles: every plugin (its configuration of plugin_configs) inside
    every adapter, the tile named adapter_plugin."""
    bsdfs = {f"{adapter}_{name}": wrap(config) for adapter, wrap in ADAPTERS.items()
             for name, config in plugin_configs().items()}
    scene = mi.load_dict(tiles_scene(bsdfs, {"type": "path", "max_depth": 3}, spp=SPP, env=0.3,
                                     backs=[name for name in bsdfs if name.startswith("twosided")]),
                         optimize=False)        # (optimised, equal BSDFs would be merged)
    warm_up(scene)            # what a first render sets up, traced before any recording
    return scene


def render(scene: mi.Scene) -> mi.TensorXf:
    return mi.render(scene, spp=SPP, seed=1)


def tile_names() -> list[str]:
    return [f"{adapter}_{name}" for adapter in ADAPTERS for name in BY_NAME]


def assert_lit_tiles(image: np.ndarray) -> None:
    for i, name in enumerate(tile_names()):
        assert tile(image, i).max() > 0.01, f"{name}: a black tile"


def recolour(scene: mi.Scene, factor: float) -> None:
    """Every colour of every BSDF of the scene (both sides, both blended BSDFs)
    times ``factor``, written as arrays in memory."""
    params = mi.traverse(scene)
    keys = [k for k in params.keys() if ".bsdf." in k and k.endswith("reflectance.value")]
    assert {k.split(".")[0] for k in keys} == set(tile_names())
    for key in keys:
        params[key] = floats(np.array(params[key]) * factor)
    params.update()


@pytest.fixture(autouse=True)
def collected():
    """Garbage collected before each test records: a frozen render traces
    every BSDF alive in the process (what earlier tests left), and Dr.Jit
    aborts when a frozen function (a failed test's) is freed during another's
    recording."""
    gc.collect()


@pytest.mark.parametrize("auto_opaque", [True, False], ids=["auto_opaque", "literal"])
def test_frozen_render_replays(auto_opaque):
    """Four calls on one instance of the scene, its colours changed before
    each but the first, then three on another instance: every frozen image is
    the plain render's, each differs from all before it, and the last calls
    on each instance replay. (How often Dr.Jit records before that is its
    own matter: the first value changes and a new instance record again.)"""
    frozen = dr.freeze(render, auto_opaque=auto_opaque)
    try:
        images, recordings, scenes = [], {}, []
        for instance, factors in (("first", [1.0, 0.9, 0.9, 0.9]), ("second", [0.6, 0.9, 0.9])):
            scene = scene_of()
            scenes.append(scene)        # alive while the function is (its recordings use it)
            for i, factor in enumerate(factors):
                if factor != 1.0:
                    recolour(scene, factor)
                image = np.array(frozen(scene))
                np.testing.assert_allclose(image, np.array(render(scene)), rtol=1e-5, atol=1e-6,
                                           err_msg=f"{instance} instance, call {i}")
                assert_lit_tiles(image)
                assert all(not np.allclose(image, earlier, rtol=1e-3) for earlier in images)
                images.append(image)
                recordings[instance, i] = frozen.n_recordings
            last = len(factors) - 1
            assert recordings[instance, last] == recordings[instance, last - 1], recordings
    finally:
        del frozen, scenes
