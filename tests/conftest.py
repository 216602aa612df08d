"""Shared fixtures; the helpers live in support.py (one place for every test module)."""
import os

import numpy as np
import pytest

import mi_brdfs  # noqa: F401  (LLVM set-up, variant, plugin registration)
from support import BrokenCases

# A command a test runs in a subprocess (mi-brdfs validate, render, ...) that
# dies by a signal prints its Python traceback on its stderr, which the test's
# failure message shows: a crash names the line it happened at.
os.environ.setdefault("PYTHONFAULTHANDLER", "1")


@pytest.hookimpl(tryfirst=True)
def pytest_pyfunc_call(pyfuncitem):
    """A case standing for a model whose cases could not be built fails, with
    that entry's error (see test_battery.from_entries)."""
    for value in pyfuncitem.funcargs.values():
        if isinstance(value, BrokenCases):
            raise RuntimeError(f"the cases of {value.name} cannot be built: "
                               f"{type(value.error).__name__}: {value.error}") from value.error


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
