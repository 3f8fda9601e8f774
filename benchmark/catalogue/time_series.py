"""Time-series classifiers of a sequence data set's windows (:mod:`benchmark.sequence`).

Each takes the flat feature matrix every catalogue pipeline passes on and its
``sequence`` parameter, ``(start, n_channels, length)``, set by
:func:`benchmark.catalogue.build_pipeline`: the block of columns from ``start`` is
reshaped into sequences of shape (n_channels, length) and transformed; any other column
(a flat feature beside the sequence, a multi-target chain's parent targets) is appended
to the transform's features before the final classifier.

* :class:`RocketClassifier`: aeon's MiniRocket or MultiRocket transform (random
  dilated convolutions, proportion of positive values and, for MultiRocket, three more
  pooling operators over the series and its first difference), then a ridge
  classifier whose penalty is chosen by leave-one-out cross-validation on standardised
  features, as aeon's ``MiniRocketClassifier`` does.  A fitted MiniRocket or MultiRocket
  holds its kernels as integer and float arrays; a model file names its class, and
  nothing else of aeon (:mod:`benchmark.artifacts` trusts exactly these two classes).
* :class:`IntervalForestClassifier`: random-interval statistics
  (:mod:`benchmark.catalogue.intervals`) and extremely randomised trees.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.linear_model import RidgeClassifierCV
from sklearn.pipeline import Pipeline, make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import check_is_fitted, validate_data

from touchbench.benchmark.catalogue.intervals import RandomIntervalFeatures
from touchbench.benchmark.extras import require
from touchbench.benchmark.sequence import panel

#: The transforms :class:`RocketClassifier` offers, by name.
ROCKETS = ("minirocket", "multirocket")
#: Penalties the ridge classifier chooses from (aeon's MiniRocketClassifier's).
RIDGE_ALPHAS = tuple(np.logspace(-3, 3, 10).tolist())


class _SequenceClassifier(ClassifierMixin, BaseEstimator):
    """Sequences through ``_make_transform()``, other columns appended, then ``_make_head()``.

    Subclasses store ``sequence`` and ``random_state`` among their parameters.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    transform_ : transformer
        Fitted on the training sequences, of shape (n, n_channels, length).
    head_ : classifier
        Fitted on the transform's features followed by the other columns.
    """

    sequence: tuple[int, int, int] | None

    def _make_transform(self) -> Any:
        raise NotImplementedError

    def _make_head(self) -> Any:
        raise NotImplementedError

    def fit(self, X: np.ndarray, y: np.ndarray) -> _SequenceClassifier:
        """Fit on ``X`` of shape (n_samples, n_columns) and labels ``y`` (n_samples,)."""
        X, y = validate_data(self, X, y)
        sequences, others = self._split(X)
        self.classes_ = np.unique(y)
        self.transform_ = self._make_transform().fit(self._prepared(sequences), y)
        features = np.hstack([self._transformed(sequences), others])
        self.head_ = self._make_head().fit(features, y)
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Labels of shape (n_samples,)."""
        return np.asarray(self.head_.predict(self._features(X)))

    def _features(self, X: np.ndarray) -> np.ndarray:
        check_is_fitted(self)
        X = validate_data(self, X, reset=False)
        sequences, others = self._split(X)
        return np.hstack([self._transformed(sequences), others])

    def _prepared(self, sequences: np.ndarray) -> np.ndarray:
        """The sequences as the transform takes them, in fitting as in transforming."""
        return sequences

    def _transformed(self, sequences: np.ndarray) -> np.ndarray:
        features = self.transform_.transform(self._prepared(sequences))
        return np.asarray(features, dtype=np.float64)

    def _split(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.sequence is None:
            raise ValueError(
                f"{type(self).__name__} needs its 'sequence' parameter (start, n_channels, "
                "length); build it with benchmark.catalogue.build_pipeline on a sequence data set"
            )
        start, n_channels, length = (int(value) for value in self.sequence)
        return panel(X, (start, n_channels, length))


class RocketClassifier(_SequenceClassifier):
    """MiniRocket or MultiRocket features and a cross-validated ridge classifier.

    Parameters
    ----------
    variant : {"minirocket", "multirocket"}
        aeon's transform.
    n_kernels : int
        Kernels of the transform (MiniRocket: features, rounded down to a multiple of 84;
        MultiRocket: 8 features per kernel and representation).
    max_dilations_per_kernel : int
        As aeon's transforms take it.
    sequence : (int, int, int) or None
        ``(start, n_channels, length)`` of the sequence block among the columns.
    random_state : int or None
        Seed of the transform's biases.
    """

    #: The optional modules it needs (:mod:`benchmark.extras`).
    REQUIRES = ("aeon",)

    def __init__(
        self,
        variant: str = "minirocket",
        n_kernels: int = 10_000,
        max_dilations_per_kernel: int = 32,
        sequence: tuple[int, int, int] | None = None,
        random_state: int | None = None,
    ) -> None:
        self.variant = variant
        self.n_kernels = n_kernels
        self.max_dilations_per_kernel = max_dilations_per_kernel
        self.sequence = sequence
        self.random_state = random_state

    def _make_transform(self) -> Any:
        require(self.REQUIRES, f"classifier '{self.variant}'")
        # aeon takes a second to import: only the processes that fit a rocket pay for it
        from aeon.transformations.collection.convolution_based import MiniRocket, MultiRocket

        if self.variant not in ROCKETS:
            raise ValueError(f"variant must be one of {', '.join(ROCKETS)}, got {self.variant!r}")
        kind = MiniRocket if self.variant == "minirocket" else MultiRocket
        return kind(
            n_kernels=self.n_kernels,
            max_dilations_per_kernel=self.max_dilations_per_kernel,
            n_jobs=1,
            random_state=self.random_state,
        )

    def _make_head(self) -> Pipeline:
        return make_pipeline(
            StandardScaler(with_mean=False), RidgeClassifierCV(alphas=list(RIDGE_ALPHAS))
        )

    def _prepared(self, sequences: np.ndarray) -> np.ndarray:
        # aeon's rockets compute in float32 and compile a kernel per memory layout: always
        # C-contiguous, so that fitting and transforming use the same compiled kernels
        return np.ascontiguousarray(sequences, dtype=np.float32)


class IntervalForestClassifier(_SequenceClassifier):
    """Random-interval statistics and extremely randomised trees.

    Parameters
    ----------
    n_intervals : int or None
        Intervals per representation (:class:`RandomIntervalFeatures`).
    n_estimators : int
        Trees of the forest.
    sequence : (int, int, int) or None
        ``(start, n_channels, length)`` of the sequence block among the columns.
    random_state : int or None
        Seed of the intervals and of the forest.
    """

    def __init__(
        self,
        n_intervals: int | None = None,
        n_estimators: int = 300,
        sequence: tuple[int, int, int] | None = None,
        random_state: int | None = None,
    ) -> None:
        self.n_intervals = n_intervals
        self.n_estimators = n_estimators
        self.sequence = sequence
        self.random_state = random_state

    def _make_transform(self) -> RandomIntervalFeatures:
        return RandomIntervalFeatures(n_intervals=self.n_intervals, random_state=self.random_state)

    def _make_head(self) -> ExtraTreesClassifier:
        return ExtraTreesClassifier(
            n_estimators=self.n_estimators, criterion="entropy", random_state=self.random_state
        )

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Probabilities of shape (n_samples, n_classes), columns as ``classes_``."""
        return np.asarray(self.head_.predict_proba(self._features(X)))
