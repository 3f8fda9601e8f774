"""scikit-multilearn's methods for binary targets behind the multi-target interface."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import clone

from tests.support.multitarget import logistic
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.multitarget import MultiLabelAdapter
from touchbench.benchmark.multitarget.multilabel import (
    METHODS_WITH_BASE,
    METHODS_WITHOUT_BASE,
    METHODS_WITHOUT_PROBABILITIES,
)


def labels(n_samples: int = 120, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Four binary labels, each a noisy threshold of one of four features."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n_samples, 4))
    Y = (X + rng.normal(scale=0.3, size=X.shape) > 0).astype(int)
    return X, Y


def adapter(method: str) -> MultiLabelAdapter:
    base = logistic() if method in METHODS_WITH_BASE else None
    return MultiLabelAdapter(method, base, labelset_size=2, random_state=0)


@pytest.fixture(params=METHODS_WITH_BASE + METHODS_WITHOUT_BASE)
def method(request: pytest.FixtureRequest) -> str:
    return str(request.param)


def test_every_method_fits_and_predicts_binary_labels(method: str) -> None:
    X, Y = labels()
    model = adapter(method)
    assert model.fit(X, Y) is model
    predicted = model.predict(X)
    assert predicted.shape == (120, 4) and predicted.dtype == np.int64
    assert set(np.unique(predicted)) <= {0, 1}
    proba = model.predict_proba(X)
    assert [p.shape for p in proba] == [(120, 2)] * 4
    for p in proba:
        np.testing.assert_allclose(p.sum(axis=1), 1.0)
    # MLARAM's fuzzy ART is the weakest here; everything else is far above chance.
    assert model.score(X, Y) > (0.6 if method == "mlaram" else 0.8)


def test_methods_without_probabilities_give_one_hot_predictions() -> None:
    X, Y = labels()
    for method in METHODS_WITHOUT_PROBABILITIES:
        model = adapter(method).fit(X, Y)
        predicted = model.predict(X)
        for target, proba in enumerate(model.predict_proba(X)):
            np.testing.assert_array_equal(proba[:, 1], predicted[:, target])


def test_the_estimator_contract(method: str) -> None:
    X, Y = labels()
    model = adapter(method)
    copy = clone(model)
    assert copy.get_params().keys() == model.get_params().keys()
    assert (copy.method, copy.labelset_size, copy.random_state) == (method, 2, 0)
    model.fit(X, Y)
    assert not hasattr(clone(model), "model_")
    if method in METHODS_WITH_BASE:
        assert not hasattr(model.estimator, "coef_")
    assert model.n_classes_ == (2, 2, 2, 2)


def test_seeded_subsets_and_orders_are_reproducible() -> None:
    X, Y = labels()
    for method in ("cc", "rakeld", "rakelo"):
        first = adapter(method).fit(X, Y).predict(X)
        second = adapter(method).fit(X, Y).predict(X)
        np.testing.assert_array_equal(first, second)


def test_a_label_that_never_occurs_in_the_training_fold() -> None:
    X, Y = labels()
    Y[:, 2] = 0
    for method in ("br", "cc", "lp", "mlknn"):
        model = adapter(method).fit(X, Y)
        assert np.all(model.predict(X)[:, 2] == 0)
        assert model.predict_proba(X)[2].shape == (120, 2)


def test_multi_class_targets_are_a_configuration_error() -> None:
    X, Y = labels()
    Y[0, 1] = 2
    with pytest.raises(ConfigurationError, match=r"needs binary targets, but target\(s\) \[1\]"):
        adapter("br").fit(X, Y)


def test_unknown_method_and_missing_base_are_configuration_errors() -> None:
    X, Y = labels()
    with pytest.raises(ConfigurationError, match="unknown multi-label method 'bogus'"):
        MultiLabelAdapter("bogus").fit(X, Y)
    with pytest.raises(ConfigurationError, match="'lp' needs a base classifier"):
        MultiLabelAdapter("lp").fit(X, Y)
