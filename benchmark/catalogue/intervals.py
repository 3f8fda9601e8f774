"""Random-interval summary features of multichannel sequences (the interval family of
time-series classification: TSF, DrCIF and aeon's ``RandomIntervalClassifier``).

Each sequence is seen in three representations, as DrCIF sees it: the series itself,
its first difference, and its amplitude spectrum ``|rfft(x)|``.  In each representation
``n_intervals`` intervals are drawn once at fit time (a channel, a start, a length of at
least ``min_length`` steps), and every interval gives seven statistics of its values:
mean, standard deviation, least-squares slope, median, interquartile range, minimum and
maximum.  The fitted state is three integer arrays, so a model that holds it stores as
plain data (aeon's own interval transformers hold compiled functions and generators,
which a safe model file cannot represent).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted

#: Statistics of each interval, in output order.
STATISTICS = ("mean", "std", "slope", "median", "iqr", "min", "max")
#: Representations of each sequence, in output order.
REPRESENTATIONS = ("series", "difference", "spectrum")


class RandomIntervalFeatures(TransformerMixin, BaseEstimator):
    """Seven statistics over random intervals of three representations of each sequence.

    Parameters
    ----------
    n_intervals : int or None
        Intervals per representation; ``None``: ``4 + sqrt(length * n_channels)`` (DrCIF's
        rule).
    min_length : int
        Fewest steps of an interval (shorter representations use all their steps).
    random_state : int, RandomState or None
        Seed of the draw.

    Attributes
    ----------
    intervals_ : list of ndarray of shape (n_intervals_, 3), int64
        Per representation: channel, first step, one past the last step.
    n_channels_, length_ : int
        Shape of the sequences seen in fit.
    """

    def __init__(
        self, n_intervals: int | None = None, min_length: int = 3, random_state: Any = None
    ) -> None:
        self.n_intervals = n_intervals
        self.min_length = min_length
        self.random_state = random_state

    def fit(self, X: np.ndarray, y: Any = None) -> RandomIntervalFeatures:
        """Draw the intervals for sequences ``X`` of shape (n, n_channels, length)."""
        X = _check_panel(X)
        _, self.n_channels_, self.length_ = X.shape
        rng = check_random_state(self.random_state)
        count = self.n_intervals or 4 + int(math.sqrt(self.length_ * self.n_channels_))
        self.intervals_ = []
        for representation in _representations(X[:1]):
            length = representation.shape[-1]
            shortest = min(self.min_length, length)
            sizes = rng.randint(shortest, length + 1, size=count)
            starts = rng.randint(0, length - sizes + 1)
            channels = rng.randint(0, self.n_channels_, size=count)
            self.intervals_.append(
                np.stack([channels, starts, starts + sizes], axis=1).astype(np.int64)
            )
        return self

    def transform(self, X: np.ndarray) -> np.ndarray:
        """Features of shape (n, 3 * n_intervals_ * 7): representation-major, then interval,
        then :data:`STATISTICS`."""
        check_is_fitted(self)
        X = _check_panel(X)
        if X.shape[1:] != (self.n_channels_, self.length_):
            raise ValueError(
                f"sequences of shape {X.shape[1:]} differ from the {self.n_channels_} x "
                f"{self.length_} seen in fit"
            )
        blocks = [
            _interval_statistics(representation, intervals)
            for representation, intervals in zip(_representations(X), self.intervals_, strict=True)
        ]
        return np.concatenate(blocks, axis=1)


def _check_panel(X: np.ndarray) -> np.ndarray:
    X = np.asarray(X, dtype=np.float64)
    if X.ndim != 3 or X.shape[2] < 2:
        raise ValueError(f"sequences must have shape (n, n_channels, length >= 2), got {X.shape}")
    if not np.isfinite(X).all():
        raise ValueError("sequences must be finite (impute missing values first)")
    return X


def _representations(X: np.ndarray) -> list[np.ndarray]:
    """The series, its first difference and its amplitude spectrum, each (n, c, steps)."""
    return [X, np.diff(X, axis=-1), np.abs(np.fft.rfft(X, axis=-1))]


def _interval_statistics(X: np.ndarray, intervals: np.ndarray) -> np.ndarray:
    """:data:`STATISTICS` of each interval, shape (n, n_intervals * 7)."""
    out = np.empty((X.shape[0], intervals.shape[0], len(STATISTICS)))
    for i, (channel, start, stop) in enumerate(intervals.tolist()):
        values = X[:, channel, start:stop]
        steps = np.arange(stop - start, dtype=np.float64)
        centred = steps - steps.mean()
        spread = float(centred @ centred)
        q25, median, q75 = np.percentile(values, [25, 50, 75], axis=1)
        out[:, i, 0] = values.mean(axis=1)
        out[:, i, 1] = values.std(axis=1)
        out[:, i, 2] = values @ centred / spread if spread > 0 else 0.0
        out[:, i, 3] = median
        out[:, i, 4] = q75 - q25
        out[:, i, 5] = values.min(axis=1)
        out[:, i, 6] = values.max(axis=1)
    return out.reshape(X.shape[0], -1)
