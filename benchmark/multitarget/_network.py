"""Targets predicted one after another, each from the features and its parent targets.

CR (no parents), CC (every earlier target in the chain) and BCC (the parent in a tree)
differ only in the structure they learn; :class:`TargetNetwork` fits and runs any of them.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import clone
from sklearn.utils import check_random_state

from touchbench.benchmark.multitarget._base import MultiTargetClassifier
from touchbench.benchmark.multitarget._target_classifier import TargetClassifier
from touchbench.benchmark.targets import TargetError, one_hot


class TargetNetwork(MultiTargetClassifier):
    """One classifier per target, fed the features plus one-hot codes of its parents.

    At training time each classifier sees the true values of its parents, at prediction
    time the predicted ones (the most probable value of each parent), in ``order_``.
    The parents' one-hot columns are appended after the features, so a catalogue
    pipeline that preprocesses the first ``n_features`` columns passes them through.

    Fitted attributes, besides those of :class:`MultiTargetClassifier`:

    - ``order_`` : ndarray of shape (n_targets,), the prediction order
    - ``parents_`` : list of tuple of int, the parents of each target
    - ``estimators_`` : list of :class:`TargetClassifier`, one per target (target index)
    """

    estimator: Any

    @abstractmethod
    def _structure(self, X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, list[tuple[int, ...]]]:
        """The prediction order and each target's parents, learnt from training data."""

    def fit(self, X: object, Y: object) -> TargetNetwork:
        """Learn the structure, then one classifier per target.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
            Features, NaN for missing values.
        Y : array-like of shape (n_samples, n_targets)
            Integer class codes.

        Returns
        -------
        self
        """
        X_checked, codes = self._validate_training_data(X, Y)
        order, parents = self._structure(X_checked, codes)
        self.order_ = np.asarray(order, dtype=np.int64)
        self.parents_ = [tuple(int(p) for p in pa) for pa in parents]
        self.estimators_ = [
            TargetClassifier(clone(self.estimator), self.n_classes_[target]).fit(
                self._design(X_checked, codes, self.parents_[target]), codes[:, target]
            )
            for target in range(self.n_targets_)
        ]
        return self

    def _design(self, X: np.ndarray, Y: np.ndarray, parents: Sequence[int]) -> np.ndarray:
        """Features followed by the one-hot codes of ``parents``' values in ``Y``."""
        if not parents:
            return X
        blocks = [X] + [one_hot(Y[:, p], self.n_classes_[p]) for p in parents]
        return np.hstack(blocks)

    def predict_proba(self, X: object) -> list[np.ndarray]:
        """Probabilities of each target given the features and the predicted parents.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        list of ndarray
            One (n_samples, n_classes_[t]) matrix per target, in target order.
        """
        X_checked = self._validate_prediction_data(X)
        return self._propagate(X_checked)[1]

    def predict(self, X: object) -> np.ndarray:
        """The most probable value of each target, following ``order_``.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        ndarray of shape (n_samples, n_targets), int64
        """
        X_checked = self._validate_prediction_data(X)
        return self._propagate(X_checked)[0]

    def _propagate(self, X: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
        predicted = np.zeros((X.shape[0], self.n_targets_), dtype=np.int64)
        proba: list[np.ndarray] = [np.empty((0, 0))] * self.n_targets_
        for target in self.order_:
            design = self._design(X, predicted, self.parents_[target])
            proba[target] = self.estimators_[target].predict_proba(design)
            predicted[:, target] = np.argmax(proba[target], axis=1)
        return predicted, proba


def chain_order(
    order: Sequence[int] | None, n_targets: int, random_state: int | np.random.RandomState | None
) -> np.ndarray:
    """A chain order: ``order`` checked, or a random permutation drawn from the seed.

    Raises
    ------
    TargetError
        ``order`` is not a permutation of ``0 .. n_targets - 1``.
    """
    if order is None:
        return check_random_state(random_state).permutation(n_targets).astype(np.int64)
    chosen = np.asarray(order, dtype=np.int64)
    if sorted(chosen.tolist()) != list(range(n_targets)):
        raise TargetError(
            f"order must be a permutation of the {n_targets} target indices, got {list(order)}"
        )
    return chosen
