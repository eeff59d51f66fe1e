"""Which critical speeds a Campbell summary lists."""

import numpy as np

from rotor.torsion.campbell import shown_critical


def test_ties_with_the_smallest_listed_are_listed_too():
    amp = np.array([0.9, 0.5, 0.5, 0.5, 0.1, np.nan])
    shown = set(shown_critical(amp, 3).tolist())
    assert shown == {0, 5, 1, 2, 3}  # the unknown counts as 1; the three tied at 0.5 all kept
    left = set(range(len(amp))) - shown
    assert all(amp[i] < min(np.nan_to_num(amp[j], nan=1.0) for j in shown) for i in left)


def test_without_ties_the_largest_are_listed():
    amp = np.array([0.1, 0.7, 0.3, 0.9])
    assert sorted(shown_critical(amp, 2).tolist()) == [1, 3]
    assert sorted(shown_critical(amp, 10).tolist()) == [0, 1, 2, 3]
