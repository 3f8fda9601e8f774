"""The scikit-learn estimator contract, for every multi-target meta-classifier."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.utils.estimator_checks import check_estimator

from tests.support.multitarget import META_FACTORIES, logistic, three_targets, tree
from touchbench.benchmark.errors import ConfigurationError

#: Checks of ``check_estimator`` that assume single-output classifiers.  Multi-target
#: estimators take a 2-D ``Y`` of integer codes and return a list from predict_proba:
#: - check_classifiers_classes fits string labels and a 1-D y;
#: - check_classifiers_train expects predict to return shape (n_samples,);
#: - check_methods_sample_order_invariance indexes predict_proba's output as an array.
SINGLE_OUTPUT_CHECKS = {
    "check_classifiers_classes": "string labels and 1-D y; multi-target Y is 2-D codes",
    "check_classifiers_train": "expects 1-D predictions",
    "check_methods_sample_order_invariance": "indexes the list predict_proba returns",
}

#: Methods whose ``predict`` is a joint decision (the most probable combination, a vote)
#: while ``predict_proba`` gives per-target marginals or means, so the argmax of the
#: latter may differ from the former, which check_classifier_multioutput asserts against.
JOINT_DECISION_METHODS = {"lc", "ps", "nsr", "eps", "ecc", "rakeld", "scc", "pcc"}


def test_every_meka_method_is_listed() -> None:
    expected = {"cr", "cc", "bcc", "pcc", "lc", "ps", "eps", "ecc", "rakeld", "nsr", "scc"}
    assert set(META_FACTORIES) == expected


def test_sklearn_estimator_checks_pass(meta_id: str) -> None:
    """sklearn's own ``check_estimator`` suite, but for the single-output checks above."""
    estimator = META_FACTORIES[meta_id](tree())
    expected = dict(SINGLE_OUTPUT_CHECKS)
    if meta_id in JOINT_DECISION_METHODS:
        expected["check_classifier_multioutput"] = "joint decisions, marginal probabilities"
    outcomes: dict[str, set[str]] = {}

    def record(**info: object) -> None:
        outcomes.setdefault(str(info["check_name"]), set()).add(str(info["status"]))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_estimator(
            estimator,
            expected_failed_checks=expected,
            on_fail=None,
            on_skip=None,
            callback=record,
        )
    failed = sorted(name for name, statuses in outcomes.items() if "failed" in statuses)
    assert failed == []
    passed = {name for name, statuses in outcomes.items() if statuses == {"passed"}}
    assert len(passed) >= 45
    for name in (
        "check_estimator_cloneable",
        "check_get_params_invariance",
        "check_set_params",
        "check_no_attributes_set_in_init",
        "check_estimators_fit_returns_self",
        "check_estimators_overwrite_params",
        "check_dont_overwrite_parameters",
        "check_estimators_unfitted",
        "check_n_features_in",
        "check_fit_check_is_fitted",
        "check_estimators_pickle",
        "check_fit_idempotent",
        "check_estimators_dtypes",
        "check_requires_y_none",
        "check_classifiers_regression_target",
    ):
        assert name in passed, f"{name}: {outcomes.get(name)}"
    if meta_id not in JOINT_DECISION_METHODS:
        assert "check_classifier_multioutput" in passed


def test_clone_gives_unfitted_copy_with_same_params(meta_id: str, tiny) -> None:
    X, Y = tiny
    estimator = META_FACTORIES[meta_id](logistic())
    estimator.fit(X, Y)
    copy = clone(estimator)
    assert copy.get_params().keys() == estimator.get_params().keys()
    assert not hasattr(copy, "n_classes_")
    with pytest.raises(NotFittedError):
        copy.predict(X)


def test_set_params_reaches_the_base(meta_id: str) -> None:
    estimator = META_FACTORIES[meta_id](logistic())
    estimator.set_params(estimator__C=0.25)
    assert estimator.get_params()["estimator__C"] == 0.25
    assert estimator.estimator.C == 0.25


def test_fit_returns_self_and_never_fits_the_prototype(meta_id: str, tiny) -> None:
    X, Y = tiny
    base = logistic()
    estimator = META_FACTORIES[meta_id](base)
    assert estimator.fit(X, Y) is estimator
    assert not hasattr(base, "coef_")
    assert estimator.n_features_in_ == 4
    assert estimator.n_targets_ == 3
    assert estimator.n_classes_ == (3, 2, 3)
    assert [list(c) for c in estimator.classes_] == [[0, 1, 2], [0, 1], [0, 1, 2]]


def test_predictions_and_probabilities_have_the_documented_shapes(meta_id: str, tiny) -> None:
    X, Y = tiny
    estimator = META_FACTORIES[meta_id](logistic()).fit(X, Y)
    predicted = estimator.predict(X)
    assert predicted.shape == (120, 3)
    assert predicted.dtype == np.int64
    proba = estimator.predict_proba(X)
    assert [p.shape for p in proba] == [(120, 3), (120, 2), (120, 3)]
    for p in proba:
        assert np.all(p >= 0)
        np.testing.assert_allclose(p.sum(axis=1), 1.0)
    # Every target here is learnable from the features: far better than chance (~0.4).
    assert estimator.score(X, Y) > 0.8


def test_pickled_model_predicts_the_same(meta_id: str, tiny) -> None:
    X, Y = tiny
    estimator = META_FACTORIES[meta_id](logistic()).fit(X, Y)
    restored = pickle.loads(pickle.dumps(estimator))
    np.testing.assert_array_equal(restored.predict(X), estimator.predict(X))


def test_same_seed_same_model(meta_id: str) -> None:
    X, Y = three_targets(seed=3)
    first = META_FACTORIES[meta_id](tree()).fit(X, Y).predict_proba(X)
    second = META_FACTORIES[meta_id](tree()).fit(X, Y).predict_proba(X)
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a, b)


def test_bad_targets_are_configuration_errors(meta_id: str, tiny) -> None:
    X, Y = tiny
    estimator = META_FACTORIES[meta_id](logistic())
    with pytest.raises(ConfigurationError, match="2-D"):
        estimator.fit(X, Y[:, 0])
    with pytest.raises(ConfigurationError, match="missing target value"):
        estimator.fit(X, np.where(np.arange(120)[:, None] == 5, np.nan, Y.astype(float)))
    with pytest.raises(ConfigurationError, match="negative"):
        estimator.fit(X, Y - 1)
    with pytest.raises(ConfigurationError, match="X has 120 rows but Y has 60"):
        estimator.fit(X, Y[:60])
    with pytest.raises(ConfigurationError, match="n_classes"):
        clone(estimator).set_params(n_classes=(2, 2, 3)).fit(X, Y)


def test_prediction_needs_the_training_width(meta_id: str, tiny) -> None:
    X, Y = tiny
    estimator = META_FACTORIES[meta_id](logistic()).fit(X, Y)
    with pytest.raises(ValueError, match="features"):
        estimator.predict(X[:, :3])
