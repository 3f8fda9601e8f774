"""Models trained on a whole data set, and their serialisation.

A :class:`TrainedModel` keeps the schema it was trained on, so that new instances can be
checked and predicted with the labels of that schema.  Serialised models are skops
artifacts (:mod:`benchmark.artifacts`): loading one cannot run code, whoever wrote it;
:func:`loads_model` also refuses bytes whose SHA-256 differs from the digest recorded when
they were stored (damage in transit or in the store).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from importlib import metadata
from typing import Any, Protocol

import numpy as np
from sklearn.base import BaseEstimator

from touchbench.benchmark.artifacts import dumps_artifact, loads_artifact
from touchbench.benchmark.catalogue import get_spec
from touchbench.benchmark.catalogue.predicting import predicts_most_probable
from touchbench.benchmark.dataset import Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import build_estimator, check_classifier, group_fit_params
from touchbench.benchmark.evaluation.metrics import expand_proba
from touchbench.benchmark.forest_inference import forest_proba
from touchbench.benchmark.problem import feature_matrix, problem_from_dataset

#: Libraries whose versions are recorded with a model.
RECORDED_LIBRARIES = ("numpy", "scikit-learn", "xgboost", "aeon")


@dataclass
class TrainedModel:
    """A fitted classifier and what it needs to predict.

    Parameters
    ----------
    classifier : str
        Catalogue id (one target) or ``META:BASE`` configuration (several targets).
    params : dict
        The configuration's parameters and its ``random_state``.
    schema : Schema
        The training data's schema: features in order, targets and their labels.
    estimator : BaseEstimator
        The fitted estimator (a catalogue pipeline or a multi-target classifier).
    versions : dict of str to str
        Versions of the libraries the model was fitted with.
    """

    classifier: str
    params: dict[str, Any]
    schema: Schema
    estimator: BaseEstimator
    versions: dict[str, str] = field(default_factory=dict)

    @property
    def n_classes(self) -> tuple[int, ...]:
        return tuple(len(target.values) for target in self.schema.targets)

    @property
    def regression(self) -> bool:
        """Whether it predicts numbers (its targets are numeric)."""
        return all(target.kind == "numeric" for target in self.schema.targets)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predicted target codes (a regression model: use :meth:`predict_values`).

        Parameters
        ----------
        X : ndarray of shape (n_instances, n_features)
            Features in the order of ``schema.features`` (as :attr:`Dataset.X`), nominal
            values as codes of the schema's labels, NaN for missing.

        Returns
        -------
        ndarray of shape (n_instances, n_targets), int64
        """
        return self._predicted(X, np.int64)

    def predict_values(self, X: np.ndarray) -> np.ndarray:
        """Predicted target values of a regression model: float64 of shape (n_instances,
        n_targets) from ``X`` as for :meth:`predict`."""
        return self._predicted(X, np.float64)

    def _predicted(self, X: np.ndarray, dtype: type[np.generic]) -> np.ndarray:
        features = self._features(X)
        predicted = np.asarray(self.estimator.predict(features), dtype=dtype)
        return predicted.reshape(features.shape[0], -1)

    def predict_proba(self, X: np.ndarray) -> list[np.ndarray]:
        """Class probabilities per target.

        Parameters
        ----------
        X : ndarray of shape (n_instances, n_features)
            As for :meth:`predict`.

        Returns
        -------
        list of ndarray of shape (n_instances, n_classes[t])
            One matrix per target, columns in the order of the target's labels.

        Raises
        ------
        NotImplementedError
            The classifier gives no probabilities (a regressor never does).
        """
        features = self._features(X)
        if self.regression or not hasattr(self.estimator, "predict_proba"):
            raise NotImplementedError(f"classifier '{self.classifier}' gives no probabilities")
        if len(self.schema.target_indices) == 1:
            proba = forest_proba(self.estimator, features)
            if proba is None:
                proba = self.estimator.predict_proba(features)
            return [expand_proba(proba, self.estimator.classes_, n_classes=self.n_classes[0])]
        return [np.asarray(p, dtype=np.float64) for p in self.estimator.predict_proba(features)]

    def predict_with_proba(self, X: np.ndarray) -> tuple[np.ndarray, list[np.ndarray] | None]:
        """Codes and probabilities at once, in one pass where the classifier allows it.

        A classifier that predicts its class of highest probability
        (:func:`benchmark.catalogue.predicting.predicts_most_probable`) has its codes read
        off the probabilities instead of running twice: live and served predictions pay for
        each pass.

        Returns
        -------
        codes : ndarray of shape (n_instances, n_targets), int64
        probabilities : list of ndarray of shape (n_instances, n_classes[t]) or None
            None when the classifier gives no probabilities.
        """
        try:
            probabilities = self.predict_proba(X)
        except NotImplementedError:
            return self.predict(X), None
        if self._predicts_most_probable():
            codes = np.column_stack([np.argmax(p, axis=1) for p in probabilities])
            return codes.astype(np.int64), probabilities
        return self.predict(X), probabilities

    def _predicts_most_probable(self) -> bool:
        return len(self.schema.target_indices) == 1 and predicts_most_probable(self.estimator)

    def _features(self, X: np.ndarray) -> np.ndarray:
        X = np.asarray(X, dtype=np.float64)
        expected = len(self.schema.feature_indices)
        if X.ndim != 2 or X.shape[1] != expected:
            raise ConfigurationError(
                f"the model expects {expected} feature columns "
                f"({', '.join(self.schema.feature_names[:5])}...), got an array of shape "
                f"{X.shape}"
            )
        return feature_matrix(self.schema, X)[0]


