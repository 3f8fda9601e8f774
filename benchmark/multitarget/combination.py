"""LC, PS and NSR: one multi-class classifier over joint target combinations."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import clone

from touchbench.benchmark.multitarget._base import MultiTargetClassifier
from touchbench.benchmark.multitarget._target_classifier import TargetClassifier
from touchbench.benchmark.targets import all_binary, combination_marginals


class LabelCombination(MultiTargetClassifier):
    """Label combination (MEKA's ``LC``, a.k.a. label powerset), for multi-target data.

    Every distinct combination of target values in the training data becomes one class
    of a single multi-class classifier.  ``predict`` decodes the most probable
    combination, so only combinations seen in training can be predicted;
    ``predict_proba`` gives each target's marginal, the summed probability of the
    combinations holding each value.  As MEKA's LC, but for ``predict_proba`` (MEKA
    reports the chosen combination's values with a confidence per target).

    Parameters
    ----------
    estimator : classifier
        Base classifier over the combination classes.
    n_classes : sequence of int, optional
        Classes per target; default ``max(code) + 1`` per target of the training data.

    Attributes
    ----------
    combinations_ : ndarray of shape (n_combinations, n_targets)
        The combinations learnt (class ``c`` of the base is row ``c``).
    estimator_ : TargetClassifier
        The fitted classifier over combinations.
    """

    def __init__(self, estimator: Any, *, n_classes: Sequence[int] | None = None) -> None:
        self.estimator = estimator
        self.n_classes = n_classes

    def fit(self, X: object, Y: object) -> LabelCombination:
        """Fit the classifier over the (possibly pruned) combinations of ``Y``.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
        Y : array-like of shape (n_samples, n_targets), int codes

        Returns
        -------
        self
        """
        X_checked, codes = self._validate_training_data(X, Y)
        rows, targets, weights = self._training_set(codes)
        self.combinations_, classes = np.unique(targets, axis=0, return_inverse=True)
        self.estimator_ = TargetClassifier(clone(self.estimator), len(self.combinations_))
        self.estimator_.fit(X_checked[rows], classes.reshape(-1), sample_weight=weights)
        return self

    def _training_set(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows of X to train on, their combinations and weights (all of Y here)."""
        return np.arange(Y.shape[0]), Y, np.ones(Y.shape[0])

    def _combination_proba(self, X: object) -> np.ndarray:
        X_checked = self._validate_prediction_data(X)
        return self.estimator_.predict_proba(X_checked)

    def predict_proba(self, X: object) -> list[np.ndarray]:
        """Per-target marginals of the probabilities of the learnt combinations.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        list of ndarray
            One (n_samples, n_classes_[t]) matrix per target.
        """
        proba = self._combination_proba(X)
        return combination_marginals(proba, self.combinations_, self.n_classes_)

    def predict(self, X: object) -> np.ndarray:
        """The most probable combination of each sample.

        Returns
        -------
        ndarray of shape (n_samples, n_targets), int64
        """
        proba = self._combination_proba(X)
        return self.combinations_[np.argmax(proba, axis=1)].astype(np.int64)


class _PrunedCombination(LabelCombination):
    """LC trained on frequent combinations only, infrequent ones replaced (PS and NSR).

    A combination seen at most ``pruning`` times is infrequent.  Each instance holding
    one is replaced by up to ``n_replacements`` copies labelled with frequent
    combinations chosen by :meth:`_replacements`, each weighted ``1 / copies`` (the
    weights reach the base when it accepts ``sample_weight``); without a replacement
    the instance is dropped.  If pruning would leave no training data, ``pruning`` is
    lowered until some remains, as MEKA does (``pruning_`` tells the value used).
    """

    def __init__(
        self,
        estimator: Any,
        *,
        pruning: int = 1,
        n_replacements: int = 1,
        n_classes: Sequence[int] | None = None,
    ) -> None:
        self.estimator = estimator
        self.pruning = pruning
        self.n_replacements = n_replacements
        self.n_classes = n_classes

    def _replacements(
        self, combination: np.ndarray, frequent: np.ndarray, counts: np.ndarray
    ) -> np.ndarray:
        """Indices into ``frequent`` of the replacements for one infrequent combination."""
        raise NotImplementedError

    def _training_set(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        distinct, inverse, counts = np.unique(Y, axis=0, return_inverse=True, return_counts=True)
        inverse = inverse.reshape(-1)
        # Pruning 0 keeps every instance, so the loop always returns.
        for pruning in range(max(int(self.pruning), 0), -1, -1):
            rows, targets, weights = self._pruned(Y, distinct, inverse, counts > pruning)
            if rows.shape[0] > 0:
                self.pruning_ = pruning
                return rows, targets, weights
        raise AssertionError("unreachable")  # pragma: no cover

    def _pruned(
        self, Y: np.ndarray, distinct: np.ndarray, inverse: np.ndarray, frequent_mask: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Frequent instances as they are, infrequent ones replaced (rows, targets, weights).

        ``distinct`` holds the distinct combinations, ``inverse`` each instance's index into
        them and ``frequent_mask`` which of them are frequent.
        """
        kept = np.flatnonzero(frequent_mask[inverse])
        rows, targets, weights = [kept], [Y[kept]], [np.ones(kept.shape[0])]
        frequent = distinct[frequent_mask]
        frequent_counts = np.bincount(inverse)[frequent_mask]
        if self.n_replacements < 1 or frequent.shape[0] == 0:
            return kept, Y[kept], weights[0]
        for combination_index in np.flatnonzero(~frequent_mask):
            chosen = self._replacements(distinct[combination_index], frequent, frequent_counts)
            chosen = chosen[: self.n_replacements]
            members = np.flatnonzero(inverse == combination_index)
            for replacement in chosen:
                rows.append(members)
                targets.append(np.repeat(frequent[replacement][None, :], members.shape[0], 0))
                weights.append(np.full(members.shape[0], 1.0 / chosen.shape[0]))
        return np.concatenate(rows), np.concatenate(targets), np.concatenate(weights)


class PrunedSets(_PrunedCombination):
    """Pruned sets (Read, Pfahringer & Holmes, ICDM 2008; MEKA's ``PS``), multi-target.

    LC on the frequent combinations; the instances of an infrequent combination (seen
    at most ``pruning`` times) are reintroduced with up to ``n_replacements`` frequent
    "subsets" of their combination.

    On binary targets (multi-label data) a subset is what MEKA means: a frequent
    labelset contained in the instance's labelset, largest first, then most frequent.
    On multi-class targets, where subsets have no meaning, MEKA offers no PS; here a
    subset is a frequent combination that agrees with the instance's on some targets,
    most agreeing targets first, then most frequent (NSR, by contrast, only accepts
    combinations that differ in one target).

    Parameters
    ----------
    estimator : classifier
        Base classifier over the combination classes.
    pruning : int, default 1
        MEKA's ``P``: combinations seen at most this often are pruned.
    n_replacements : int, default 1
        MEKA's ``N``: how many subsets replace an infrequent combination.
    n_classes : sequence of int, optional
        Classes per target.

    Attributes
    ----------
    combinations_ : ndarray of shape (n_combinations, n_targets)
    estimator_ : TargetClassifier
    pruning_ : int
        The pruning value actually used.
    """

    def _replacements(
        self, combination: np.ndarray, frequent: np.ndarray, counts: np.ndarray
    ) -> np.ndarray:
        if all_binary(self.n_classes_):
            contained = np.all(frequent <= combination, axis=1)
            size = frequent.sum(axis=1)
            candidates = np.flatnonzero(contained)
            rank = np.lexsort((-counts[candidates], -size[candidates]))
            return candidates[rank]
        agreement = (frequent == combination).sum(axis=1)
        candidates = np.flatnonzero(agreement > 0)
        rank = np.lexsort((-counts[candidates], -agreement[candidates]))
        return candidates[rank]


class NearestSetReplacement(_PrunedCombination):
    """Nearest set replacement (MEKA's ``multitarget.NSR``), the multi-target PS.

    LC on the frequent combinations; the instances of an infrequent combination (seen
    at most ``pruning`` times) are reintroduced with up to ``n_replacements`` frequent
    combinations that differ from theirs in at most one target, most frequent first.
    ``predict_proba`` gives per-target marginals of the combination probabilities (MEKA
    reports the top vote per target as confidence).  MEKA limits targets to 10 values;
    there is no such limit here.

    Parameters
    ----------
    estimator : classifier
        Base classifier over the combination classes.
    pruning : int, default 1
        MEKA's ``P``: combinations seen at most this often are pruned.
    n_replacements : int, default 1
        MEKA's ``N``: how many nearest frequent combinations replace an infrequent one.
    n_classes : sequence of int, optional
        Classes per target.

    Attributes
    ----------
    combinations_ : ndarray of shape (n_combinations, n_targets)
    estimator_ : TargetClassifier
    pruning_ : int
        The pruning value actually used.
    """

    def _replacements(
        self, combination: np.ndarray, frequent: np.ndarray, counts: np.ndarray
    ) -> np.ndarray:
        distance = (frequent != combination).sum(axis=1)
        candidates = np.flatnonzero(distance <= 1)
        return candidates[np.argsort(-counts[candidates], kind="stable")]
