"""RAkELd: label combination on random disjoint subsets of the targets."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.utils import check_random_state

from touchbench.benchmark.multitarget._base import MultiTargetClassifier, check_at_least_one
from touchbench.benchmark.multitarget.combination import NearestSetReplacement
from touchbench.benchmark.targets import random_partition


class PartitionedCombinations(MultiTargetClassifier):
    """Targets split into disjoint subsets, each learnt as one combination problem.

    Subclasses choose the partition; a subset of several targets is learnt by
    :class:`NearestSetReplacement` with ``pruning`` and ``n_replacements``, a subset of
    one target by a plain classifier.  Each target is predicted by its subset's model.

    Fitted attributes: ``partition_`` (list of ndarray of target indices, ascending) and
    ``estimators_`` (one :class:`NearestSetReplacement` per subset).
    """

    estimator: Any
    pruning: int
    n_replacements: int

    def _fit_partition(self, X: np.ndarray, Y: np.ndarray, partition: list[np.ndarray]) -> None:
        self.partition_ = [np.sort(np.asarray(part, dtype=np.int64)) for part in partition]
        self.estimators_ = [
            NearestSetReplacement(
                self.estimator,
                pruning=self.pruning if len(part) > 1 else 0,
                n_replacements=self.n_replacements,
                n_classes=[self.n_classes_[t] for t in part],
            ).fit(X, Y[:, part])
            for part in self.partition_
        ]

    def predict_proba(self, X: object) -> list[np.ndarray]:
        """Each target's marginal from its subset's model.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        list of ndarray
            One (n_samples, n_classes_[t]) matrix per target.
        """
        X_checked = self._validate_prediction_data(X)
        proba: list[np.ndarray] = [np.empty((0, 0))] * self.n_targets_
        for part, model in zip(self.partition_, self.estimators_, strict=True):
            for target, target_proba in zip(part, model.predict_proba(X_checked), strict=True):
                proba[target] = target_proba
        return proba

    def predict(self, X: object) -> np.ndarray:
        """Each subset's most probable combination.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        ndarray of shape (n_samples, n_targets), int64
        """
        X_checked = self._validate_prediction_data(X)
        predicted = np.zeros((X_checked.shape[0], self.n_targets_), dtype=np.int64)
        for part, model in zip(self.partition_, self.estimators_, strict=True):
            predicted[:, part] = model.predict(X_checked)
        return predicted


class RAkELd(PartitionedCombinations):
    """Random disjoint k-labelsets (MEKA's ``multitarget.RAkELd``).

    The targets are shuffled (seeded) and split into ``ceil(n_targets / subset_size)``
    disjoint subsets of near-equal size; each subset is learnt as one label combination
    problem (MEKA builds it on NSR with pruning ``P`` and ``N``, both 0 by default, which
    is plain LC).  Each target is predicted by the model of its subset.  With fewer
    targets than ``subset_size`` this is LC.  Departures from MEKA: the shuffle is
    NumPy's, and the subsets are split as evenly as possible (sizes differ by at most
    one), where MEKA's random partition may leave them uneven.

    Parameters
    ----------
    estimator : classifier
        Base classifier of every subset model.
    subset_size : int, default 3
        MEKA's ``k``: targets per subset.
    pruning : int, default 0
        NSR's ``P`` within each subset (0: no pruning).
    n_replacements : int, default 0
        NSR's ``N`` within each subset.
    n_classes : sequence of int, optional
        Classes per target.
    random_state : int, RandomState or None
        Seed of the partition.

    Attributes
    ----------
    partition_ : list of ndarray
        The target indices of each subset.
    estimators_ : list of NearestSetReplacement
        The model of each subset.
    """

    def __init__(
        self,
        estimator: Any,
        *,
        subset_size: int = 3,
        pruning: int = 0,
        n_replacements: int = 0,
        n_classes: Sequence[int] | None = None,
        random_state: int | np.random.RandomState | None = None,
    ) -> None:
        self.estimator = estimator
        self.subset_size = subset_size
        self.pruning = pruning
        self.n_replacements = n_replacements
        self.n_classes = n_classes
        self.random_state = random_state

    def fit(self, X: object, Y: object) -> RAkELd:
        """Partition the targets and fit one combination model per subset.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
        Y : array-like of shape (n_samples, n_targets), int codes

        Returns
        -------
        self
        """
        X_checked, codes = self._validate_training_data(X, Y)
        check_at_least_one("subset_size", self.subset_size)
        rng = check_random_state(self.random_state)
        partition = random_partition(self.n_targets_, self.subset_size, rng)
        self._fit_partition(X_checked, codes, partition)
        return self