class Predictor(Protocol):
    """What predicting callers (served predictions, live sessions) use of a model: a
    :class:`TrainedModel`, or its ONNX twin (:class:`benchmark.export.onnx.OnnxModel`)."""

    @property
    def schema(self) -> Schema: ...

    @property
    def regression(self) -> bool: ...

    def predict_with_proba(self, X: np.ndarray) -> tuple[np.ndarray, list[np.ndarray] | None]: ...

    def predict_values(self, X: np.ndarray) -> np.ndarray: ...


def fit_model(dataset: Dataset, classifier_id: str, *, random_state: int = 0) -> TrainedModel:
    """Fit a classifier on every instance of a data set.

    Parameters
    ----------
    dataset : Dataset
        Training data; its targets decide between a catalogue classifier (one target),
        a multi-target configuration (several) and a regressor (numeric targets).
    classifier_id : str
        Catalogue id, ``META:BASE`` configuration id, or regressor id.
    random_state : int
        Seed of the classifier.

    Raises
    ------
    ConfigurationError
        Unknown classifier, a nominal target with a single class, no data.
    """
    problem, _ = problem_from_dataset(dataset)
    if problem.n_instances == 0:
        raise ConfigurationError("the data set has no instance with a known target to train on")
    if problem.kind == "regression":
        spec = check_classifier(classifier_id, problem)
        assert spec is not None
        estimator = build_estimator(classifier_id, problem, random_state=random_state)
        targets = problem.Y if problem.n_targets > 1 else problem.Y[:, 0]
        estimator.fit(problem.X, targets, **group_fit_params(estimator, problem.groups))
        return TrainedModel(
            classifier_id,
            {**spec.params, "random_state": random_state},
            dataset.schema,
            estimator,
            _library_versions(),
        )
    for name, column in zip(problem.target_names, problem.Y.T, strict=True):
        if np.unique(column).size < 2:
            raise ConfigurationError(
                f"target '{name}' has a single class in the training data; nothing to learn"
            )
    estimator = build_estimator(classifier_id, problem, random_state=random_state)
    if problem.kind == "multiclass":
        estimator.fit(problem.X, problem.Y[:, 0], **group_fit_params(estimator, problem.groups))
        params: dict[str, Any] = dict(get_spec(classifier_id).params)
    else:
        estimator.fit(problem.X, problem.Y)
        params = {"config": classifier_id}
    params["random_state"] = random_state
    return TrainedModel(classifier_id, params, dataset.schema, estimator, _library_versions())


def model_digest(data: bytes) -> str:
    """Hex SHA-256 of serialised model bytes."""
    return hashlib.sha256(data).hexdigest()


def dumps_model(model: TrainedModel) -> bytes:
    """Serialise a model as an artifact that cannot run code when loaded (store
    :func:`model_digest` of it beside it)."""
    return dumps_artifact(
        {
            "classifier": model.classifier,
            "params": model.params,
            "schema": model.schema.to_json(),
            "versions": model.versions,
            "estimator": model.estimator,
        }
    )


def loads_model(data: bytes, *, sha256: str) -> TrainedModel:
    """Deserialise a model after checking its bytes against their recorded digest.

    Raises
    ------
    ConfigurationError
        The digest differs, the bytes are not a touchbench artifact, or they name types
        outside the trusted packages (nothing is built from them then).
    """
    actual = model_digest(data)
    if actual != sha256.strip().lower():
        raise ConfigurationError(
            f"model bytes do not match their recorded sha256 ({sha256[:12]}..., got "
            f"{actual[:12]}...); refusing to load them"
        )
    content = loads_artifact(data)
    try:
        return TrainedModel(
            classifier=str(content["classifier"]),
            params=dict(content["params"]),
            schema=Schema.from_json(content["schema"]),
            estimator=content["estimator"],
            versions=dict(content.get("versions", {})),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise ConfigurationError(f"the stored model is incomplete: {exc}") from None


def _library_versions() -> dict[str, str]:
    versions = {}
    for name in RECORDED_LIBRARIES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return versions
