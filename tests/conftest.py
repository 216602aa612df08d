"""Shared fixtures; the helpers live in support.py (one place for every test module)."""
import numpy as np
import pytest

import mi_brdfs  # noqa: F401  (LLVM set-up, variant, plugin registration)
from support import evaluate, random_hemisphere, surface, vec  # noqa: F401  (for older modules)


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
