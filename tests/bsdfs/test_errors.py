"""Bad input raises a clear error at load time: plugin, parameter, value, valid range."""
import re

import pytest

import mitsuba as mi

CASES = [
    ({"type": "cook_torrance", "alpha": -0.1}, "cook_torrance", "alpha", "-0.1", "[0, inf]"),
    ({"type": "cook_torrance", "alpha": {"type": "checkerboard", "color0": -0.5}},
     "cook_torrance", "alpha", "-0.5", "[0, inf]"),
    ({"type": "cook_torrance", "distribution": "blinn", "alpha": 1.5},
     "cook_torrance", "alpha", "1.5", "[0, 1]"),
    ({"type": "cook_torrance", "k": 1.5}, "cook_torrance", "k", "1.5", "[0, 1]"),
    ({"type": "cook_torrance", "k": -0.01}, "cook_torrance", "k", "-0.01", "[0, 1]"),
    ({"type": "cook_torrance", "f0": 2.0}, "cook_torrance", "f0", "2.0", "[0, 1]"),
    ({"type": "cook_torrance", "f0": float("nan")}, "cook_torrance", "f0", "nan", "[0, 1]"),
    ({"type": "cook_torrance", "distribution": "phong"}, "cook_torrance", "distribution",
     "'phong'", '"blinn", "beckmann", "ggx"'),
    ({"type": "cook_torrance", "geometry": "kelemen"}, "cook_torrance", "geometry",
     "'kelemen'", '"cook_torrance", "smith"'),
    ({"type": "cook_torrance", "mode": "ldr"}, "cook_torrance", "mode", "'ldr'", '"scanline", "hdr"'),
    ({"type": "lambert", "mode": "HDR"}, "lambert", "mode", "'HDR'", '"scanline", "hdr"'),
    ({"type": "lambert", "reflectance": {"type": "rgb", "value": [-1, 0, 0]}},
     "lambert", "reflectance", "-1.0", "[0, inf]"),
    ({"type": "cook_torrance", "specular_reflectance": -2.0},
     "cook_torrance", "specular_reflectance", "-2.0", "[0, inf]"),
]


@pytest.mark.parametrize("config, plugin, name, value, valid", CASES,
                         ids=[f"{c[1]}-{c[2]}-{c[3]}" for c in CASES])
def test_bad_input_names_plugin_parameter_value_and_range(config, plugin, name, value, valid):
    with pytest.raises(Exception) as info:
        mi.load_dict(config)
    last = str(info.value).strip().splitlines()[-1]
    assert re.search(rf"{plugin}: parameter '{name}' = {re.escape(value)} is invalid", last), last
    assert valid in last, last


def test_unknown_parameter_is_refused():
    with pytest.raises(Exception, match="unreferenced property.*\n.*colour"):
        mi.load_dict({"type": "lambert", "colour": 0.3})


@pytest.mark.parametrize("config", [
    {"type": "lambert", "reflectance": {"type": "rgb", "value": [3.0, 1.5, 0.0]}},
    {"type": "cook_torrance", "alpha": 0.0},
    {"type": "cook_torrance", "alpha": 1e-9, "distribution": "ggx"},
    {"type": "cook_torrance", "alpha": 4.0, "distribution": "ggx"},
    {"type": "cook_torrance", "k": 0.0, "f0": 0.0},
    {"type": "cook_torrance", "k": 1.0, "f0": 1.0},
])
def test_edge_values_are_accepted(config):
    mi.load_dict(config)
