"""WEKA's ZeroR (``weka.classifiers.rules.ZeroR``): the majority class.

The class distribution is estimated with a Laplace correction (every class count starts
at 1), as WEKA's ``DiscreteEstimator`` does; the prediction is the most frequent class
(the first on ties).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.utils import Tags
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from touchbench.benchmark.weka._data import NanClassifier


class WekaZeroR(NanClassifier):
    """Predict the majority class with Laplace-corrected class frequencies.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    distribution_ : ndarray of shape (n_classes,)
        ``(count + 1) / (n + n_classes)`` per class.
    """

    def __sklearn_tags__(self) -> Tags:
        tags = super().__sklearn_tags__()
        if tags.classifier_tags is not None:
            tags.classifier_tags.poor_score = True
        return tags

    def fit(self, X: Any, y: Any) -> WekaZeroR:
        """Count the classes of ``y`` (n_samples,); ``X`` (n_samples, n_features) is unused."""
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", dtype=np.float64)
        check_classification_targets(y)
        self.classes_, codes = np.unique(y, return_inverse=True)
        counts = np.bincount(codes, minlength=len(self.classes_)) + 1.0
        self.distribution_ = counts / counts.sum()
        return self

    def predict_proba(self, X: Any) -> np.ndarray:
        """The class distribution for every row: shape (n_samples, n_classes)."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan", dtype=np.float64)
        return np.tile(self.distribution_, (X.shape[0], 1))
