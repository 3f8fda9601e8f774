"""Ensembles of catalogue entries: votes, and Caruana's greedy ensemble selection.

An ensemble is defined by the entries it combines (:class:`~benchmark.catalogue.spec.Ensemble`):
``voting`` is the soft vote of ``xgb``, ``hgb`` and ``calibrated-svm-rbf``.  In a run the
engine computes it from its members' fold predictions, which the run has anyway
(:mod:`benchmark.run.combine`); on its own (a model trained on all the data) it fits its
members itself.  Both go through the functions here, so that they agree to the last bit:

- :func:`soft_vote` and :func:`hard_vote`: what scikit-learn's ``VotingClassifier`` predicts
  with the same fitted members (the mean of their probabilities; the most frequent label,
  ties to the lowest code).
- :func:`greedy_selection` (Caruana et al., "Ensemble selection from libraries of models",
  ICML 2004, with replacement and without a sorted start, as AutoGluon's weighted
  ensemble): in each training fold, on the members' inner out-of-fold class scores
  (:mod:`benchmark.catalogue.inner`), add ``rounds`` times the member whose addition gives
  the best weighted F1 of the mean so far; the weights are the counts.  :func:`blend` makes
  the weighted mean.  A member without probabilities takes part with its labels, one-hot.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone

from touchbench.benchmark.catalogue.inner import INNER_FOLDS, inner_splits, out_of_fold
from touchbench.benchmark.catalogue.spec import ClassifierSpec, Ensemble
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.metrics import confusion_scores

#: Most rounds an ensemble selection may take.
MAX_ROUNDS = 100


def soft_vote(probas: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The mean of the members' class probabilities and its most probable class.

    Parameters
    ----------
    probas : sequence of ndarray of shape (n, n_columns)
        Each member's probabilities, columns in the same order of classes.

    Returns
    -------
    columns : ndarray of shape (n,), int64
        The column of each row's most probable class (ties: the first).
    mean : ndarray of shape (n, n_columns)
        ``VotingClassifier(voting="soft").predict_proba``: the same call of ``np.average``.
    """
    mean = np.average(np.asarray(probas), axis=0)
    return np.argmax(mean, axis=1).astype(np.int64), mean


def hard_vote(labels: Sequence[np.ndarray], n_classes: int) -> np.ndarray:
    """The most frequent of the members' labels per row (ties: the lowest code), as
    ``VotingClassifier(voting="hard")`` votes; shape (n,), from (n,) label codes each."""
    first = np.asarray(labels[0])
    counts = np.zeros((first.size, n_classes), dtype=np.int64)
    rows = np.arange(first.size)
    for member in labels:
        np.add.at(counts, (rows, np.asarray(member, dtype=np.int64)), 1)
    return np.argmax(counts, axis=1).astype(np.int64)


def class_scores(labels: np.ndarray, proba: np.ndarray | None, classes: np.ndarray) -> np.ndarray:
    """A member's class scores over ``classes``: its probabilities (already in those
    columns), or its labels one-hot when it has none; shape (n, len(classes)), float64."""
    if proba is not None:
        return np.asarray(proba, dtype=np.float64)
    return (np.asarray(labels)[:, None] == np.asarray(classes)[None, :]).astype(np.float64)


def inner_blocks(
    members: Sequence[tuple[str, Any]],
    X: np.ndarray,
    y: np.ndarray,
    classes: np.ndarray,
    seed: int | None,
    cv: int = INNER_FOLDS,
) -> dict[str, np.ndarray]:
    """Each named member's out-of-fold class scores of the rows ``(X, y)`` on their inner
    folds (:func:`benchmark.catalogue.inner.inner_splits`), shape (n, len(classes)) each:
    what a stack or a selection fitted on its own chooses by."""
    splits = inner_splits(y, seed, cv)
    blocks = {}
    for name, member in members:
        probabilities = hasattr(member, "predict_proba")
        labels, proba = out_of_fold(
            member, X, y, splits, classes=classes, probabilities=probabilities
        )
        blocks[name] = class_scores(labels, proba, classes)
    return blocks


