"""WEKA's NaiveBayes (``weka.classifiers.bayes.NaiveBayes``, 3.6), on nominal codes.

* class prior and nominal attributes: frequency estimates with a Laplace correction (every
  declared label starts with a count of 1);
* numeric attributes: a normal density integrated over the attribute's *precision* (the
  mean gap between adjacent distinct training values), values rounded to that precision,
  standard deviation at least precision / 6 (WEKA's ``NormalEstimator``); or, with
  ``numeric="kernel"``, a sum of such normal kernels, one per distinct value, with
  bandwidth range / sqrt(n) (``KernelEstimator``, option ``-K``); or, with
  ``numeric="discretize"``, Fayyad and Irani's MDL intervals treated as nominal labels
  (option ``-D``);
* a missing value is left out of its attribute's counts in training and the attribute is
  skipped when predicting; each factor is at least 1e-75, as in WEKA.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

import numpy as np
from scipy.special import ndtr
from sklearn.utils.validation import check_is_fitted

from touchbench.benchmark.weka._data import NanClassifier, check_test_data, check_training_data
from touchbench.benchmark.weka.discretize import mdl_cut_points

NumericModel = Literal["normal", "kernel", "discretize"]

#: WEKA's precision of a numeric attribute with fewer than two distinct values.
DEFAULT_PRECISION = 0.01
#: WEKA's floor of each factor of the product, against underflow.
MIN_FACTOR = 1e-75


class WekaNaiveBayes(NanClassifier):
    """Naive Bayes exactly as WEKA 3.6 computes it.

    Parameters
    ----------
    numeric : {"normal", "kernel", "discretize"}
        Model of numeric attributes: WEKA's default normal estimator, its kernel density
        estimator (``-K``) or supervised discretisation (``-D``).
    nominal_features : mapping of int to int, optional
        Nominal column index to its number of declared labels; other columns are numeric.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    nominal_ : dict of int to int
        The nominal columns.
    log_prior_ : ndarray of shape (n_classes,)
    log_tables_ : dict of int to ndarray of shape (n_classes, n_labels)
        Log-probabilities of each label of a nominal (or discretised) column.
    cut_points_ : dict of int to ndarray
        Interval boundaries of each discretised column (``numeric="discretize"``).
    precision_ : ndarray of shape (n_features,)
        Rounding precision of each numeric column (unused entries 0).
    mean_, std_ : ndarray of shape (n_classes, n_features)
        Normal estimators of numeric columns (``numeric="normal"``).
    kernels_ : dict of int to list of (values, weights) per class
        Kernel estimators (``numeric="kernel"``): distinct rounded values and their counts.
    kernel_std_ : ndarray of shape (n_classes, n_features)
    """

    def __init__(
        self, numeric: NumericModel = "normal", nominal_features: Mapping[int, int] | None = None
    ) -> None:
        self.numeric = numeric
        self.nominal_features = nominal_features

    def fit(self, X: object, y: object) -> WekaNaiveBayes:
        """Estimate every distribution from ``X`` (n_samples, n_features) and ``y``."""
        if self.numeric not in ("normal", "kernel", "discretize"):
            raise ValueError(
                f"numeric must be 'normal', 'kernel' or 'discretize', got {self.numeric!r}"
            )
        X, codes, nominal = check_training_data(self, X, y)
        n_classes = len(self.classes_)
        counts = np.bincount(codes, minlength=n_classes).astype(np.float64)
        self.log_prior_ = np.log((counts + 1.0) / (counts.sum() + n_classes))
        self.nominal_ = nominal
        self.log_tables_ = {}
        self.cut_points_ = {}
        numeric = [c for c in range(X.shape[1]) if c not in nominal]
        for column, n_labels in nominal.items():
            self.log_tables_[column] = _laplace_table(X[:, column], codes, n_classes, n_labels)
        if self.numeric == "discretize":
            for column in numeric:
                cuts = mdl_cut_points(X[:, column], codes, n_classes)
                self.cut_points_[column] = cuts
                binned = _bin(X[:, column], cuts)
                self.log_tables_[column] = _laplace_table(binned, codes, n_classes, cuts.size + 1)
            return self
        self.precision_ = np.zeros(X.shape[1])
        for column in numeric:
            self.precision_[column] = _precision(X[:, column])
        if self.numeric == "normal":
            self._fit_normal(X, codes, numeric)
        else:
            self._fit_kernel(X, codes, numeric)
        return self

    def _fit_normal(self, X: np.ndarray, codes: np.ndarray, numeric: list[int]) -> None:
        n_classes = len(self.classes_)
        self.mean_ = np.zeros((n_classes, X.shape[1]))
        self.std_ = np.ones((n_classes, X.shape[1]))
        for column in numeric:
            precision = self.precision_[column]
            rounded = _round(X[:, column], precision)
            for c in range(n_classes):
                values = rounded[(codes == c) & ~np.isnan(rounded)]
                std = precision / 6.0
                if values.size:
                    total, total_sq = values.sum(), (values * values).sum()
                    mean = total / values.size
                    spread = np.sqrt(abs(total_sq - mean * total) / values.size)
                    self.mean_[c, column] = mean
                    if spread > 1e-10:
                        std = max(precision / 6.0, spread)
                self.std_[c, column] = std

    def _fit_kernel(self, X: np.ndarray, codes: np.ndarray, numeric: list[int]) -> None:
        n_classes = len(self.classes_)
        self.kernels_ = {}
        self.kernel_std_ = np.ones((n_classes, X.shape[1]))
        for column in numeric:
            precision = self.precision_[column]
            rounded = _round(X[:, column], precision)
            per_class = []
            for c in range(n_classes):
                values, weights = np.unique(
                    rounded[(codes == c) & ~np.isnan(rounded)], return_counts=True
                )
                per_class.append((values, weights.astype(np.float64)))
                std = precision / 6.0
                if values.size and values[-1] > values[0]:
                    std = max((values[-1] - values[0]) / np.sqrt(weights.sum()), std)
                self.kernel_std_[c, column] = std
            self.kernels_[column] = per_class

    def predict_log_proba(self, X: object) -> np.ndarray:
        """Normalised log-probabilities of shape (n_samples, n_classes)."""
        joint = self._joint_log_likelihood(X)
        return joint - np.logaddexp.reduce(joint, axis=1, keepdims=True)

    def predict_proba(self, X: object) -> np.ndarray:
        """Probabilities of shape (n_samples, n_classes), columns as ``classes_``."""
        return np.exp(self.predict_log_proba(X))

    def _joint_log_likelihood(self, X: object) -> np.ndarray:
        check_is_fitted(self)
        X = check_test_data(self, X)
        joint = np.tile(self.log_prior_, (X.shape[0], 1))
        for column, table in self.log_tables_.items():
            values = X[:, column]
            if column in self.cut_points_:
                values = _bin(values, self.cut_points_[column])
            known = ~np.isnan(values)
            joint[known] += table[:, values[known].astype(np.intp)].T
        if self.numeric == "discretize":
            return joint
        for column in (c for c in range(X.shape[1]) if c not in self.nominal_):
            values = X[:, column]
            known = ~np.isnan(values)
            if self.numeric == "normal":
                factors = self._normal_probability(column, values[known])
            else:
                factors = self._kernel_probability(column, values[known])
            joint[known] += np.log(np.maximum(factors, MIN_FACTOR))
        return joint

    def _normal_probability(self, column: int, values: np.ndarray) -> np.ndarray:
        """P(value | class) of shape (n_values, n_classes), as ``NormalEstimator``."""
        precision = self.precision_[column]
        centred = _round(values, precision)[:, None] - self.mean_[:, column]
        std = self.std_[:, column]
        upper = ndtr((centred + precision / 2.0) / std)
        lower = ndtr((centred - precision / 2.0) / std)
        return np.asarray(upper - lower)

    def _kernel_probability(self, column: int, values: np.ndarray) -> np.ndarray:
        """P(value | class) of shape (n_values, n_classes), as ``KernelEstimator``."""
        precision = self.precision_[column]
        out = np.empty((values.size, len(self.classes_)))
        for c, (centres, weights) in enumerate(self.kernels_[column]):
            std = self.kernel_std_[c, column]
            if centres.size == 0:
                upper = ndtr((values + precision / 2.0) / std)
                out[:, c] = upper - ndtr((values - precision / 2.0) / std)
                continue
            delta = centres[None, :] - values[:, None]
            mass = ndtr((delta + precision / 2.0) / std) - ndtr((delta - precision / 2.0) / std)
            out[:, c] = mass @ weights / weights.sum()
        return out


def _precision(values: np.ndarray) -> float:
    """Mean gap between adjacent distinct values, 0.01 with fewer than two of them."""
    distinct = np.unique(values[~np.isnan(values)])
    if distinct.size < 2:
        return DEFAULT_PRECISION
    return float((distinct[-1] - distinct[0]) / (distinct.size - 1))


def _round(values: np.ndarray, precision: float) -> np.ndarray:
    """Values rounded to a multiple of ``precision`` (Java's ``Math.rint``: half to even)."""
    return np.rint(values / precision) * precision


def _laplace_table(
    values: np.ndarray, codes: np.ndarray, n_classes: int, n_labels: int
) -> np.ndarray:
    """log P(label | class) of shape (n_classes, n_labels), counts starting at 1."""
    known = ~np.isnan(values)
    table = np.ones((n_classes, n_labels))
    np.add.at(table, (codes[known], values[known].astype(np.intp)), 1.0)
    return np.log(table / table.sum(axis=1, keepdims=True))


def _bin(values: np.ndarray, cuts: np.ndarray) -> np.ndarray:
    """Interval index of each value (NaN stays NaN); ``v <= cuts[j]`` is interval ``j``."""
    out = np.searchsorted(cuts, values, side="left").astype(np.float64)
    out[np.isnan(values)] = np.nan
    return out
