"""The corrected resampled t-test against a hand-computed example and WEKA's corner cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.significance import corrected_resampled_ttest


def test_hand_computed_example() -> None:
    a = np.array([0.90, 0.85, 0.88, 0.92, 0.87])
    b = np.array([0.80, 0.82, 0.85, 0.84, 0.83])
    # d = 0.10, 0.03, 0.03, 0.08, 0.04: mean 0.056, sample variance 0.00103
    # t = 0.056 / sqrt((1/5 + 1/4) * 0.00103) = 2.6011...; 4 degrees of freedom
    t, p, sign = corrected_resampled_ttest(a, b, test_train_ratio=0.25)
    assert t == pytest.approx(0.056 / math.sqrt(0.45 * 0.00103))
    assert t == pytest.approx(2.6011, abs=1e-4)
    assert p == pytest.approx(0.06, abs=0.001)  # t(4) two-sided: 0.0600
    assert sign == 0  # not significant at 0.05 ...
    assert corrected_resampled_ttest(a, b, test_train_ratio=0.25, alpha=0.1)[2] == 1
    # ... whereas the uncorrected test (ratio 0) would call it significant
    t0, p0, sign0 = corrected_resampled_ttest(a, b, test_train_ratio=0.0)
    assert t0 == pytest.approx(0.056 / math.sqrt(0.00103 / 5))
    assert p0 < 0.05 and sign0 == 1


def test_sign_follows_the_direction() -> None:
    a = np.array([0.5, 0.52, 0.49, 0.51, 0.5, 0.5, 0.53, 0.48, 0.5, 0.51])
    b = a + 0.2 + np.linspace(-0.01, 0.01, 10)
    assert corrected_resampled_ttest(a, b, test_train_ratio=1 / 9)[2] == -1
    assert corrected_resampled_ttest(b, a, test_train_ratio=1 / 9)[2] == 1


def test_zero_variance_as_weka_does() -> None:
    same = np.array([0.8, 0.7, 0.9])
    assert corrected_resampled_ttest(same, same, test_train_ratio=0.5) == (0.0, 1.0, 0)
    t, p, sign = corrected_resampled_ttest(same + 0.1, same, test_train_ratio=0.5)
    assert (t, p, sign) == (math.inf, 0.0, 1)
    t, p, sign = corrected_resampled_ttest(same - 0.1, same, test_train_ratio=0.5)
    assert (t, p, sign) == (-math.inf, 0.0, -1)


def test_fewer_than_two_pairs_cannot_be_tested() -> None:
    t, p, sign = corrected_resampled_ttest(np.array([0.9]), np.array([0.1]), test_train_ratio=0.1)
    assert math.isnan(t) and math.isnan(p) and sign == 0


def test_bad_arguments() -> None:
    with pytest.raises(ConfigurationError, match="differ in length"):
        corrected_resampled_ttest(np.ones(3), np.ones(4), test_train_ratio=0.1)
    with pytest.raises(ConfigurationError, match="alpha must lie in"):
        corrected_resampled_ttest(np.ones(3), np.ones(3), test_train_ratio=0.1, alpha=0)
