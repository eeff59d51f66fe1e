"""The running median and extremes of rotor.logs.windows give scipy.ndimage's numbers."""

import numpy as np
import pytest
from scipy.ndimage import maximum_filter1d, median_filter, minimum_filter1d

from rotor.logs.windows import running


@pytest.mark.parametrize("n", [1, 2, 5, 9, 10, 101])
@pytest.mark.parametrize("size", [1, 3, 5, 9])
def test_running_windows_match_scipy(n, size):
    x = np.random.default_rng(n * 100 + size).normal(size=n) * np.exp(np.linspace(0, 3, n))
    for ends in ("mirror", "nearest") if n >= size else ("nearest",):  # scipy's mirror: n ≥ size
        np.testing.assert_array_equal(running(x, size, np.median, ends), median_filter(x, size, mode=ends))
        np.testing.assert_array_equal(running(x, size, np.max, ends), maximum_filter1d(x, size, mode=ends))
        np.testing.assert_array_equal(running(x, size, np.min, ends), minimum_filter1d(x, size, mode=ends))


def test_running_refuses_an_even_window():
    with pytest.raises(ValueError, match="odd"):
        running(np.arange(5.0), 4, np.median, "nearest")
