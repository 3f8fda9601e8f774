"""BCC's Chow-Liu tree and the dependence measures it is built from."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.utils import check_random_state

from tests.support.multitarget import logistic
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.multitarget import BayesianClassifierChain
from touchbench.benchmark.multitarget.dependence import (
    CHI2_CRITICAL_2DOF,
    error_dependence_matrix,
    maximum_spanning_tree,
    mutual_information_matrix,
    orient_tree,
)

A, B, C = 0, 1, 2


def dependent_targets(n_samples: int = 400, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """B is a noisy function of A (90 % ``(A + 1) mod 3``), C independent of both."""
    rng = np.random.default_rng(seed)
    a = rng.integers(0, 3, n_samples)
    b = np.where(rng.random(n_samples) < 0.9, (a + 1) % 3, rng.integers(0, 3, n_samples))
    c = rng.integers(0, 2, n_samples)
    X = np.column_stack([a + rng.normal(scale=0.3, size=n_samples), rng.normal(size=n_samples)])
    return X, np.column_stack([a, b, c])


def test_the_tree_links_the_dependent_targets() -> None:
    X, Y = dependent_targets()
    model = BayesianClassifierChain(logistic(), random_state=0).fit(X, Y)
    information = model.mutual_information_
    assert information[A, B] > 0.5
    assert information[A, C] < 0.02 and information[B, C] < 0.02
    assert (A, B) in model.edges_ or (B, A) in model.edges_
    assert model.tree_[B] == A or model.tree_[A] == B
    assert len(model.edges_) == 2
    assert int(np.sum(model.tree_ == -1)) == 1


def test_the_root_comes_first_and_edges_point_away_from_it() -> None:
    X, Y = dependent_targets()
    model = BayesianClassifierChain(logistic(), root=C).fit(X, Y)
    assert model.root_ == C
    assert model.tree_[C] == -1
    assert model.order_[0] == C
    position = {int(t): i for i, t in enumerate(model.order_)}
    for child, parent in enumerate(model.tree_):
        if parent >= 0:
            assert position[parent] < position[child]
    assert model.parents_ == [() if p < 0 else (int(p),) for p in model.tree_]


def test_each_target_classifier_sees_its_parent_one_hot() -> None:
    X, Y = dependent_targets()
    model = BayesianClassifierChain(logistic(), root=A).fit(X, Y)
    assert model.tree_[B] == A
    assert model.estimators_[A].estimator_.n_features_in_ == 2
    assert model.estimators_[B].estimator_.n_features_in_ == 2 + 3


def test_b_is_predicted_well_through_its_parent() -> None:
    X, Y = dependent_targets(seed=1)
    X_test, Y_test = dependent_targets(seed=2)
    model = BayesianClassifierChain(logistic(), root=A).fit(X, Y)
    accuracy_b = np.mean(model.predict(X_test)[:, B] == Y_test[:, B])
    assert accuracy_b > 0.8


def test_the_root_is_drawn_from_the_seed() -> None:
    X, Y = dependent_targets()
    for seed in range(4):
        model = BayesianClassifierChain(logistic(), random_state=seed).fit(X, Y)
        assert model.root_ == check_random_state(seed).randint(3)


def test_a_root_outside_the_targets_is_refused() -> None:
    X, Y = dependent_targets()
    with pytest.raises(ConfigurationError, match=r"root must be a target index 0\.\.2, got 3"):
        BayesianClassifierChain(logistic(), root=3).fit(X, Y)


def test_mutual_information_by_hand() -> None:
    # Joint counts of (Y0, Y1): (0,0) x2, (1,1) x1, (1,0) x1 over 4 rows.
    Y = np.array([[0, 0], [0, 0], [1, 1], [1, 0]])
    p = {(0, 0): 0.5, (1, 1): 0.25, (1, 0): 0.25}
    p0 = {0: 0.5, 1: 0.5}
    p1 = {0: 0.75, 1: 0.25}
    expected = sum(v * np.log(v / (p0[a] * p1[b])) for (a, b), v in p.items())
    information = mutual_information_matrix(Y, [2, 2])
    assert information[0, 1] == pytest.approx(expected)
    assert information[1, 0] == pytest.approx(expected)
    assert information[0, 0] == 0.0


def test_independent_and_identical_targets() -> None:
    Y = np.array([[a, b] for a in range(3) for b in range(2)] * 5)
    assert mutual_information_matrix(Y, [3, 2])[0, 1] == pytest.approx(0.0, abs=1e-12)
    same = np.column_stack([Y[:, 0], Y[:, 0]])
    assert mutual_information_matrix(same, [3, 3])[0, 1] == pytest.approx(np.log(3))


def test_maximum_spanning_tree_keeps_the_heaviest_edges() -> None:
    weights = np.array(
        [
            [0.0, 5.0, 1.0, 0.0],
            [5.0, 0.0, 4.0, 3.0],
            [1.0, 4.0, 0.0, 2.0],
            [0.0, 3.0, 2.0, 0.0],
        ]
    )
    edges = {frozenset(edge) for edge in maximum_spanning_tree(weights)}
    assert edges == {frozenset({0, 1}), frozenset({1, 2}), frozenset({1, 3})}


def test_spanning_tree_of_unweighted_graph_is_still_a_tree() -> None:
    edges = maximum_spanning_tree(np.zeros((4, 4)))
    parents, order = orient_tree(edges, 4, root=2)
    assert len(edges) == 3
    assert sorted(order.tolist()) == [0, 1, 2, 3]
    assert int(np.sum(parents == -1)) == 1 and parents[2] == -1


def test_orient_tree_breadth_first() -> None:
    parents, order = orient_tree([(0, 1), (1, 2), (1, 3)], 4, root=3)
    assert parents.tolist() == [1, 3, 1, -1]
    assert order.tolist() == [3, 1, 0, 2]


def test_error_dependence_by_hand() -> None:
    # Target 0 and 1 are wrong on the same two of eight rows, target 2 on two others.
    truth = np.zeros((8, 3), dtype=int)
    predicted = truth.copy()
    predicted[[0, 1], 0] = 1
    predicted[[0, 1], 1] = 1
    predicted[[4, 5], 2] = 1
    dependence = error_dependence_matrix(truth, predicted)
    # Error rates 1/4 each.  Pair (0, 1): observed (2, 0, 6) against expected
    # 8 * (1/16, 6/16, 9/16) = (0.5, 3, 4.5).
    together = (2 - 0.5) ** 2 / 0.5 + (0 - 3) ** 2 / 3 + (6 - 4.5) ** 2 / 4.5
    assert dependence[0, 1] == pytest.approx(together - CHI2_CRITICAL_2DOF)
    # Pair (0, 2): observed (0, 4, 4).
    apart = (0 - 0.5) ** 2 / 0.5 + (4 - 3) ** 2 / 3 + (4 - 4.5) ** 2 / 4.5
    assert dependence[0, 2] == pytest.approx(apart - CHI2_CRITICAL_2DOF)
    assert dependence[0, 1] > 0 > dependence[0, 2]
