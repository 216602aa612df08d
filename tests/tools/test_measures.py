"""The numbers the reports share, checked by hand."""
import numpy as np
import pytest

from mi_brdfs.tools import measures


def test_relmse_by_hand():
    r = np.array([0.0, 1.0])
    t = np.array([0.01, 1.5])
    assert measures.relmse(t, r) == pytest.approx((0.01**2 / 0.01**2 + 0.25 / 1.01**2) / 2)
    assert measures.relmse(r, r) == 0
    # a plain float, whatever the images' dtype (reports write it as JSON)
    assert type(measures.relmse(t.astype(np.float32), r.astype(np.float32))) is float
    # per row along an axis, as compare reports each channel
    rows = measures.relmse(np.stack([t, r]), np.stack([r, r]), axis=1)
    assert rows.tolist() == pytest.approx([(1.0 + 0.25 / 1.01**2) / 2, 0.0])


def test_pareto_by_hand():
    # (cost, error): b is dominated by a (dearer and worse); c and d trade off; e duplicates a.
    points = [(1.0, 0.1), (2.0, 0.2), (0.5, 0.5), (3.0, 0.01), (1.0, 0.1)]
    assert measures.pareto(points) == [True, False, True, True, True]
