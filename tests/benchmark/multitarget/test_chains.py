"""CC's chain order and PCC's inference over value combinations."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.utils import check_random_state

from tests.support.multitarget import logistic, three_targets, tree
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.multitarget import (
    ClassifierChain,
    EnsembleClassifierChains,
    ProbabilisticClassifierChain,
)


def mirrored_targets(n_samples: int = 200, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Target 1 is ``1 - target 0``; the features only hint at target 0."""
    rng = np.random.default_rng(seed)
    first = rng.integers(0, 2, n_samples)
    X = np.column_stack([first + rng.normal(scale=1.0, size=n_samples), rng.normal(size=n_samples)])
    return X, np.column_stack([first, 1 - first])


def test_a_given_order_decides_who_sees_whom(tiny) -> None:
    X, Y = tiny
    model = ClassifierChain(logistic(), order=[2, 0, 1]).fit(X, Y)
    assert model.order_.tolist() == [2, 0, 1]
    assert model.parents_ == [(2,), (2, 0), ()]
    widths = [link.estimator_.n_features_in_ for link in model.estimators_]
    # 4 features, then the one-hot codes of the earlier targets (3 classes each).
    assert widths == [4 + 3, 4 + 3 + 3, 4]


def test_later_links_follow_the_earlier_predictions() -> None:
    X, Y = mirrored_targets()
    X_test, _ = mirrored_targets(seed=1)
    for order in ([0, 1], [1, 0]):
        predicted = ClassifierChain(logistic(), order=order).fit(X, Y).predict(X_test)
        np.testing.assert_array_equal(predicted[:, 1], 1 - predicted[:, 0])
    # The second link decides from its parent's value, whatever the features say.
    second = ClassifierChain(logistic(), order=[0, 1]).fit(X, Y).estimators_[1]
    parent_zero = np.hstack([X_test, np.tile([1.0, 0.0], (len(X_test), 1))])
    parent_one = np.hstack([X_test, np.tile([0.0, 1.0], (len(X_test), 1))])
    assert np.all(second.predict(parent_zero) == 1)
    assert np.all(second.predict(parent_one) == 0)


def test_the_order_changes_the_model(tiny) -> None:
    X, Y = tiny
    forward = ClassifierChain(logistic(), order=[0, 1, 2]).fit(X, Y).predict_proba(X)
    backward = ClassifierChain(logistic(), order=[2, 1, 0]).fit(X, Y).predict_proba(X)
    assert not np.allclose(forward[0], backward[0])


def test_a_random_order_comes_from_the_seed(tiny) -> None:
    X, Y = tiny
    orders = set()
    for seed in range(8):
        model = ClassifierChain(logistic(), random_state=seed).fit(X, Y)
        assert model.order_.tolist() == check_random_state(seed).permutation(3).tolist()
        orders.add(tuple(model.order_.tolist()))
    assert len(orders) > 1


@pytest.mark.parametrize("order", [[0, 1], [0, 0, 1], [0, 1, 3]])
def test_an_order_must_be_a_permutation(tiny, order: list[int]) -> None:
    X, Y = tiny
    with pytest.raises(ConfigurationError, match="permutation of the 3 target indices"):
        ClassifierChain(logistic(), order=order).fit(X, Y)


def test_ensemble_members_have_their_own_orders_and_samples(tiny) -> None:
    X, Y = tiny
    model = EnsembleClassifierChains(tree(), n_estimators=8, random_state=0).fit(X, Y)
    assert len({tuple(member.order_.tolist()) for member in model.estimators_}) > 1
    for rows in model.samples_:
        assert rows.shape == (120,)
        assert np.unique(rows).shape[0] < 120  # a bootstrap sample repeats rows


def skewed_joint() -> tuple[np.ndarray, np.ndarray]:
    """An uninformative feature and a joint law where greedy decisions miss the mode.

    P(y0 = 0) = 0.6 with y1 uniform over {0, 1, 2}; P(y0 = 1) = 0.4 with y1 = 0.
    The joint mode is (1, 0) with probability 0.4; the greedy chain picks y0 = 0 and
    then a value of probability 0.2.
    """
    Y = np.array([[0, 0]] * 20 + [[0, 1]] * 20 + [[0, 2]] * 20 + [[1, 0]] * 40)
    return np.zeros((100, 1)), Y


def test_pcc_finds_the_joint_mode_that_the_greedy_chain_misses() -> None:
    X, Y = skewed_joint()
    greedy = ClassifierChain(tree(), order=[0, 1]).fit(X, Y)
    exhaustive = ProbabilisticClassifierChain(tree(), order=[0, 1]).fit(X, Y)
    assert greedy.predict(X[:1]).tolist() == [[0, 0]]
    assert exhaustive.predict(X[:1]).tolist() == [[1, 0]]
    marginals = exhaustive.predict_proba(X[:1])
    np.testing.assert_allclose(marginals[0], [[0.6, 0.4]])
    np.testing.assert_allclose(marginals[1], [[0.6, 0.2, 0.2]])


def test_a_beam_of_one_is_the_greedy_chain() -> None:
    X, Y = skewed_joint()
    narrow = ProbabilisticClassifierChain(tree(), order=[0, 1], exhaustive_limit=1, beam_width=1)
    assert narrow.fit(X, Y).predict(X[:1]).tolist() == [[0, 0]]
    wide = ProbabilisticClassifierChain(tree(), order=[0, 1], exhaustive_limit=1, beam_width=2)
    assert wide.fit(X, Y).predict(X[:1]).tolist() == [[1, 0]]


def test_exhaustive_pcc_marginals_sum_over_all_combinations() -> None:
    X, Y = three_targets(seed=4)
    model = ProbabilisticClassifierChain(logistic(), random_state=0).fit(X, Y)
    beam = ProbabilisticClassifierChain(
        logistic(), random_state=0, exhaustive_limit=1, beam_width=18
    ).fit(X, Y)
    # 3 * 2 * 3 = 18 combinations: a beam of 18 keeps them all.
    for exact, searched in zip(model.predict_proba(X), beam.predict_proba(X), strict=True):
        np.testing.assert_allclose(exact, searched)
    np.testing.assert_array_equal(model.predict(X), beam.predict(X))
