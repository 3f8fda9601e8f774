"""SCC: the super-class classifier, strongly dependent targets merged into super-classes."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.utils import check_random_state

from touchbench.benchmark.multitarget.dependence import error_dependence_matrix
from touchbench.benchmark.multitarget.rakeld import PartitionedCombinations
from touchbench.benchmark.multitarget.relevance import ClassRelevance

_TRAINING_PERCENT = 67


class SuperClassClassifier(PartitionedCombinations):
    """Super-class classifier (Read, Bielza & Larrañaga, TKDE 2014; MEKA's ``SCC``).

    1. The training rows are shuffled and split 67 / 33; CR is trained on the first part
       and predicts the second.
    2. For every pair of targets, a chi-squared test of whether their errors co-occur
       (:func:`~benchmark.multitarget.dependence.error_dependence_matrix`): positive
       values mean conditionally dependent targets.
    3. Simulated annealing over partitions of the targets, from a random one, for
       ``n_iterations`` steps, maximising the dependence summed over pairs in the same
       subset minus the dependence summed over pairs apart.  A step moves one target to
       another subset or to a new one; a worse partition is accepted with probability
       ``2 (1 - sigmoid(|loss| * step / 1000))``, as in MEKA.
    4. Each subset of the best partition becomes a super-class: its joint values, with
       combinations seen at most ``pruning`` times replaced by up to ``n_replacements``
       nearest frequent ones (NSR), learnt by one classifier on all training rows.

    Departures from MEKA: the partition kept is the best one seen (MEKA keeps the last
    accepted one); the super-classes are learnt independently (MEKA passes them to an
    inner multi-target classifier, CR-like by default); the optional refinement by
    internal evaluation (MEKA's ``-N``) is not implemented.

    Parameters
    ----------
    estimator : classifier
        Base classifier of CR (step 1) and of every super-class.
    n_iterations : int, default 1000
        MEKA's ``I``: annealing steps.
    pruning : int, default 1
        MEKA's ``P`` for the super-classes.
    n_replacements : int, default 2
        MEKA's ``L`` (formerly ``N``) for the super-classes.
    n_classes : sequence of int, optional
        Classes per target.
    random_state : int, RandomState or None
        Seed of the split and of the annealing.

    Attributes
    ----------
    dependence_ : ndarray of shape (n_targets, n_targets)
        The error-dependence statistics of step 2.
    partition_ : list of ndarray
        The super-classes (target indices of each).
    estimators_ : list of NearestSetReplacement
        The model of each super-class.
    """

    def __init__(
        self,
        estimator: Any,
        *,
        n_iterations: int = 1000,
        pruning: int = 1,
        n_replacements: int = 2,
        n_classes: Sequence[int] | None = None,
        random_state: int | np.random.RandomState | None = None,
    ) -> None:
        self.estimator = estimator
        self.n_iterations = n_iterations
        self.pruning = pruning
        self.n_replacements = n_replacements
        self.n_classes = n_classes
        self.random_state = random_state

    def fit(self, X: object, Y: object) -> SuperClassClassifier:
        """Measure the targets' error dependence, choose super-classes, fit them.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
        Y : array-like of shape (n_samples, n_targets), int codes

        Returns
        -------
        self
        """
        X_checked, codes = self._validate_training_data(X, Y)
        rng = check_random_state(self.random_state)
        self.dependence_ = self._error_dependence(X_checked, codes, rng)
        blocks = _anneal(self.dependence_, self.n_iterations, rng)
        partition = [np.flatnonzero(blocks == b) for b in np.unique(blocks)]
        self._fit_partition(X_checked, codes, partition)
        return self

    def _error_dependence(
        self, X: np.ndarray, Y: np.ndarray, rng: np.random.RandomState
    ) -> np.ndarray:
        shuffled = rng.permutation(X.shape[0])
        n_train = X.shape[0] * _TRAINING_PERCENT // 100
        train, validation = shuffled[:n_train], shuffled[n_train:]
        if n_train == 0 or validation.shape[0] == 0:
            return error_dependence_matrix(Y[:0], Y[:0])
        relevance = ClassRelevance(self.estimator, n_classes=self.n_classes_)
        relevance.fit(X[train], Y[train])
        return error_dependence_matrix(Y[validation], relevance.predict(X[validation]))


def _anneal(dependence: np.ndarray, n_iterations: int, rng: np.random.RandomState) -> np.ndarray:
    """Simulated annealing over partitions of the targets.

    Parameters
    ----------
    dependence : ndarray of shape (n_targets, n_targets)
        Pairwise dependence; the rating of a partition is the sum over pairs together
        minus the sum over pairs apart.
    n_iterations : int
    rng : RandomState

    Returns
    -------
    ndarray of shape (n_targets,), int
        Subset label of each target in the best partition seen.
    """
    n_targets = dependence.shape[0]
    upper = np.triu(np.ones((n_targets, n_targets), dtype=bool), k=1)

    def rating(blocks: np.ndarray) -> float:
        together = blocks[:, None] == blocks[None, :]
        return float(np.sum(np.where(together, dependence, -dependence)[upper]))

    blocks = np.asarray(rng.randint(n_targets, size=n_targets))
    current = rating(blocks)
    best_blocks, best = blocks.copy(), current
    for step in range(n_iterations):
        labels = np.unique(blocks)
        source = labels[rng.randint(labels.shape[0])]
        moved = rng.choice(np.flatnonzero(blocks == source))
        destination = labels[rng.randint(labels.shape[0])]
        candidate = blocks.copy()
        candidate[moved] = blocks.max() + 1 if destination == source else destination
        value = rating(candidate)
        accept_worse = 2.0 * (1.0 - 1.0 / (1.0 + np.exp(-abs(value - current) * step / 1000.0)))
        if value > current or accept_worse > rng.random_sample():
            blocks, current = candidate, value
            if current > best:
                best_blocks, best = blocks.copy(), current
    return best_blocks
