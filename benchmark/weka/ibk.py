"""WEKA's IBk (``weka.classifiers.lazy.IBk``, 3.6): k nearest neighbours on WEKA's distance.

The distance is WEKA's ``EuclideanDistance``: a numeric attribute is normalised by the
range it spans, a nominal one differs by 0 (same label) or 1; a missing value differs by
1 from another missing value or any nominal label, and from a known numeric value ``v``
(normalised) by ``max(v, 1 - v)``.  Every training instance tied with the k-th nearest
counts as a neighbour; each class starts with a vote of ``1 / n_train`` and the votes are
normalised into probabilities.

WEKA widens the attribute ranges with each instance it is asked to classify, before
searching (``IBk.distributionForInstance`` calls ``addInstanceInfo``), so the ranges used
for the i-th row of a prediction call are those of the training data and rows ``0..i``.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Literal

import numpy as np
from sklearn.utils.validation import check_is_fitted

from touchbench.benchmark.weka._data import NanClassifier, check_test_data, check_training_data

Weighting = Literal["none", "inverse", "similarity"]

#: Bytes of each of the two scratch matrices of a block of prediction rows: small enough
#: for both to stay in a core's cache while every attribute passes over them.
BLOCK_BYTES = 512 * 2**10


class WekaIBk(NanClassifier):
    """k-nearest-neighbour classifier with WEKA's distance, ties and vote.

    Parameters
    ----------
    n_neighbors : int
        k (``-K``).
    weighting : {"none", "inverse", "similarity"}
        Vote of a neighbour at distance d: 1, ``1 / (d + 0.001)`` (``-I``) or ``1 - d``
        (``-F``), with d the Euclidean distance divided by the square root of the number
        of attributes.
    nominal_features : mapping of int to int, optional
        Nominal column index to its number of declared labels; other columns are numeric.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    nominal_ : dict of int to int
    X_ : ndarray of shape (n_train, n_features)
        The training instances.
    y_ : ndarray of shape (n_train,)
        Their class codes.
    minimum_, maximum_ : ndarray of shape (n_features,)
        Training range of each attribute (NaN when it has no known value).
    """

    def __init__(
        self,
        n_neighbors: int = 1,
        weighting: Weighting = "none",
        nominal_features: Mapping[int, int] | None = None,
    ) -> None:
        self.n_neighbors = n_neighbors
        self.weighting = weighting
        self.nominal_features = nominal_features

    def fit(self, X: object, y: object) -> WekaIBk:
        """Store the training instances ``X`` (n_samples, n_features) and labels ``y``."""
        if not isinstance(self.n_neighbors, int | np.integer) or self.n_neighbors < 1:
            raise ValueError(f"n_neighbors must be a positive integer, got {self.n_neighbors!r}")
        if self.weighting not in ("none", "inverse", "similarity"):
            raise ValueError(
                f"weighting must be 'none', 'inverse' or 'similarity', got {self.weighting!r}"
            )
        X, codes, nominal = check_training_data(self, X, y)
        self.nominal_ = nominal
        self.X_, self.y_ = X, codes
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns
            self.minimum_ = np.nanmin(X, axis=0) if X.size else np.full(X.shape[1], np.nan)
            self.maximum_ = np.nanmax(X, axis=0) if X.size else np.full(X.shape[1], np.nan)
        return self

    def predict_proba(self, X: object) -> np.ndarray:
        """Normalised votes of shape (n_samples, n_classes), columns as ``classes_``."""
        check_is_fitted(self)
        X = check_test_data(self, X)
        n_train, n_features = self.X_.shape
        low, high = self._ranges(X)
        # rows share their ranges until a row widens them: one block per stretch
        widened = np.any(
            (low[1:] != low[:-1]) & ~(np.isnan(low[1:]) & np.isnan(low[:-1]))
            | (high[1:] != high[:-1]) & ~(np.isnan(high[1:]) & np.isnan(high[:-1])),
            axis=1,
        )
        starts = [0, *(np.flatnonzero(widened) + 1).tolist()]
        block = max(1, BLOCK_BYTES // (8 * max(1, n_train)))
        out = np.empty((X.shape[0], len(self.classes_)))
        for start, end in zip(starts, [*starts[1:], X.shape[0]], strict=True):
            for first in range(start, end, block):
                last = min(first + block, end)
                squared = self._squared_distances(X[first:last], low[first], high[first])
                out[first:last] = self._vote(squared, n_features)
        return out

    def _ranges(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per-row attribute ranges: training ranges widened by rows 0..i of ``X``."""
        with np.errstate(all="ignore"):
            low = np.fmin.accumulate(np.vstack([self.minimum_, X]), axis=0)[1:]
            high = np.fmax.accumulate(np.vstack([self.maximum_, X]), axis=0)[1:]
        return low, high

    def _squared_distances(self, rows: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """Squared WEKA distances of shape (n_rows, n_train), ranges ``low..high``.

        Accumulated attribute by attribute, in WEKA's order and arithmetic, so that ties
        between neighbours are the ones WEKA sees; each attribute's differences go through
        one scratch block, written in place (a block that stays in the cache).
        """
        out = np.zeros((rows.shape[0], self.X_.shape[0]))
        scratch = np.empty_like(out)
        for column in range(rows.shape[1]):
            a, b = rows[:, column][:, None], self.X_[:, column][None, :]
            a_missing, b_missing = np.isnan(a), np.isnan(b)
            if column in self.nominal_:
                out += (a != b) | a_missing | b_missing
                continue
            width = high[column] - low[column]
            if width > 0:
                a, b = (a - low[column]) / width, (b - low[column]) / width
            else:  # no range: WEKA normalises every value to 0
                a, b = np.where(a_missing, np.nan, 0.0), np.where(b_missing, np.nan, 0.0)
            diff = np.subtract(a, b, out=scratch)
            if a_missing.any() or b_missing.any():
                one = np.where(a_missing, b, a)
                diff = np.where(a_missing ^ b_missing, np.maximum(one, 1.0 - one), diff)
                diff = np.where(a_missing & b_missing, 1.0, diff)
            out += np.multiply(diff, diff, out=scratch)
        return out

    def _vote(self, squared: np.ndarray, n_features: int) -> np.ndarray:
        """Class distributions of shape (n_rows, n_classes) from squared distances."""
        n_rows, n_train = squared.shape
        n_classes = len(self.classes_)
        k = min(self.n_neighbors, n_train)
        kth = np.partition(squared, k - 1, axis=1)[:, k - 1 : k]
        neighbour = squared <= kth  # every instance tied with the k-th nearest counts
        distance = np.sqrt(squared / n_features)
        if self.weighting == "inverse":
            weight = 1.0 / (distance + 0.001)
        elif self.weighting == "similarity":
            weight = 1.0 - distance
        else:
            weight = np.ones_like(distance)
        weight = np.where(neighbour, weight, 0.0)
        votes = np.full((n_rows, n_classes), 1.0 / max(1, n_train))
        for c in range(n_classes):
            # row by row: numpy adds a row of a many-row matrix in another order than the
            # row alone, and a row's votes must not depend on the rows predicted with it
            votes[:, c] += [row.sum() for row in weight[:, self.y_ == c]]
        return np.asarray(votes / votes.sum(axis=1, keepdims=True))
