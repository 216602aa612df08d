"""Mitsuba's variant fixtures, under Mitsuba's names, for the ported tests.

On a CPU machine Mitsuba's groups ``variants_vec_backends_once_rgb``,
``variants_vec_rgb`` and ``variants_all_ad_rgb`` are all ``llvm_ad_rgb``
(the wheel has no non-AD LLVM variant); ``cuda_ad_rgb`` joins them where a
GPU exists. Each fixture activates its variant, registers the plugins for
it and restores the previous variant and Dr.Jit's flags afterwards.
"""
import drjit as dr
import pytest

from support import active_variant

VEC_RGB = ["llvm_ad_rgb"] + (["cuda_ad_rgb"] if dr.has_backend(dr.JitBackend.CUDA) else [])


@pytest.fixture
def variant_scalar_rgb():
    with active_variant("scalar_rgb") as name:
        yield name


def _vectorized(request):
    with active_variant(request.param) as name:
        yield name


variants_vec_rgb = pytest.fixture(params=VEC_RGB, name="variants_vec_rgb")(_vectorized)
variants_vec_backends_once_rgb = pytest.fixture(
    params=VEC_RGB, name="variants_vec_backends_once_rgb")(_vectorized)
variants_all_ad_rgb = pytest.fixture(params=VEC_RGB, name="variants_all_ad_rgb")(_vectorized)
