"""Small estimators the catalogue needs that scikit-learn does not ship.

Both follow scikit-learn's estimator contract (``__init__`` only stores parameters,
``fit`` sets attributes ending in ``_`` and returns ``self``), so ``clone``, pipelines and
meta-classifiers handle them like any other classifier.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.tree import DecisionTreeClassifier
from sklearn.utils.validation import check_is_fitted, validate_data


class LabelEncodedClassifier(ClassifierMixin, BaseEstimator):
    """Fit ``estimator`` on contiguous labels ``0..m-1`` whatever labels ``y`` holds.

    XGBoost insists that the classes of a training set are exactly ``0..m-1``; in a
    cross-validation fold or a classifier chain some classes may be absent, so the labels
    present are encoded before fitting and decoded after predicting.  A training set with
    a single class predicts that class (probability 1) without fitting ``estimator``.

    Parameters
    ----------
    estimator : classifier
        The classifier to fit on encoded labels (cloned, never fitted itself).

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes_present,)
        The labels seen in training, sorted.
    estimator_ : classifier or None
        The fitted clone, ``None`` when training saw a single class.
    """

    def __init__(self, estimator: Any = None) -> None:
        self.estimator = estimator

    def fit(self, X: np.ndarray, y: np.ndarray, **fit_params: Any) -> LabelEncodedClassifier:
        """Fit on ``X`` of shape (n_samples, n_features) and labels ``y`` (n_samples,)."""
        if self.estimator is None:
            raise ValueError("LabelEncodedClassifier needs an estimator")
        X, y = validate_data(self, X, y, ensure_all_finite=False)
        self.classes_, encoded = np.unique(y, return_inverse=True)
        self.estimator_ = None
        if len(self.classes_) > 1:
            self.estimator_ = clone(self.estimator).fit(X, encoded, **fit_params)
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Labels of shape (n_samples,)."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite=False)
        if self.estimator_ is None:
            return np.full(X.shape[0], self.classes_[0])
        return self.classes_[np.asarray(self.estimator_.predict(X), dtype=np.intp)]

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Probabilities of shape (n_samples, n_classes_present), columns as ``classes_``."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite=False)
        if self.estimator_ is None:
            return np.ones((X.shape[0], 1))
        return np.asarray(self.estimator_.predict_proba(X))


class OneRuleClassifier(ClassifierMixin, BaseEstimator):
    """OneR-like rule: the single feature whose interval rule classifies training best.

    For every feature a one-dimensional decision tree with at least ``min_bucket``
    instances per interval is grown (WEKA's OneR discretises each attribute into buckets
    of at least 6); the feature with the highest training accuracy is kept.

    Parameters
    ----------
    min_bucket : int
        Minimum number of training instances per interval.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    feature_ : int
        Index of the chosen feature.
    tree_ : DecisionTreeClassifier
        The interval rule on that feature.
    """

    def __init__(self, min_bucket: int = 6) -> None:
        self.min_bucket = min_bucket

    def fit(self, X: np.ndarray, y: np.ndarray) -> OneRuleClassifier:
        """Fit on ``X`` of shape (n_samples, n_features) and labels ``y`` (n_samples,)."""
        X, y = validate_data(self, X, y)
        self.classes_ = np.unique(y)
        best_accuracy = -1.0
        for feature in range(X.shape[1]):
            column = X[:, [feature]]
            tree = DecisionTreeClassifier(min_samples_leaf=self.min_bucket, random_state=0)
            tree.fit(column, y)
            accuracy = float(np.mean(tree.predict(column) == y))
            if accuracy > best_accuracy:
                best_accuracy, self.feature_, self.tree_ = accuracy, feature, tree
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Labels of shape (n_samples,)."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False)
        return np.asarray(self.tree_.predict(X[:, [self.feature_]]))

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Probabilities of shape (n_samples, n_classes), columns as ``classes_``."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False)
        return np.asarray(self.tree_.predict_proba(X[:, [self.feature_]]))
