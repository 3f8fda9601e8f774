"""Input checks shared by the WEKA-faithful estimators.

These estimators take the engine's matrix as it is: float64, nominal attributes as label
codes ``0..k-1`` (WEKA's internal encoding), NaN for a missing value.  Which columns are
nominal, and how many labels each declares, is the ``nominal_features`` parameter.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils import Tags
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import validate_data


class NanClassifier(ClassifierMixin, BaseEstimator):
    """Base of classifiers that take NaN as a missing value and predict the likeliest class.

    Subclasses implement ``predict_proba`` (which checks that the model is fitted); the
    prediction is the first class of highest probability, as WEKA's ``Utils.maxIndex``.
    """

    classes_: np.ndarray

    def __sklearn_tags__(self) -> Tags:
        tags = super().__sklearn_tags__()
        tags.input_tags.allow_nan = True
        return tags

    def predict_proba(self, X: Any) -> np.ndarray:
        raise NotImplementedError

    def predict(self, X: Any) -> np.ndarray:
        """Labels of shape (n_samples,): the most probable class (the first on ties)."""
        proba = self.predict_proba(X)
        return np.asarray(self.classes_[np.argmax(proba, axis=1)])


def nominal_columns(nominal_features: Mapping[int, int] | None, n_features: int) -> dict[int, int]:
    """``nominal_features`` checked against the number of columns.

    Parameters
    ----------
    nominal_features : mapping of int to int or None
        Column index to its number of declared labels.
    n_features : int
        Number of columns of ``X``.

    Returns
    -------
    dict of int to int
        A plain copy, sorted by column.

    Raises
    ------
    ValueError
        A column outside ``0..n_features-1`` or fewer than one label.
    """
    out: dict[int, int] = {}
    for column, n_labels in sorted((nominal_features or {}).items()):
        if not 0 <= int(column) < n_features:
            raise ValueError(
                f"nominal feature column {column} is outside the {n_features} columns of X"
            )
        if int(n_labels) < 1:
            raise ValueError(f"nominal feature column {column} declares {n_labels} labels")
        out[int(column)] = int(n_labels)
    return out


def check_training_data(
    estimator: Any, X: Any, y: Any
) -> tuple[np.ndarray, np.ndarray, dict[int, int]]:
    """Validate training data, set ``classes_`` and return encoded labels.

    Returns
    -------
    X : ndarray of shape (n_samples, n_features), float64, NaN for missing
    y : ndarray of shape (n_samples,), int64 codes into ``estimator.classes_``
    nominal : dict of int to int
        The checked ``estimator.nominal_features``.
    """
    X, y = validate_data(estimator, X, y, ensure_all_finite="allow-nan", dtype=np.float64)
    check_classification_targets(y)
    estimator.classes_, codes = np.unique(y, return_inverse=True)
    nominal = nominal_columns(estimator.nominal_features, X.shape[1])
    check_codes(X, nominal)
    return X, codes.astype(np.int64), nominal


def check_test_data(estimator: Any, X: Any) -> np.ndarray:
    """Validate prediction data against what ``fit`` saw; float64 with NaN for missing."""
    X = validate_data(estimator, X, reset=False, ensure_all_finite="allow-nan", dtype=np.float64)
    check_codes(X, estimator.nominal_)
    return np.asarray(X)


def check_codes(X: np.ndarray, nominal: Mapping[int, int]) -> None:
    """Raise ValueError unless every nominal column holds codes ``0..k-1`` or NaN."""
    for column, n_labels in nominal.items():
        values = X[:, column]
        known = values[~np.isnan(values)]
        bad = (known < 0) | (known >= n_labels) | (known != np.floor(known))
        if bad.any():
            raise ValueError(
                f"nominal feature column {column} holds {float(known[bad][0])!r}; "
                f"its codes must be whole numbers in 0..{n_labels - 1} (NaN for missing)"
            )
