"""What every multi-target meta-classifier shares: input checks, fitted attributes, tags."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils import Tags
from sklearn.utils.validation import check_is_fitted, validate_data

from touchbench.benchmark.targets import TargetError, validate_targets


def check_at_least_one(name: str, value: int) -> None:
    """Check that the count parameter ``name`` is at least 1.

    Raises
    ------
    TargetError
        ``value`` is below 1.
    """
    if value < 1:
        raise TargetError(f"{name} must be at least 1, got {value}")


class MultiTargetClassifier(ClassifierMixin, BaseEstimator):
    """Base class of the multi-target meta-classifiers.

    Subclasses implement ``fit``, ``predict_proba`` and ``predict`` with
    ``X`` of shape (n_samples, n_features), float64 with NaN for missing values (left to
    the base classifier, e.g. a pipeline that imputes), and ``Y`` of shape
    (n_samples, n_targets) holding integer class codes.

    Fitted attributes set by :meth:`_validate_training_data`:

    - ``n_features_in_`` : int
    - ``n_targets_`` : int
    - ``n_classes_`` : tuple of int, classes per target (the ``n_classes`` parameter, or
      ``max(code) + 1`` of the training data)
    - ``classes_`` : list of ndarray, ``arange(n_classes_[t])`` per target
    """

    n_classes: Sequence[int] | None

    def _validate_training_data(self, X: object, Y: object) -> tuple[np.ndarray, np.ndarray]:
        """Check ``X`` and ``Y`` and record their shapes; returns float X and int Y."""
        X_checked = validate_data(
            self, X, reset=True, dtype=np.float64, ensure_all_finite="allow-nan"
        )
        codes, n_classes = validate_targets(Y, self.n_classes, n_samples=X_checked.shape[0])
        self.n_targets_ = codes.shape[1]
        self.n_classes_ = n_classes
        self.classes_ = [np.arange(k) for k in n_classes]
        return X_checked, codes

    def _validate_prediction_data(self, X: object) -> np.ndarray:
        """Check a fitted model and the ``X`` to predict; returns float X."""
        check_is_fitted(self, "n_classes_")
        return validate_data(self, X, reset=False, dtype=np.float64, ensure_all_finite="allow-nan")

    def score(self, X: object, y: object, sample_weight: object = None) -> float:
        """Hamming score (mean over samples and targets of correct values), MEKA's headline.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
        y : array-like of shape (n_samples, n_targets)
        sample_weight : array-like of shape (n_samples,), optional
        """
        codes, _ = validate_targets(y)
        correct = (self.predict(X) == codes).mean(axis=1)
        weights = None if sample_weight is None else np.asarray(sample_weight, dtype=np.float64)
        return float(np.average(correct, weights=weights))

    def __sklearn_tags__(self) -> Tags:
        tags = super().__sklearn_tags__()
        tags.input_tags.allow_nan = True
        tags.target_tags.multi_output = True
        tags.target_tags.single_output = False
        return tags
