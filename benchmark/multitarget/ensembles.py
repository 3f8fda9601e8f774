"""EPS and ECC: bagged ensembles of pruned sets and of classifier chains, voting per target."""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.utils import check_random_state

from touchbench.benchmark.multitarget._base import MultiTargetClassifier, check_at_least_one
from touchbench.benchmark.multitarget.chains import ClassifierChain
from touchbench.benchmark.multitarget.combination import PrunedSets
from touchbench.benchmark.targets import TargetError

_SEED_LIMIT = 2**31 - 1


class _VotingEnsemble(MultiTargetClassifier):
    """Members trained on random samples of the training data, voting per target.

    ``predict``: for each target, the value most members predict; ties go to the value
    with the highest mean probability (MEKA's ``EnsembleMT``/``BaggingMT`` vote the same
    way, breaking ties by value order).  ``predict_proba``: the members' mean
    probabilities.

    Fitted attributes: ``estimators_`` (the members), ``samples_`` (each member's rows).
    """

    n_estimators: int
    max_samples: float
    bootstrap: bool
    random_state: int | np.random.RandomState | None

    @abstractmethod
    def _member(self, seed: int) -> MultiTargetClassifier:
        """A new, unfitted member seeded with ``seed``."""

    def fit(self, X: object, Y: object) -> _VotingEnsemble:
        """Fit every member on its own sample of the rows.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
        Y : array-like of shape (n_samples, n_targets), int codes

        Returns
        -------
        self
        """
        X_checked, codes = self._validate_training_data(X, Y)
        check_at_least_one("n_estimators", self.n_estimators)
        if not 0.0 < self.max_samples <= 1.0:
            raise TargetError(f"max_samples must be in (0, 1], got {self.max_samples}")
        rng = check_random_state(self.random_state)
        n_samples = X_checked.shape[0]
        size = max(1, round(self.max_samples * n_samples))
        self.estimators_: list[MultiTargetClassifier] = []
        self.samples_: list[np.ndarray] = []
        for _ in range(self.n_estimators):
            rows = rng.choice(n_samples, size=size, replace=self.bootstrap)
            member = self._member(int(rng.randint(_SEED_LIMIT)))
            member.set_params(n_classes=self.n_classes_)
            self.estimators_.append(member.fit(X_checked[rows], codes[rows]))
            self.samples_.append(rows)
        return self

    def predict_proba(self, X: object) -> list[np.ndarray]:
        """Mean of the members' probabilities.

        Returns
        -------
        list of ndarray
            One (n_samples, n_classes_[t]) matrix per target.
        """
        X_checked = self._validate_prediction_data(X)
        return self._mean_proba(X_checked)

    def _mean_proba(self, X: np.ndarray) -> list[np.ndarray]:
        totals = [np.zeros((X.shape[0], k)) for k in self.n_classes_]
        for member in self.estimators_:
            for total, proba in zip(totals, member.predict_proba(X), strict=True):
                total += proba
        return [total / len(self.estimators_) for total in totals]

    def predict(self, X: object) -> np.ndarray:
        """Majority vote of the members per target.

        Returns
        -------
        ndarray of shape (n_samples, n_targets), int64
        """
        X_checked = self._validate_prediction_data(X)
        n_samples = X_checked.shape[0]
        votes = [np.zeros((n_samples, k)) for k in self.n_classes_]
        rows = np.arange(n_samples)
        for member in self.estimators_:
            predicted = member.predict(X_checked)
            for target, target_votes in enumerate(votes):
                target_votes[rows, predicted[:, target]] += 1.0
        mean_proba = self._mean_proba(X_checked)
        # A mean probability is at most 1, so half of it separates tied votes only.
        return np.stack(
            [
                np.argmax(target_votes + 0.5 * proba, axis=1)
                for target_votes, proba in zip(votes, mean_proba, strict=True)
            ],
            axis=1,
        ).astype(np.int64)


class EnsemblePrunedSets(_VotingEnsemble):
    """Ensemble of pruned sets, EPS (Read et al., ICDM 2008; MEKA's ``EnsembleML`` of PS).

    ``n_estimators`` :class:`PrunedSets` members, each trained on ``max_samples`` of the
    training rows drawn without replacement (the paper's 63 %), voting per target.
    The paper's EPS thresholds summed label votes; for multi-class targets the vote is
    per target value instead, so EPS can predict combinations no member learnt.

    Parameters
    ----------
    estimator : classifier
        Base classifier of every member.
    n_estimators : int, default 10
    max_samples : float, default 0.63
        Fraction of the rows each member sees.
    bootstrap : bool, default False
        Draw rows with replacement.
    pruning, n_replacements : int, default 1
        The members' PS parameters (MEKA's ``P`` and ``N``).
    n_classes : sequence of int, optional
        Classes per target.
    random_state : int, RandomState or None
        Seed of the samples.

    Attributes
    ----------
    estimators_ : list of PrunedSets
    samples_ : list of ndarray
        The rows each member was trained on.
    """

    def __init__(
        self,
        estimator: Any,
        *,
        n_estimators: int = 10,
        max_samples: float = 0.63,
        bootstrap: bool = False,
        pruning: int = 1,
        n_replacements: int = 1,
        n_classes: Sequence[int] | None = None,
        random_state: int | np.random.RandomState | None = None,
    ) -> None:
        self.estimator = estimator
        self.n_estimators = n_estimators
        self.max_samples = max_samples
        self.bootstrap = bootstrap
        self.pruning = pruning
        self.n_replacements = n_replacements
        self.n_classes = n_classes
        self.random_state = random_state

    def _member(self, seed: int) -> MultiTargetClassifier:
        return PrunedSets(self.estimator, pruning=self.pruning, n_replacements=self.n_replacements)


class EnsembleClassifierChains(_VotingEnsemble):
    """Ensemble of classifier chains, ECC (Read et al., 2009; MEKA's ``BaggingML`` of CC).

    ``n_estimators`` :class:`ClassifierChain` members, each with its own random chain
    order and a bootstrap sample of the training rows, voting per target.

    Parameters
    ----------
    estimator : classifier
        Base classifier of every link.
    n_estimators : int, default 10
    max_samples : float, default 1.0
        Fraction of the rows each member draws.
    bootstrap : bool, default True
        Draw rows with replacement (bagging).
    n_classes : sequence of int, optional
        Classes per target.
    random_state : int, RandomState or None
        Seed of the samples and chain orders.

    Attributes
    ----------
    estimators_ : list of ClassifierChain
    samples_ : list of ndarray
    """

    def __init__(
        self,
        estimator: Any,
        *,
        n_estimators: int = 10,
        max_samples: float = 1.0,
        bootstrap: bool = True,
        n_classes: Sequence[int] | None = None,
        random_state: int | np.random.RandomState | None = None,
    ) -> None:
        self.estimator = estimator
        self.n_estimators = n_estimators
        self.max_samples = max_samples
        self.bootstrap = bootstrap
        self.n_classes = n_classes
        self.random_state = random_state

    def _member(self, seed: int) -> MultiTargetClassifier:
        return ClassifierChain(self.estimator, random_state=seed)
