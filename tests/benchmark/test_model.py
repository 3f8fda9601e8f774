"""Trained models: fit on a whole data set, predict with the schema's labels, serialise."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.synthetic import nominal_dataset
from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.model import (
    TrainedModel,
    dumps_model,
    fit_model,
    loads_model,
    model_digest,
)


def features(data: Dataset) -> np.ndarray:
    return data.X


def test_fit_predict_and_probabilities_of_a_catalogue_classifier() -> None:
    data = nominal_dataset()
    model = fit_model(data, "logistic", random_state=4)
    assert model.classifier == "logistic"
    assert model.params["random_state"] == 4 and model.params["C"] == 10.0
    assert "scikit-learn" in model.versions
    predicted = model.predict(data.X)
    assert predicted.shape == (90, 1) and predicted.dtype == np.int64
    assert np.mean(predicted[:, 0] == data.Y[:, 0]) > 0.8
    [proba] = model.predict_proba(data.X)
    assert proba.shape == (90, 3)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0)


def test_a_model_without_probabilities_says_so() -> None:
    model = fit_model(nominal_dataset(), "svm-rbf")
    with pytest.raises(NotImplementedError, match="classifier 'svm-rbf' gives no probabilities"):
        model.predict_proba(nominal_dataset().X)


def test_multitarget_models_predict_every_target() -> None:
    data = nominal_dataset(targets=2)
    model = fit_model(data, "cc:j48")
    predicted = model.predict(data.X)
    assert predicted.shape == (90, 2)
    assert np.mean(predicted == data.Y) > 0.8
    probas = model.predict_proba(data.X)
    assert [p.shape for p in probas] == [(90, 3), (90, 2)]


def test_wrong_feature_count_is_refused() -> None:
    model = fit_model(nominal_dataset(), "nb")
    with pytest.raises(ConfigurationError, match="expects 4 feature columns"):
        model.predict(np.zeros((2, 5)))


@pytest.mark.parametrize(
    ("classifier", "mutate", "message"),
    [
        ("rff", None, "unknown classifier 'rff'; did you mean 'rf'"),
        ("nb", "one_class", "target 'gesture' has a single class"),
        ("nb", "numeric_target", "classifier 'nb' has no regressor: the targets are numeric"),
    ],
)
def test_bad_training_requests(classifier: str, mutate: str | None, message: str) -> None:
    data = nominal_dataset()
    if mutate == "one_class":
        data.values[:, 0] = 1
    if mutate == "numeric_target":
        data = data.with_targets([4])
    with pytest.raises(ConfigurationError, match=message):
        fit_model(data, classifier)


def test_serialised_models_load_only_with_their_digest() -> None:
    data = nominal_dataset()
    model = fit_model(data, "j48")
    blob = dumps_model(model)
    digest = model_digest(blob)
    again = loads_model(blob, sha256=digest.upper())
    assert isinstance(again, TrainedModel) and again.schema == model.schema
    np.testing.assert_array_equal(again.predict(data.X), model.predict(data.X))
    tampered = blob[:-1] + bytes([blob[-1] ^ 1])
    with pytest.raises(ConfigurationError, match="do not match their recorded sha256"):
        loads_model(tampered, sha256=digest)
    import pickle

    other = pickle.dumps({"not": "a model"})
    with pytest.raises(ConfigurationError, match="not a skops artifact"):
        loads_model(other, sha256=model_digest(other))


@pytest.mark.parametrize(
    "classifier",
    [
        "rf",
        "extra-trees",
        "cart",
        "nb",
        "nb-gaussian",
        "logistic",
        "knn5",
        "calibrated-nb",
        "cc:j48",
    ],
)
def test_codes_and_probabilities_in_one_pass_agree_with_predict(classifier: str) -> None:
    data = nominal_dataset(targets=2 if ":" in classifier else 1)
    model = fit_model(data, classifier)
    codes, probabilities = model.predict_with_proba(data.X)
    np.testing.assert_array_equal(codes, model.predict(data.X))
    assert probabilities is not None
    for mine, theirs in zip(probabilities, model.predict_proba(data.X), strict=True):
        np.testing.assert_allclose(mine, theirs)
