"""Writes the small files the test scenes of this folder load (assets/):
meshes with shading normals in both of Mitsuba's mesh formats, bitmaps for
textured parameters and adapters, an environment map. Deterministic; the
files are committed, so that the scenes load as a user's scene does, by
relative path. Re-run after a change: ``python tests/scenes/make_assets.py``.

- ``sphere.obj``: a UV sphere (radius 1, 8 x 16 facets) with texture
  coordinates and smooth vertex normals (``vn``), the shading normals.
- ``torus.ply``: a torus (radii 1 and 0.35, 8 x 16 facets) with vertex
  normals and texture coordinates, written by Mitsuba's PLY writer.
- ``checker.png``: an 8 x 8 checker of two colours (a reflectance).
- ``weight.png``, ``mask.png``, ``height.png``: one channel each (a blend
  weight, an opacity with a fully transparent half, a bump height field).
- ``normals.png``: a normal map (unit normals tilted by up to ~25 degrees,
  stored as n/2 + 1/2, 8 bits).
- ``sky.exr``: a 32 x 16 latitude-longitude environment, a bright sky over a
  darker ground with a warm sun spot.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

import mi_brdfs  # noqa: F401  (LLVM set-up and variant)
import mitsuba as mi
from mi_brdfs._jit import from_numpy

ASSETS = Path(__file__).resolve().parent / "assets"


def grid(n_theta: int, n_phi: int):
    """(u, v) in [0, 1]² on a (n_theta + 1) x (n_phi + 1) vertex grid, and
    the two triangles of each cell as vertex indices."""
    u, v = np.meshgrid(np.linspace(0, 1, n_phi + 1), np.linspace(0, 1, n_theta + 1))
    i, j = np.meshgrid(np.arange(n_theta), np.arange(n_phi), indexing="ij")
    a = (i * (n_phi + 1) + j).ravel()
    b, c, d = a + 1, a + n_phi + 1, a + n_phi + 2
    faces = np.concatenate([np.stack([a, c, b], 1), np.stack([b, c, d], 1)])
    return u.ravel(), v.ravel(), faces


def sphere_obj(path: Path, n_theta: int = 8, n_phi: int = 16) -> None:
    u, v, faces = grid(n_theta, n_phi)
    theta, phi = v * np.pi, u * 2 * np.pi
    n = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1)
    lines = [f"v {x:.5f} {y:.5f} {z:.5f}" for x, y, z in n]
    lines += [f"vt {s:.5f} {t:.5f}" for s, t in zip(u, v)]
    lines += [f"vn {x:.5f} {y:.5f} {z:.5f}" for x, y, z in n]
    lines += ["f " + " ".join(f"{k + 1}/{k + 1}/{k + 1}" for k in face) for face in faces]
    path.write_text("\n".join(lines) + "\n")


def torus_ply(path: Path, n_theta: int = 8, n_phi: int = 16, r: float = 0.35) -> None:
    u, v, faces = grid(n_theta, n_phi)
    phi, theta = u * 2 * np.pi, v * 2 * np.pi
    n = np.stack([np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi), np.sin(theta)], 1)
    p = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], 1) + r * n
    mesh = mi.Mesh("torus", len(p), len(faces), has_vertex_normals=True,
                   has_vertex_texcoords=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = from_numpy(mi.Float, p.ravel())
    params["vertex_normals"] = from_numpy(mi.Float, n.ravel())
    params["vertex_texcoords"] = from_numpy(mi.Float, np.stack([u, v], 1).ravel())
    params["faces"] = from_numpy(mi.UInt32, faces.ravel())
    params.update()
    mesh.write_ply(str(path))


def png(path: Path, value: np.ndarray) -> None:
    """An 8-bit PNG of values in [0, 1] (sRGB-encoded by Mitsuba's writer)."""
    mi.Bitmap(np.ascontiguousarray(value, dtype=np.float32)).convert(
        component_format=mi.Struct.Type.UInt8, srgb_gamma=False).write(str(path))


def main() -> None:
    ASSETS.mkdir(exist_ok=True)
    sphere_obj(ASSETS / "sphere.obj")
    torus_ply(ASSETS / "torus.ply")
    i, j = np.meshgrid(np.arange(32), np.arange(32), indexing="ij")
    check = ((i // 4 + j // 4) % 2)[..., None]
    png(ASSETS / "checker.png", np.where(check, [0.8, 0.5, 0.2], [0.2, 0.45, 0.7]))
    png(ASSETS / "weight.png", (0.15 + 0.7 * j / 31.0)[..., None])
    png(ASSETS / "mask.png", np.where(j < 16, 0.0, 0.5 + 0.5 * (i / 31.0))[..., None])
    png(ASSETS / "height.png", (0.5 + 0.5 * np.sin(i / 2.0) * np.cos(j / 3.0))[..., None])
    tilt = 0.45 * np.stack([np.sin(i / 3.0), np.cos(j / 4.0)], -1)
    n = np.dstack([tilt, np.ones((32, 32))])
    png(ASSETS / "normals.png", 0.5 * n / np.linalg.norm(n, axis=-1, keepdims=True) + 0.5)
    y, x = np.meshgrid(np.arange(16), np.arange(32), indexing="ij")
    sky = np.where((y < 8)[..., None], [0.6, 0.75, 1.0], [0.25, 0.2, 0.15])
    sun = np.exp(-((x - 10) ** 2 + (y - 4) ** 2) / 3.0)[..., None] * [8.0, 6.0, 3.0]
    mi.Bitmap((sky + sun).astype(np.float32)).write(str(ASSETS / "sky.exr"))
    for p in sorted(ASSETS.iterdir()):
        print(f"{p.name}: {p.stat().st_size} bytes")


if __name__ == "__main__":
    main()
