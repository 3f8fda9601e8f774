from __future__ import annotations

import numpy as np
import pytest

from touchbench.features.errors import FeatureError
from touchbench.features.stats import segment_statistics


def test_statistics_of_each_segment_and_zeros_for_an_empty_one() -> None:
    values = np.array([[1.0, 3.0, 2.0, 5.0, 4.0], [0.0, 0.0, 1.0, 1.0, 1.0]])
    stats = segment_statistics(values, lengths=np.array([3, 0, 2]))
    assert np.allclose(stats.mean, [[2.0, 0.0, 4.5], [1 / 3, 0.0, 1.0]])
    assert np.array_equal(stats.minimum, [[1.0, 0.0, 4.0], [0.0, 0.0, 1.0]])
    assert np.array_equal(stats.maximum, [[3.0, 0.0, 5.0], [1.0, 0.0, 1.0]])
    assert np.array_equal(stats.range, [[2.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def test_no_values_at_all_gives_zeros() -> None:
    stats = segment_statistics(np.zeros((2, 0)), lengths=np.array([0, 0]))
    assert stats.mean.shape == (2, 2) and not stats.maximum.any()


def test_lengths_must_cover_the_values() -> None:
    with pytest.raises(FeatureError, match="sum to 3"):
        segment_statistics(np.zeros(3), lengths=np.array([1, 1]))
