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
        ("Beckmann, V-cavity, alpha = 0.3, k = 0.5, F0 = 1",
         {"type": "cook_torrance", "distribution": "beckmann", "alpha": 0.3, "k": 0.5,
          "f0": 1.0, "diffuse_reflectance": 1.0, "specular_reflectance": 1.0}),
    ],
}

# Sampling: (label, config, incident angles in degrees) per model.
CHI2: dict[str, list[tuple[str, dict, tuple[float, ...]]]] = {
    "lambert": [("m_D = 0.5", {"type": "lambert"}, (0, 45, 85))],
    "cook_torrance": [
        (f"{d}, alpha = {a}, k = {k}",
         {"type": "cook_torrance", "distribution": d, "alpha": a, "k": k}, (0, 45, 85))
        for d in ("blinn", "beckmann", "ggx") for a in (0.1, 0.5) for k in (0.0, 0.5)
    ],
}

# Lobe plots: one representative, readable configuration per model.
LOBES: dict[str, dict] = {
    "lambert": {"type": "lambert", "reflectance": 0.8},
    "cook_torrance": {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3, "k": 0.3,
                      "f0": 0.5, "diffuse_reflectance": 0.8},
}


def quick(entries: dict, n: int = 1) -> dict:
    """The first n configurations of each model (for --quick runs)."""
    return {name: configs[:n] for name, configs in entries.items()}


# Benchmarks: every model and variant whose cost is compared (name, config).
BENCH_MODELS: list[tuple[str, dict]] = [
    ("lambert", {"type": "lambert", "reflectance": 0.6}),
    *[(f"cook_torrance {d} {g}",
       {"type": "cook_torrance", "distribution": d, "geometry": g, "alpha": 0.3})
      for d in ("blinn", "beckmann", "ggx") for g in ("cook_torrance", "smith")],
    ("ward vectors", {"type": "ward", "alpha_u": 0.1, "alpha_v": 0.3, "formula": "vectors"}),
    ("ward angles", {"type": "ward", "alpha_u": 0.1, "alpha_v": 0.3, "formula": "angles"}),
]

# Sampling strategies per glossy lobe: (name, config, [(strategy, options), ...]);
# the first strategy is the plugin's default.
BENCH_SAMPLING: list[tuple[str, dict, list[tuple[str, dict]]]] = [
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
