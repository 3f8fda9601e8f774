"""Forests' probabilities tree by tree (benchmark/forest_inference.py) are scikit-learn's."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from tests.support.synthetic import nominal_dataset as dataset
from touchbench.benchmark.forest_inference import forest_proba
from touchbench.benchmark.model import fit_model


def _data(n: int = 300) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1)
    X = rng.normal(size=(n, 12))
    y = (X[:, 0] + 0.5 * X[:, 1] > 0).astype(int) + (X[:, 2] > 1)
    return X, y


@pytest.mark.parametrize("forest", [RandomForestClassifier, ExtraTreesClassifier])
@pytest.mark.parametrize("rows", [1, 7, 300])
def test_the_tree_walk_gives_scikit_learns_probabilities(forest: type, rows: int) -> None:
    X, y = _data()
    model = make_pipeline(StandardScaler(), forest(n_estimators=30, random_state=0)).fit(X, y)
    ours = forest_proba(model, X[:rows])
    assert ours is not None
    np.testing.assert_allclose(ours, model.predict_proba(X[:rows]), rtol=1e-12, atol=1e-15)
    bare = forest(n_estimators=5, min_samples_leaf=3, random_state=2).fit(X, y)
    np.testing.assert_allclose(forest_proba(bare, X[:rows]), bare.predict_proba(X[:rows]))


def test_what_the_shortcut_does_not_take_is_left_to_scikit_learn() -> None:
    X, y = _data()
    assert forest_proba(LogisticRegression().fit(X, y), X) is None
    parallel = RandomForestClassifier(n_estimators=4, n_jobs=2, random_state=0).fit(X, y)
    assert forest_proba(parallel, X) is None
    multi_output = RandomForestClassifier(n_estimators=4).fit(X, np.column_stack([y, y]))
    assert forest_proba(multi_output, X) is None
    serial = RandomForestClassifier(n_estimators=4, random_state=0).fit(X, y)
    assert forest_proba(serial, X[:, :5]) is None  # scikit-learn says the width is wrong
    missing = X[:3].copy()
    missing[0, 0] = np.nan
    assert forest_proba(serial, missing) is None


def test_trained_models_of_forests_read_the_same_probabilities() -> None:
    data = dataset()
    complete = data.X[~np.isnan(data.X).any(axis=1)]
    for classifier in ("rf", "extra-trees"):
        model = fit_model(data, classifier, random_state=0)
        assert forest_proba(model.estimator, model._features(complete)) is not None
        ours = model.predict_proba(complete)[0]
        theirs = model.estimator.predict_proba(model._features(complete))
        np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-15)
        with_missing = model.predict_proba(data.X)[0]  # scikit-learn routes missing values
        np.testing.assert_allclose(
            with_missing, model.estimator.predict_proba(model._features(data.X))
        )
