"""The configurations the validation report and the benchmarks run, in one place.

Each entry is a plugin dictionary without ``mode`` (both modes are run) and a
short label. Colours are white (1) where energy is measured, so the albedo
is the fraction of light reflected.
"""
from __future__ import annotations

# White furnace: one or more white configurations per model.
FURNACE: dict[str, list[tuple[str, dict]]] = {
    "lambert": [("m_D = 1", {"type": "lambert", "reflectance": 1.0})],
    "cook_torrance": [
        ("GGX, Smith, alpha = 1, k = 0, F0 = 1",
         {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "alpha": 1.0,
          "k": 0.0, "f0": 1.0, "specular_reflectance": 1.0}),
        ("Blinn D, Smith (Blinn G1), alpha = 1, k = 0, F0 = 1",
         {"type": "cook_torrance", "distribution": "blinn", "geometry": "smith", "alpha": 1.0,
          "k": 0.0, "f0": 1.0, "specular_reflectance": 1.0}),
        ("Beckmann, V-cavity, alpha = 0.3, k = 0.5, F0 = 1",
         {"type": "cook_torrance", "distribution": "beckmann", "alpha": 0.3, "k": 0.5,
          "f0": 1.0, "diffuse_reflectance": 1.0, "specular_reflectance": 1.0}),
    ],
    "oren_nayar": [
        ("sigma = 0.2", {"type": "oren_nayar", "reflectance": 1.0, "sigma": 0.2}),
        ("sigma = pi/2", {"type": "oren_nayar", "reflectance": 1.0, "sigma": 1.5707963}),
    ],
    "phong": [
        ("m_D = 0, m_S = 1, gamma = 1",
         {"type": "phong", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0, "exponent": 1}),
        ("m_D = 0.5, m_S = 0.5, gamma = 50",
         {"type": "phong", "diffuse_reflectance": 0.5, "specular_reflectance": 0.5, "exponent": 50}),
    ],
    "blinn": [
        ("m_D = 0, m_S = 1, gamma = 10",
         {"type": "blinn", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0, "exponent": 10}),
    ],
    "ward": [
        ("m_S = 1, alpha 0.2 x 0.2",
         {"type": "ward", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0, "alpha": 0.2}),
    ],
    "toon": [("defaults", {"type": "toon"})],
}

# Sampling: (label, config, incident angles in degrees) per model.
CHI2: dict[str, list[tuple[str, dict, tuple[float, ...]]]] = {
    "lambert": [("m_D = 0.5", {"type": "lambert"}, (0, 45, 85))],
    "cook_torrance": [
        (f"{d}, alpha = {a}, k = {k}",
         {"type": "cook_torrance", "distribution": d, "alpha": a, "k": k}, (0, 45, 85))
        for d in ("blinn", "beckmann", "ggx") for a in (0.1, 0.5) for k in (0.0, 0.5)
    ],
    "oren_nayar": [("sigma = 0.5", {"type": "oren_nayar", "sigma": 0.5}, (0, 45, 85))],
    "phong": [(f"gamma = {g}", {"type": "phong", "exponent": g}, (0, 45, 85)) for g in (10, 200)],
    "blinn": [(f"gamma = {g}", {"type": "blinn", "exponent": g}, (0, 45, 85)) for g in (10, 200)],
    "ward": [("alpha 0.05 x 0.3", {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3}, (0, 45, 85))],
    "toon": [("defaults", {"type": "toon"}, (0, 45, 85))],
}

# Lobe plots: one representative, readable configuration per model.
LOBES: dict[str, dict] = {
    "lambert": {"type": "lambert", "reflectance": 0.8},
    "oren_nayar": {"type": "oren_nayar", "reflectance": 0.8, "sigma": 0.8},
    "toon": {"type": "toon", "smoothness": 0.1},
    "phong": {"type": "phong", "diffuse_reflectance": 0.3, "specular_reflectance": 0.6,
              "exponent": 30},
    "blinn": {"type": "blinn", "diffuse_reflectance": 0.3, "specular_reflectance": 0.6,
              "exponent": 30},
    "ward": {"type": "ward", "diffuse_reflectance": 0.3, "specular_reflectance": 0.6,
             "alpha_u": 0.1, "alpha_v": 0.3},
    "cook_torrance": {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3, "k": 0.3,
                      "f0": 0.5, "diffuse_reflectance": 0.8},
}


def quick(entries: dict, n: int = 1) -> dict:
    """The first n configurations of each model (for --quick runs)."""
    return {name: configs[:n] for name, configs in entries.items()}


def toon_ramp(colours) -> dict:
    """A 1-D ramp texture (one pixel high, left = cosine -1, right = +1)."""
    import mitsuba as mi
    import numpy as np
    data = np.asarray(colours, dtype=np.float32)[None, :, :]
    return {"type": "bitmap", "bitmap": mi.Bitmap(data), "wrap_mode": "clamp",
            "filter_type": "bilinear", "raw": True}


def bench_models() -> list[tuple[str, dict]]:
    """Every model and variant whose render cost is compared (name, config)."""
    return [
        ("lambert", {"type": "lambert", "reflectance": 0.6}),
        ("oren_nayar exact", {"type": "oren_nayar", "sigma": 0.5, "method": "exact"}),
        ("oren_nayar table", {"type": "oren_nayar", "sigma": 0.5, "method": "table"}),
        ("toon", {"type": "toon"}),
        ("toon with ramps", {"type": "toon",
                             "diffuse_ramp": toon_ramp([[0.1] * 3, [0.1] * 3, [0.4] * 3, [0.8] * 3]),
                             "specular_ramp": toon_ramp([[0.0] * 3] * 7 + [[1.0] * 3])}),
        ("phong", {"type": "phong", "exponent": 50}),
        ("blinn", {"type": "blinn", "exponent": 50}),
        *[(f"cook_torrance {d} {g}",
           {"type": "cook_torrance", "distribution": d, "geometry": g, "alpha": 0.3})
          for d in ("blinn", "beckmann", "ggx") for g in ("cook_torrance", "smith")],
        ("ward vectors", {"type": "ward", "alpha_u": 0.1, "alpha_v": 0.3, "formula": "vectors"}),
        ("ward angles", {"type": "ward", "alpha_u": 0.1, "alpha_v": 0.3, "formula": "angles"}),
    ]


# Sampling strategies per glossy lobe: (name, config, [(strategy, options), ...]);
# the first strategy is the plugin's default.
BENCH_SAMPLING: list[tuple[str, dict, list[tuple[str, dict]]]] = [
    *[(f"phong gamma {g}",
       {"type": "phong", "exponent": g, "diffuse_reflectance": 0.0, "specular_reflectance": 0.9},
       [("lobe", {}), ("cosine", {"sampling": "cosine"})])
      for g in (10, 100, 1000)],
    *[(f"cook_torrance ggx alpha {a}",
       {"type": "cook_torrance", "distribution": "ggx", "alpha": a, "k": 0.0, "f0": 0.9},
       [("visible normals", {}), ("full distribution", {"sample_visible": False}),
        ("cosine", {"sampling": "cosine"})])
      for a in (0.05, 0.3)],
    ("ward anisotropic 0.05 x 0.3",
     {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3, "diffuse_reflectance": 0.0,
      "specular_reflectance": 0.9},
     [("lobe", {}), ("cosine", {"sampling": "cosine"})]),
]
