"""The logistic model tree: regions from the tree, a linear boundary inside each region."""

from __future__ import annotations

import numpy as np
from sklearn.linear_model import LogisticRegression
from sklearn.tree import DecisionTreeClassifier

from touchbench.benchmark.artifacts import dumps_artifact, loads_artifact
from touchbench.benchmark.catalogue.model_trees import LogisticModelTree


def regimes(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Two regimes split on ``x0``, each with its own oblique boundary in ``(x1, x2)``.

    The regimes' class balances differ, so that the split on ``x0`` has information gain.
    """
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, size=(n, 3))
    y = np.where(X[:, 0] > 0, X[:, 1] + X[:, 2] > 0.8, X[:, 1] - X[:, 2] > -0.8).astype(int)
    return X, y


def test_a_linear_model_per_region_learns_what_neither_part_learns_alone() -> None:
    X, y = regimes(1200, seed=0)
    X_test, y_test = regimes(600, seed=1)
    tree = LogisticModelTree(max_depth=1, random_state=0).fit(X, y)
    logistic = LogisticRegression().fit(X, y)
    plain_tree = DecisionTreeClassifier(min_samples_leaf=50, random_state=0).fit(X, y)
    assert tree.tree_model_.tree_.feature[0] == 0
    assert tree.score(X_test, y_test) > 0.97
    assert logistic.score(X_test, y_test) < 0.85
    assert plain_tree.score(X_test, y_test) < 0.95


def test_a_leaf_of_one_class_answers_its_laplace_frequencies() -> None:
    X = np.array([[0.0], [1.0], [2.0], [10.0], [11.0], [12.0], [13.0]])
    y = np.array(["a", "a", "a", "b", "c", "b", "c"])
    model = LogisticModelTree(min_samples_leaf=3, max_depth=1).fit(X, y)
    assert model.leaf_models_[0] is None and model.leaf_models_[1] is not None
    np.testing.assert_allclose(model.predict_proba(np.array([[0.5]])), [[4 / 6, 1 / 6, 1 / 6]])
    assert model.predict_proba(np.array([[11.5], [12.5]])).sum(axis=1).tolist() == [1.0, 1.0]
    assert model.predict(np.array([[1.0]])).tolist() == ["a"]


def test_it_round_trips_through_a_model_artifact() -> None:
    X, y = regimes(300, seed=2)
    model = LogisticModelTree(min_samples_leaf=30).fit(X, y)
    again = loads_artifact(dumps_artifact({"estimator": model}))["estimator"]
    np.testing.assert_allclose(again.predict_proba(X), model.predict_proba(X))
