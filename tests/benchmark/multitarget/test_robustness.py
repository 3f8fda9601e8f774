"""What cross-validation folds throw at the meta-classifiers: unseen combinations, one-valued
targets, absent classes, bases without probabilities, nominal inputs and missing values."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.impute import SimpleImputer
from sklearn.pipeline import make_pipeline
from sklearn.svm import SVC

from tests.support.multitarget import META_FACTORIES, logistic, three_targets
from touchbench.benchmark.multitarget import (
    ClassRelevance,
    LabelCombination,
    TargetClassifier,
    build_multitarget,
)


def independent_pair(n_samples: int = 160, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Target 0 follows feature 0, target 1 feature 1; the training data never holds
    the combination (1, 1)."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n_samples, 2))
    Y = (X > 0).astype(int)
    keep = ~np.all(Y == 1, axis=1)
    return X[keep], Y[keep]


def test_unseen_combinations_at_prediction_time(meta_id: str) -> None:
    X, Y = independent_pair()
    X_new = np.array([[2.0, 2.0], [-2.0, 2.0], [2.0, -2.0]])
    model = META_FACTORIES[meta_id](logistic()).fit(X, Y)
    predicted = model.predict(X_new)
    assert predicted.shape == (3, 2)
    assert set(np.unique(predicted)) <= {0, 1}
    assert [p.shape for p in model.predict_proba(X_new)] == [(3, 2), (3, 2)]
    # The seen combinations (0, 1) and (1, 0) come out right for everyone.
    assert predicted[1:].tolist() == [[0, 1], [1, 0]]


def test_class_relevance_can_predict_a_combination_it_never_saw() -> None:
    X, Y = independent_pair()
    predicted = ClassRelevance(logistic()).fit(X, Y).predict([[2.0, 2.0]])
    assert predicted.tolist() == [[1, 1]]


def test_label_combination_only_predicts_what_it_saw() -> None:
    X, Y = independent_pair()
    model = LabelCombination(logistic()).fit(X, Y)
    assert model.predict([[2.0, 2.0]]).tolist()[0] != [1, 1]
    assert [1, 1] not in model.combinations_.tolist()


def test_a_target_with_one_value_in_the_training_fold(meta_id: str) -> None:
    X, Y = three_targets()
    Y[:, 1] = 1
    # LogisticRegression alone refuses one-class data: the meta-classifiers must cope.
    model = META_FACTORIES[meta_id](logistic()).set_params(n_classes=(3, 2, 3)).fit(X, Y)
    assert np.all(model.predict(X)[:, 1] == 1)
    proba = model.predict_proba(X)[1]
    assert proba.shape == (120, 2)
    np.testing.assert_allclose(proba, np.tile([0.0, 1.0], (120, 1)))


def test_a_class_absent_from_the_training_fold_gets_probability_zero(meta_id: str) -> None:
    X, Y = three_targets()
    model = META_FACTORIES[meta_id](logistic()).set_params(n_classes=(5, 2, 3)).fit(X, Y)
    proba = model.predict_proba(X)
    assert proba[0].shape == (120, 5)
    np.testing.assert_array_equal(proba[0][:, 3:], 0.0)
    assert model.predict(X)[:, 0].max() <= 2


def test_a_base_without_probabilities_falls_back_to_one_hot_predictions(meta_id: str) -> None:
    X, Y = three_targets()
    model = META_FACTORIES[meta_id](SVC()).fit(X, Y)
    predicted = model.predict(X)
    for target, proba in enumerate(model.predict_proba(X)):
        assert proba.shape[0] == 120
        np.testing.assert_allclose(proba.sum(axis=1), 1.0)
        if meta_id in {"cr", "cc", "bcc"}:
            assert set(np.unique(proba)) <= {0.0, 1.0}
            np.testing.assert_array_equal(proba.argmax(axis=1), predicted[:, target])


def test_target_classifier_recodes_gaps_and_reports_its_probabilities() -> None:
    X = np.array([[0.0], [1.0], [2.0], [3.0]])
    y = np.array([0, 0, 3, 3])
    fitted = TargetClassifier(logistic(), n_classes=5).fit(X, y)
    assert fitted.present_classes_.tolist() == [0, 3]
    assert fitted.estimator_.classes_.tolist() == [0, 1]
    proba = fitted.predict_proba(X)
    assert proba.shape == (4, 5)
    np.testing.assert_array_equal(proba[:, [1, 2, 4]], 0.0)
    assert fitted.predict(X).tolist() == [0, 0, 3, 3]
    assert fitted.probabilistic_
    assert not TargetClassifier(SVC(), n_classes=5).fit(X, y).probabilistic_


def meka_like(n_samples: int = 150, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A nominal feature (codes 0..2), two numeric ones, about 10 % missing values."""
    rng = np.random.default_rng(seed)
    nominal = rng.integers(0, 3, n_samples).astype(float)
    numeric = rng.normal(size=(n_samples, 2))
    Y = np.column_stack([nominal.astype(int), (numeric[:, 0] > 0).astype(int)])
    X = np.column_stack([nominal, numeric])
    X[rng.random(X.shape) < 0.1] = np.nan
    return X, Y


@pytest.mark.parametrize("meta", ["cr", "cc", "bcc", "pcc", "lc", "nsr", "ecc", "scc"])
def test_nominal_inputs_and_missing_values_through_the_catalogue(meta: str) -> None:
    X, Y = meka_like()
    model = build_multitarget(
        f"{meta}:logistic", nominal_features={0: 3}, n_features=3, n_classes=(3, 2)
    ).fit(X, Y)
    assert model.score(X, Y) > 0.75
    assert [p.shape for p in model.predict_proba(X)] == [(150, 3), (150, 2)]


def test_missing_values_through_a_plain_imputing_pipeline(meta_id: str) -> None:
    X, Y = meka_like()
    base = make_pipeline(SimpleImputer(), logistic())
    model = META_FACTORIES[meta_id](base).fit(X, Y)
    assert model.predict(X).shape == (150, 2)
    assert not np.isnan(np.concatenate(model.predict_proba(X), axis=1)).any()