def member_scores(model: Any, X: np.ndarray, classes: np.ndarray) -> np.ndarray:
    """A fitted member's class scores of the rows ``X`` over ``classes`` (its probabilities,
    or its labels one-hot), shape (n, len(classes))."""
    if not hasattr(model, "predict_proba"):
        return class_scores(np.asarray(model.predict(X)), None, classes)
    proba = np.zeros((len(X), len(classes)))
    proba[:, np.searchsorted(classes, model.classes_)] = model.predict_proba(X)
    return proba


def blend(blocks: Sequence[np.ndarray], counts: Sequence[int]) -> np.ndarray:
    """The mean of the class scores ``blocks`` (each (n, n_columns)) weighted by ``counts``,
    summed in the members' order; the members counted 0 are left out."""
    total = np.zeros_like(np.asarray(blocks[0], dtype=np.float64))
    for block, count in zip(blocks, counts, strict=True):
        if count:
            total += count * block
    return total / float(sum(counts))


def greedy_selection(
    blocks: Sequence[np.ndarray], y: np.ndarray, classes: np.ndarray, rounds: int
) -> list[int]:
    """Caruana's greedy ensemble selection with replacement.

    Parameters
    ----------
    blocks : sequence of ndarray of shape (n, len(classes))
        Each candidate's out-of-fold class scores of the same rows.
    y : ndarray of shape (n,)
        The rows' labels.
    classes : ndarray
        The label codes of the columns.
    rounds : int
        Members added (a member may be added again).

    Returns
    -------
    list of int
        How often each candidate was chosen (the weights, times ``rounds``).  Each round
        adds the candidate whose addition gives the best weighted F1 of the mean; ties go
        to the first candidate.
    """
    codes = np.searchsorted(classes, np.asarray(y, dtype=np.int64))
    k = len(classes)
    total = np.zeros((len(codes), k))
    counts = [0] * len(blocks)
    for _ in range(rounds):
        best, best_score = 0, -np.inf
        for c, block in enumerate(blocks):
            predicted = np.argmax(total + block, axis=1)
            confusion = np.bincount(codes * k + predicted, minlength=k * k).reshape(k, k)
            score = confusion_scores(confusion)["f1_weighted"]
            if score > best_score:
                best, best_score = c, score
        counts[best] += 1
        total += blocks[best]
    return counts


def selection_id(rounds: int) -> str:
    """``5`` -> ``"ensemble-5"``."""
    return f"ensemble-{rounds}"


def selection_spec(members: Sequence[ClassifierSpec], rounds: int) -> ClassifierSpec:
    """The spec of an ensemble selection of ``rounds`` rounds over ``members``.

    Raises
    ------
    ConfigurationError
        ``rounds`` outside 1..:data:`MAX_ROUNDS`, or no member.
    """
    if not 1 <= rounds <= MAX_ROUNDS:
        raise ConfigurationError(f"`ensemble` must be between 1 and {MAX_ROUNDS}, got {rounds}")
    if not members:
        raise ConfigurationError("an ensemble selection needs entries of the run to choose from")
    return ClassifierSpec(
        id=selection_id(rounds),
        weka_command=None,
        family="ensemble-selection",
        description=f"Caruana's greedy selection, {rounds} rounds with replacement, over "
        f"{len(members)} entries of the run, on inner out-of-fold predictions of each "
        "training fold",
        factory=GreedyEnsemble,
        params={"rounds": rounds},
        probabilities=True,
        needs_scaling=False,
        handles_missing=True,
        handles_nominal=True,
        cost="slow",
        suites=frozenset(),
        ensemble=Ensemble(tuple(members), "selection", rounds),
    )


