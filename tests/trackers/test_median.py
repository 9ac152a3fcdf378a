"""The one fast median (trackers.median): np.median's numbers."""

import numpy as np

from trackreplay.trackers.median import median


def test_median_is_numpys_median():
    rng = np.random.default_rng(9)
    for n in range(1, 60):
        values = rng.normal(0, 10, n)
        if n % 3 == 0:
            values = np.round(values)  # ties
        assert median(values) == float(np.median(values))
        assert median(values.astype(np.float32)) == float(np.median(values.astype(np.float32)))  # float32's own mean
        assert np.isnan(median(np.append(values, np.nan)))
    assert np.isnan(median(np.zeros(0)))
    assert median(np.array([3.0, 1.0, 2.0, 10.0])) == 2.5


def _sorted_middle(values: np.ndarray) -> float:
    """The sort-based median trackers.golf.range had (the form this one replaced)."""
    s = np.sort(values)
    n = len(s)
    return float(s[n // 2]) if n % 2 else float((s[n // 2 - 1] + s[n // 2]) / 2.0)


def test_median_is_the_sorted_middle_it_replaced():
    rng = np.random.default_rng(4)
    for n in range(1, 200):
        values = rng.integers(0, 256, n).astype(np.float64)  # grey levels, as range's ring holds: ties
        assert median(values) == _sorted_middle(values)
