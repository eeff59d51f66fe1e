"""Running medians and extremes of a 1-D signal over an odd window, in NumPy.

The same numbers as ``scipy.ndimage``'s ``median_filter``, ``maximum_filter1d`` and
``minimum_filter1d`` (``tests/logs/test_windows.py`` compares them), without importing
``scipy.ndimage`` (about 0.5 s of a command's start): the windows here are a few samples
wide, so a view of every window and one reduction over it is as fast.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["running"]


def running(x: np.ndarray, size: int, how: Callable[..., np.ndarray], ends: str) -> np.ndarray:
    """``how`` (``np.median``, ``np.max`` or ``np.min``) of ``x`` over the window of ``size``
    samples (odd) centred on each sample. ``ends``: how the window is filled past the ends,
    ``"mirror"`` (reflected about the end sample: c b | a b c …, scipy's ``mode="mirror"``
    where ``x`` has at least ``size`` samples) or ``"nearest"`` (the end sample repeated,
    scipy's ``mode="nearest"``). Returns an array of the length of ``x``."""
    if size < 1 or size % 2 == 0:
        raise ValueError(f"size = {size!r}: an odd number of samples")
    x = np.asarray(x, dtype=np.float64)
    if x.size == 0:
        return x.copy()
    if ends not in ("mirror", "nearest"):
        raise ValueError(f"ends = {ends!r}: 'mirror' or 'nearest'")
    half = size // 2
    if ends == "mirror" and x.size > 1:
        padded = np.pad(x, half, mode="reflect")
    else:  # the end sample repeated (a single sample has nothing to reflect about)
        padded = np.pad(x, half, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, size)
    return how(windows, axis=1)