def describe_members(combine: str, members: Sequence[ClassifierSpec]) -> str:
    """``Soft vote of xgb, hgb and calibrated-svm-rbf``: an ensemble's description."""
    ids = [member.id for member in members]
    listed = ", ".join(ids[:-1]) + f" and {ids[-1]}" if len(ids) > 1 else ids[0]
    kind = {"soft": "Soft vote", "hard": "Majority vote", "stack": "Logistic regression over"}
    return f"{kind[combine]} of {listed}" if combine != "stack" else f"{kind[combine]} {listed}"


def voting_classifier(members: Sequence[tuple[str, Any]], voting: str = "soft") -> Any:
    """scikit-learn's ``VotingClassifier`` over named ``members``: a vote's factory."""
    from sklearn.ensemble import VotingClassifier

    return VotingClassifier(list(members), voting=voting)


class InnerChoice(ClassifierMixin, BaseEstimator):
    """A combination of named members that chooses on their inner out-of-fold class scores
    of its training rows (:func:`inner_blocks`): the base of a stack and of a selection
    fitted on their own.  Subclasses declare their parameters (``members``, ``cv``,
    ``random_state`` and their own) and choose in :meth:`_choose`.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    """

    members: Sequence[tuple[str, Any]]
    cv: int
    random_state: int | None

    def fit(self, X: np.ndarray, y: np.ndarray) -> InnerChoice:
        """Choose on the inner out-of-fold predictions of ``(X, y)`` alone, refit the chosen.

        Parameters
        ----------
        X : ndarray of shape (n_samples, n_features)
        y : ndarray of shape (n_samples,)
        """
        y = np.asarray(y)
        self.classes_ = np.unique(y)
        blocks = inner_blocks(self.members, X, y, self.classes_, self.random_state, self.cv)
        self._choose(blocks, X, y)
        return self

    def _choose(self, blocks: dict[str, np.ndarray], X: np.ndarray, y: np.ndarray) -> None:
        raise NotImplementedError

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predictions, shape (n_samples,)."""
        return np.asarray(self.classes_[np.argmax(self.predict_proba(X), axis=1)])

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        raise NotImplementedError


class GreedyEnsemble(InnerChoice):
    """Caruana's ensemble selection inside the training data: the estimator of an
    ``ensemble-N`` entry fitted on its own (the engine computes the same from its members'
    fold predictions).

    Parameters
    ----------
    members : sequence of (str, estimator)
        Named candidate classifiers (pipelines); cloned, never fitted themselves.
    rounds : int
    cv : int
        Inner folds (:func:`benchmark.catalogue.inner.inner_folds`).
    random_state : int or None
        Seed of the inner folds.

    Attributes
    ----------
    weights_ : dict of str to float
        Each chosen member's weight (count / rounds), in the members' order.
    estimators_ : list of (str, estimator, int)
        The chosen members refitted on all the training rows, with their counts.
    best_params_ : dict
        ``{"weights": weights_}``, for the run's per-fold record.
    """

    def __init__(
        self,
        members: Sequence[tuple[str, Any]] = (),
        rounds: int = 5,
        cv: int = INNER_FOLDS,
        random_state: int | None = None,
    ) -> None:
        self.members = members
        self.rounds = rounds
        self.cv = cv
        self.random_state = random_state

    def _choose(self, blocks: dict[str, np.ndarray], X: np.ndarray, y: np.ndarray) -> None:
        counts = greedy_selection(list(blocks.values()), y, self.classes_, self.rounds)
        self.estimators_ = [
            (name, clone(member).fit(X, y), count)
            for (name, member), count in zip(self.members, counts, strict=True)
            if count
        ]
        self.weights_ = {name: count / self.rounds for name, _, count in self.estimators_}
        self.best_params_ = {"weights": dict(self.weights_)}

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """The chosen members' weighted mean class scores, shape (n_samples, n_classes)."""
        blocks = [member_scores(member, X, self.classes_) for _, member, _ in self.estimators_]
        return blend(blocks, [count for _, _, count in self.estimators_])
