"""Bayesian comparisons against baycomp (test-only oracle) and hand-checked corner cases."""

from __future__ import annotations

import numpy as np
import pytest
from baycomp import CorrelatedTTest, SignedRankTest

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.bayesian import correlated_ttest, signed_rank_test
from touchbench.benchmark.evaluation.significance import corrected_resampled_ttest


def folds(seed: int, shift: float, n: int = 10) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    a = rng.normal(0.80, 0.03, n)
    return a, a - shift + rng.normal(0, 0.015, n)


@pytest.mark.parametrize(
    ("seed", "shift", "rope"), [(0, 0.01, 0.01), (1, 0.03, 0.01), (2, 0.0, 0.02)]
)
def test_correlated_ttest_against_baycomp(seed: int, shift: float, rope: float) -> None:
    a, b = folds(seed, shift)
    ours = correlated_ttest(a, b, test_train_ratio=1 / 9, rope=rope)
    # baycomp's difference is y - x and its "left" is x better; 10 folds, one run.
    left, equivalent, right = CorrelatedTTest.probs(a, b, rope=rope, runs=1)
    assert (ours.p_left, ours.p_rope, ours.p_right) == pytest.approx(
        (left, equivalent, right), abs=1e-12
    )
    assert ours.p_left + ours.p_rope + ours.p_right == pytest.approx(1.0)
    assert ours.mean_difference == pytest.approx(float((a - b).mean()))


def test_correlated_ttest_with_repeats_against_baycomp() -> None:
    a, b = folds(3, 0.02, n=30)  # 3 x 10-fold
    ours = correlated_ttest(a, b, test_train_ratio=1 / 9, rope=0.01)
    expected = CorrelatedTTest.probs(a, b, rope=0.01, runs=3)
    assert (ours.p_left, ours.p_rope, ours.p_right) == pytest.approx(expected, abs=1e-12)


def test_correlated_ttest_is_the_corrected_ttest_without_rope() -> None:
    a, b = folds(4, 0.01)
    bayes = correlated_ttest(a, b, test_train_ratio=1 / 9, rope=0.0)
    _, p, _ = corrected_resampled_ttest(a, b, test_train_ratio=1 / 9)
    assert bayes.p_rope == 0.0
    assert min(bayes.p_left, bayes.p_right) == pytest.approx(p / 2)


def test_direction_of_the_metric() -> None:
    a, b = folds(5, 0.05)
    higher = correlated_ttest(a, b, test_train_ratio=0.25)
    lower = correlated_ttest(a, b, test_train_ratio=0.25, lower_is_better=True)
    assert higher.p_left > 0.95 and lower.p_right > 0.95
    assert higher.decision() == "left" and lower.decision() == "right"
    assert higher.mean_difference == lower.mean_difference


def test_zero_variance_is_a_point_mass() -> None:
    a = np.array([0.8, 0.7, 0.9, 0.85])
    assert correlated_ttest(a, a, test_train_ratio=1 / 3).p_rope == 1.0
    better = correlated_ttest(a + 0.05, a, test_train_ratio=1 / 3)
    assert (better.p_left, better.p_rope, better.p_right) == (1.0, 0.0, 0.0)


def data_sets(seed: int, shift: float, n: int = 12) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    a = rng.uniform(0.6, 0.95, n)
    return a, a - shift + rng.normal(0, 0.01, n)


@pytest.mark.parametrize(
    ("seed", "shift", "rope"),
    [(0, 0.005, 0.01), (1, 0.02, 0.01), (2, -0.015, 0.005), (3, 0.004, 0.0)],
)
def test_signed_rank_against_baycomp(seed: int, shift: float, rope: float) -> None:
    a, b = data_sets(seed, shift)
    ours = signed_rank_test(a, b, rope=rope, n_samples=50_000, seed=seed)
    oracle = SignedRankTest.probs(a, b, rope=rope, nsamples=50_000, random_state=seed)
    if rope == 0:
        left, right = oracle
        assert ours.p_rope == 0.0
        assert (ours.p_left, ours.p_right) == pytest.approx((left, right), abs=0.015)
    else:
        # Monte Carlo on both sides: about 0.002 standard error each at 50,000 samples.
        assert (ours.p_left, ours.p_rope, ours.p_right) == pytest.approx(oracle, abs=0.015)
    assert ours.p_left + ours.p_rope + ours.p_right == pytest.approx(1.0)
    assert signed_rank_test(a, b, rope=rope, n_samples=2_000, seed=7) == signed_rank_test(
        a, b, rope=rope, n_samples=2_000, seed=7
    )


def test_signed_rank_clear_cases() -> None:
    a, b = data_sets(6, 0.05)
    assert signed_rank_test(a, b, rope=0.01).p_left > 0.99
    assert signed_rank_test(a, b, rope=0.01, lower_is_better=True).p_right > 0.99
    same, _ = data_sets(7, 0.0)
    assert signed_rank_test(same, same + 0.001, rope=0.01).p_rope > 0.99


def test_bad_input() -> None:
    a = np.array([0.8, 0.9, 0.7])
    with pytest.raises(ConfigurationError, match="differ in length: 3 and 2"):
        correlated_ttest(a, a[:2], test_train_ratio=0.1)
    with pytest.raises(ConfigurationError, match="at least 2 pair"):
        correlated_ttest(a[:1], a[:1], test_train_ratio=0.1)
    with pytest.raises(ConfigurationError, match="rope must be >= 0"):
        signed_rank_test(a, a, rope=-0.1)
    with pytest.raises(ConfigurationError, match="NaN"):
        signed_rank_test(a, np.array([0.8, np.nan, 0.7]))
    with pytest.raises(ConfigurationError, match="prior must be > 0"):
        signed_rank_test(a, a, prior=0)
