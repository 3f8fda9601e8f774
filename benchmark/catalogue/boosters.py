"""LightGBM and CatBoost behind scikit-learn's contract, nominal attributes passed natively.

Both take the engine's matrix (nominal columns as label codes, NaN for missing) and the
nominal columns through ``nominal_features`` (set by the catalogue's pipeline): LightGBM
gets them as ``categorical_feature`` (NaN stays missing), CatBoost as ``cat_features``
(integer codes, a missing value as its own category -1, as CatBoost treats a missing
string).  A training set with a single class predicts it without fitting.  The libraries
are imported on first use so that a worker that never needs them does not pay for them.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils import Tags
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from touchbench.benchmark.extras import require


class _NominalBooster(ClassifierMixin, BaseEstimator):
    """Shared fit/predict of the wrappers: label encoding and the single-class case."""

    nominal_features: Mapping[int, int] | None
    random_state: int | None

    def __sklearn_tags__(self) -> Tags:
        tags = super().__sklearn_tags__()
        tags.input_tags.allow_nan = True
        return tags

    def fit(self, X: Any, y: Any) -> _NominalBooster:
        """Fit on ``X`` of shape (n_samples, n_features) and labels ``y`` (n_samples,)."""
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", dtype=np.float64)
        check_classification_targets(y)
        self.classes_, codes = np.unique(y, return_inverse=True)
        self.nominal_ = sorted(int(c) for c in (self.nominal_features or {}))
        self.model_ = None
        if len(self.classes_) > 1:
            self.model_ = self._fit_model(X, codes)
        return self

    def predict_proba(self, X: Any) -> np.ndarray:
        """Probabilities of shape (n_samples, n_classes), columns as ``classes_``."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan", dtype=np.float64)
        if self.model_ is None:
            return np.ones((X.shape[0], 1))
        return np.asarray(self.model_.predict_proba(self._prepare(X)), dtype=np.float64)

    def predict(self, X: Any) -> np.ndarray:
        """Labels of shape (n_samples,)."""
        proba = self.predict_proba(X)
        return np.asarray(self.classes_[np.argmax(proba, axis=1)])

    def _prepare(self, X: np.ndarray) -> Any:
        return X

    def _fit_model(self, X: np.ndarray, codes: np.ndarray) -> Any:
        raise NotImplementedError


class LightGBMClassifier(_NominalBooster):
    """LightGBM gradient boosting (``lightgbm.LGBMClassifier``), one thread, quiet.

    Parameters
    ----------
    n_estimators, learning_rate, num_leaves, min_child_samples : LightGBM's parameters
    subsample, subsample_freq, colsample_bytree, reg_lambda : LightGBM's parameters
    boosting_type : {"gbdt", "dart", "rf"}
    class_weight : None or "balanced"
    random_state : int or None
    nominal_features : mapping of int to int, optional
        Nominal column index to its number of labels (passed as categorical).

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    model_ : lightgbm.LGBMClassifier or None
        The fitted booster (None when training saw a single class).
    """

    #: The optional modules it needs (:mod:`benchmark.extras`).
    REQUIRES = ("lightgbm",)

    def __init__(
        self,
        n_estimators: int = 300,
        learning_rate: float = 0.05,
        num_leaves: int = 31,
        min_child_samples: int = 10,
        subsample: float = 1.0,
        subsample_freq: int = 0,
        colsample_bytree: float = 1.0,
        reg_lambda: float = 0.0,
        boosting_type: str = "gbdt",
        class_weight: str | None = None,
        random_state: int | None = None,
        nominal_features: Mapping[int, int] | None = None,
    ) -> None:
        self.n_estimators = n_estimators
        self.learning_rate = learning_rate
        self.num_leaves = num_leaves
        self.min_child_samples = min_child_samples
        self.subsample = subsample
        self.subsample_freq = subsample_freq
        self.colsample_bytree = colsample_bytree
        self.reg_lambda = reg_lambda
        self.boosting_type = boosting_type
        self.class_weight = class_weight
        self.random_state = random_state
        self.nominal_features = nominal_features

    def _fit_model(self, X: np.ndarray, codes: np.ndarray) -> Any:
        require(self.REQUIRES, "LightGBM")
        from lightgbm import LGBMClassifier

        params = self.get_params()
        del params["nominal_features"]
        model = LGBMClassifier(**params, n_jobs=1, verbose=-1)
        return model.fit(X, codes, categorical_feature=self.nominal_ or "auto")


class CatBoostNominalClassifier(_NominalBooster):
    """CatBoost (``catboost.CatBoostClassifier``) with nominal codes as ``cat_features``.

    Parameters
    ----------
    iterations, depth, learning_rate, l2_leaf_reg : CatBoost's parameters
    auto_class_weights : None or "Balanced"
    random_state : int or None
    nominal_features : mapping of int to int, optional
        Nominal column index to its number of labels.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    model_ : catboost.CatBoostClassifier or None
    """

    #: The optional modules it needs (:mod:`benchmark.extras`).
    REQUIRES = ("catboost",)

    def __init__(
        self,
        iterations: int = 300,
        depth: int = 6,
        learning_rate: float | None = None,
        l2_leaf_reg: float = 3.0,
        auto_class_weights: str | None = None,
        random_state: int | None = None,
        nominal_features: Mapping[int, int] | None = None,
    ) -> None:
        self.iterations = iterations
        self.depth = depth
        self.learning_rate = learning_rate
        self.l2_leaf_reg = l2_leaf_reg
        self.auto_class_weights = auto_class_weights
        self.random_state = random_state
        self.nominal_features = nominal_features

    def _prepare(self, X: np.ndarray) -> Any:
        """Nominal columns as integer codes (missing: -1) in an object array, if any."""
        if not self.nominal_:
            return X
        out = X.astype(object)
        for column in self.nominal_:
            values = X[:, column]
            out[:, column] = np.where(np.isnan(values), -1, values).astype(np.int64)
        return out

    def _fit_model(self, X: np.ndarray, codes: np.ndarray) -> Any:
        require(self.REQUIRES, "CatBoost")
        from catboost import CatBoostClassifier

        model = CatBoostClassifier(
            iterations=self.iterations,
            depth=self.depth,
            learning_rate=self.learning_rate,
            l2_leaf_reg=self.l2_leaf_reg,
            auto_class_weights=self.auto_class_weights,
            random_seed=self.random_state,
            cat_features=self.nominal_ or None,
            thread_count=1,
            verbose=0,
            allow_writing_files=False,
        )
        return model.fit(self._prepare(X), codes)
