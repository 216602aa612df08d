"""The ground truth of microfacet multiple scattering: a random walk on a
Smith microsurface (Heitz, Hanika, d'Eon & Dachsbacher 2016, "Multiple-
Scattering Microfacet BSDFs with the Smith Model", ACM TOG 35(4)), GGX and
Beckmann, isotropic or anisotropic, with Schlick's Fresnel at every bounce.

- :mod:`.microsurface`: the surface — projected area, Smith's Λ, D,
  visible normals (their density and sampling), the height-correlated single
  scattering; roughness one α or an :class:`Alpha` pair (α_x along s, α_y along t);
- :mod:`.walk`: the walk — :func:`walk`, the albedo W (:func:`albedo`, any
  viewer azimuth), the BRDF by next-event estimation (:func:`brdf`), the
  energy tables' W (:func:`table`, for ``python -m mi_brdfs.tools.tables``);
- :mod:`.report`: what is measured against it — the reference albedos
  (``tests/bsdfs/walk_reference.json``; for anisotropic roughness
  ``tests/bsdfs/walk_reference_anisotropic.json``), the compensated plugins' residuals,
  BRDF slices, the validation report's section (:func:`report_section`);
- :mod:`.pairs`: the walk's BRDF at pairs of directions against
  ``cook_torrance``'s directional lobe (``tests/bsdfs/walk_reference_directional.json``:
  the walk at grazing pairs and the L1 over the hemisphere of pairs);
- :mod:`.command`: the command line::

    python -m mi_brdfs.tools.groundtruth -o tests/bsdfs/walk_reference.json   # reference albedos
    python -m mi_brdfs.tools.groundtruth --roughness anisotropic \
        -o tests/bsdfs/walk_reference_anisotropic.json                     # (theta, phi, alpha_u, alpha_v, F0)
    python -m mi_brdfs.tools.groundtruth --directional \
        -o tests/bsdfs/walk_reference_directional.json                     # the BRDF at pairs (.pairs)
    python -m mi_brdfs.tools.groundtruth --reference FILE --residuals  # compensation vs the walk
    python -m mi_brdfs.tools.groundtruth --reference FILE --agreement  # FILE vs a new walk
    python -m mi_brdfs.tools.groundtruth --slices          # BRDF slices vs the walk
    python -m mi_brdfs.tools.groundtruth --decomposition   # separable, height-correlated, k >= 2
    python -m mi_brdfs.tools.groundtruth --anisotropic     # W for anisotropic roughness

Example::

    albedo("ggx", mu, 0.3, f0s=(1.0, 0.5))                      # W(μ) per F0
    albedo("ggx", mu, Alpha(0.05, 0.3), f0s=(0.5,), phi=phi)   # anisotropic, viewer azimuth φ
    brdf("beckmann", wi, wo, Alpha(0.1, 1.0), f0=0.6)          # f·cos θ_o

Needs SciPy (the ``reports`` extra).
"""
from .microsurface import (DISTRIBUTIONS, Alpha, d, d_visible, fresnel, lam, projected_area,
                           sample_visible, single_scattering)
from .report import (RESIDUAL_BOUND, compensated_albedo, grazing_difference, reference,
                     reference_agreement,
                     reference_anisotropic, report_html, report_section, residuals,
                     residuals_anisotropic, slice_difference)
from .walk import MAX_ORDER, MU_MIN, WALK_SEED, albedo, brdf, directions, table, walk

__all__ = ["DISTRIBUTIONS", "MAX_ORDER", "MU_MIN", "WALK_SEED", "RESIDUAL_BOUND", "Alpha",
           "albedo", "brdf", "d", "d_visible", "directions", "fresnel", "lam", "projected_area",
           "sample_visible", "single_scattering", "table", "walk", "compensated_albedo",
           "reference", "reference_agreement", "reference_anisotropic", "report_html",
           "report_section", "residuals", "residuals_anisotropic", "slice_difference",
           "grazing_difference"]
