"""C4.5 as J48: Quinlan's weather tree, fractional instances, pruning arithmetic."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.weka import C45Classifier
from touchbench.benchmark.weka.c45 import added_errors

NAN = np.nan

# Quinlan's weather data, WEKA's weather.nominal.arff coded as WEKA codes it:
# outlook {sunny, overcast, rainy}, temperature {hot, mild, cool}, humidity {high, normal},
# windy {TRUE, FALSE}; play {yes, no}
WEATHER = np.array(
    [
        [0, 0, 0, 1, 1],
        [0, 0, 0, 0, 1],
        [1, 0, 0, 1, 0],
        [2, 1, 0, 1, 0],
        [2, 2, 1, 1, 0],
        [2, 2, 1, 0, 1],
        [1, 2, 1, 0, 0],
        [0, 1, 0, 1, 1],
        [0, 2, 1, 1, 0],
        [2, 1, 1, 1, 0],
        [0, 1, 1, 0, 0],
        [1, 1, 0, 0, 0],
        [1, 0, 1, 1, 0],
        [2, 1, 0, 0, 1],
    ],
    dtype=np.float64,
)
NOMINAL = {0: 3, 1: 3, 2: 2, 3: 2}


def weather_tree() -> C45Classifier:
    return C45Classifier(nominal_features=NOMINAL).fit(WEATHER[:, :4], WEATHER[:, 4])


def test_quinlans_weather_tree() -> None:
    tree = weather_tree()
    # outlook = sunny: humidity; overcast: yes (4); rainy: windy
    assert tree.feature_[0] == 0
    children = tree.children_[0][tree.children_[0] >= 0]
    assert [tree.feature_[c] for c in children] == [2, -1, 3]
    assert tree.counts_[children[1]].tolist() == [4.0, 0.0]
    assert tree.n_leaves_ == 5
    assert tree.score(WEATHER[:, :4], WEATHER[:, 4]) == 1.0


def test_a_missing_value_goes_down_every_branch_with_its_share() -> None:
    tree = weather_tree()
    # outlook unknown, humidity high, windy TRUE: sunny -> no, overcast -> yes, rainy -> no
    proba = tree.predict_proba(np.array([[NAN, 0.0, 0.0, 0.0]]))
    np.testing.assert_allclose(proba[0], [4 / 14, 10 / 14])


def test_numeric_threshold_is_a_training_value_and_minimum_instances_hold() -> None:
    X = np.array([[1.0], [2.0], [3.0], [7.0], [8.0], [9.0]])
    y = np.array([0, 0, 0, 1, 1, 1])
    tree = C45Classifier(min_instances=2).fit(X, y)
    assert tree.threshold_[0] == 3.0  # the midpoint 5 moved down to a training value
    assert tree.predict(np.array([[3.0], [3.5], [6.9]])).tolist() == [0, 1, 1]
    too_few = C45Classifier(min_instances=4).fit(X, y)
    assert too_few.n_leaves_ == 1


def test_pessimistic_error_estimates() -> None:
    # no error: N * (1 - CF^(1/N)); at the top end: N - e
    assert added_errors(6, 0, 0.25) == pytest.approx(6 * (1 - 0.25 ** (1 / 6)))
    assert added_errors(4, 3.6, 0.25) == pytest.approx(0.4)
    # C4.5's interpolation between 0 and 1 error
    base = added_errors(10, 0, 0.25)
    assert added_errors(10, 0.5, 0.25) == pytest.approx(
        base + 0.5 * (added_errors(10, 1, 0.25) - base)
    )
    # the upper confidence limit grows as the confidence shrinks
    assert added_errors(100, 10, 0.1) > added_errors(100, 10, 0.25) > 0


def test_pruning_removes_a_split_that_only_fits_noise() -> None:
    rng = np.random.default_rng(0)
    X = rng.integers(0, 10, size=(200, 1)).astype(np.float64)
    y = rng.integers(0, 2, size=200)
    unpruned = C45Classifier(pruned=False, nominal_features={0: 10}).fit(X, y)
    pruned = C45Classifier(nominal_features={0: 10}).fit(X, y)
    assert unpruned.n_leaves_ == 10  # one branch per declared label
    assert pruned.n_leaves_ == 1


def test_bad_parameters_are_refused() -> None:
    with pytest.raises(ValueError, match="confidence must lie in"):
        C45Classifier(confidence=0.9).fit(np.zeros((2, 1)), [0, 1])
    with pytest.raises(ValueError, match="min_instances must be a positive integer"):
        C45Classifier(min_instances=0).fit(np.zeros((2, 1)), [0, 1])
