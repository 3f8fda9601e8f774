"""One target's classifier: any base estimator, made robust to what a training fold lacks.

Every meta-classifier in this package fits its base classifiers through
:class:`TargetClassifier`, so that all of them behave the same way when a training fold
lacks a class, holds a single class, or the base cannot estimate probabilities.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.pipeline import Pipeline
from sklearn.utils.validation import check_is_fitted, has_fit_parameter

from touchbench.benchmark.targets import one_hot


class TargetClassifier(ClassifierMixin, BaseEstimator):
    """A classifier over class codes ``0 .. n_classes - 1`` whatever the training data holds.

    The base estimator is trained on the classes present, re-coded ``0 .. m - 1`` (some
    bases, XGBoost among them, refuse gaps in the labels), and its outputs are mapped back.

    - A class absent from the training data gets probability 0 and is never predicted.
    - With a single class present no base is fitted: that class is predicted with
      probability 1 (most bases refuse one-class data).
    - A base without ``predict_proba`` (``SVC(probability=False)``...) falls back to the
      one-hot encoding of its predictions; :attr:`probabilistic_` tells which happened.
    - Sample weights go to the base when it (or a pipeline's last step) accepts them and
      are dropped otherwise.

    Parameters
    ----------
    estimator : classifier
        The base classifier (cloned, never fitted itself).
    n_classes : int, optional
        Number of classes; by default ``max(y) + 1`` of the training data.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
        ``0 .. n_classes - 1``.
    present_classes_ : ndarray of shape (m,)
        The classes seen in training, ascending.
    estimator_ : classifier or None
        The fitted base; ``None`` when training data held a single class.
    probabilistic_ : bool
        Whether :meth:`predict_proba` comes from the base's own probabilities.
    """

    estimator_: Any

    def __init__(self, estimator: Any, n_classes: int | None = None) -> None:
        self.estimator = estimator
        self.n_classes = n_classes

    def fit(
        self, X: np.ndarray, y: np.ndarray, sample_weight: np.ndarray | None = None
    ) -> TargetClassifier:
        """Fit the base on the classes present in ``y``.

        Parameters
        ----------
        X : ndarray of shape (n_samples, n_features)
        y : ndarray of shape (n_samples,), int codes
        sample_weight : ndarray of shape (n_samples,), optional
        """
        codes = np.asarray(y).astype(np.int64)
        n_classes = int(codes.max()) + 1 if self.n_classes is None else int(self.n_classes)
        self.classes_ = np.arange(n_classes)
        self.present_classes_, recoded = np.unique(codes, return_inverse=True)
        if self.present_classes_.shape[0] == 1:
            self.estimator_ = None
            self.probabilistic_ = True
            return self
        self.estimator_ = clone(self.estimator)
        self.estimator_.fit(X, recoded, **_weight_arguments(self.estimator_, sample_weight))
        self.probabilistic_ = hasattr(self.estimator_, "predict_proba")
        return self

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Probability of every class.

        Returns
        -------
        ndarray of shape (n_samples, n_classes)
            Columns of classes absent from training are 0.
        """
        check_is_fitted(self, "classes_")
        n_samples = np.asarray(X).shape[0]
        proba = np.zeros((n_samples, self.classes_.shape[0]), dtype=np.float64)
        if self.estimator_ is None:
            proba[:, self.present_classes_[0]] = 1.0
        elif self.probabilistic_:
            proba[:, self.present_classes_] = self.estimator_.predict_proba(X)
        else:
            predicted = np.asarray(self.estimator_.predict(X)).astype(np.int64)
            proba[:, self.present_classes_] = one_hot(predicted, self.present_classes_.shape[0])
        return proba

    def predict(self, X: np.ndarray) -> np.ndarray:
        """The most probable class of each sample.

        Returns
        -------
        ndarray of shape (n_samples,), int64
        """
        return np.argmax(self.predict_proba(X), axis=1).astype(np.int64)


def _weight_arguments(estimator: Any, sample_weight: np.ndarray | None) -> dict[str, Any]:
    """Keyword arguments that pass ``sample_weight`` to ``estimator.fit`` where accepted."""
    if sample_weight is None or np.all(sample_weight == 1.0):
        return {}
    if isinstance(estimator, Pipeline):
        name, final = estimator.steps[-1]
        if has_fit_parameter(final, "sample_weight"):
            return {f"{name}__sample_weight": sample_weight}
        return {}
    if has_fit_parameter(estimator, "sample_weight"):
        return {"sample_weight": sample_weight}
    return {}
