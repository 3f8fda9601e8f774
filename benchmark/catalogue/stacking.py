"""Stacking over the best of a run, chosen inside each training fold.

``stack-top3`` is a classifier like any other of a run: in each outer training fold it
cross-validates every member on that fold only (an inner k-fold), keeps the ``top_n``
best by the inner weighted F1, fits a logistic regression on their out-of-fold class
scores, and refits the kept members on the whole training fold. The outer test fold
chooses nothing. The inner predictions that choose the members are the ones the
logistic regression learns from, so the cost is ``cv`` fits of every member on
(cv - 1)/cv of the rows, then ``top_n`` refits: about ``(cv - 1) * M + top_n`` fits on
all the rows per outer fold for M members (``2 M + top_n`` with :data:`INNER_FOLDS` 3),
each member at its own cost (a tuned member brings its search along).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.linear_model import LogisticRegression
from sklearn.metrics import f1_score
from sklearn.model_selection import cross_val_predict

from touchbench.benchmark.catalogue.spec import ClassifierSpec, Stacking
from touchbench.benchmark.catalogue.tuning import inner_folds
from touchbench.benchmark.errors import ConfigurationError

#: Inner folds of the member selection and of the stacked class scores.
INNER_FOLDS = 3
#: Most members a stack may keep.
MAX_TOP_N = 20


def stack_id(top_n: int) -> str:
    """``3`` -> ``"stack-top3"``."""
    return f"stack-top{top_n}"


def stacked_spec(members: Sequence[ClassifierSpec], top_n: int) -> ClassifierSpec:
    """The spec of a stack over ``members`` that keeps the ``top_n`` best per fold.

    Raises
    ------
    ConfigurationError
        ``top_n`` below 1, above :data:`MAX_TOP_N` or above the number of members.
    """
    check_top_n(top_n, len(members))
    return ClassifierSpec(
        id=stack_id(top_n),
        weka_command=None,
        family="stacking",
        description=f"Logistic regression over the {top_n} best of {len(members)} members, "
        "chosen by inner cross-validation in each training fold",
        factory=LogisticRegression,
        params={},
        probabilities=True,
        needs_scaling=False,
        handles_missing=True,
        handles_nominal=True,
        cost="slow",
        suites=frozenset(),
        stacking=Stacking(tuple(members), top_n),
    )


def check_top_n(top_n: int, n_members: int) -> None:
    """Refuse a stack of the ``top_n`` best outside 1..min(members, :data:`MAX_TOP_N`)."""
    if not 1 <= top_n <= MAX_TOP_N:
        raise ConfigurationError(f"`stack` must be between 1 and {MAX_TOP_N}, got {top_n}")
    if top_n > n_members:
        raise ConfigurationError(
            f"a stack of the top {top_n} needs at least {top_n} classifiers in the run to "
            f"choose from, the run has {n_members}"
        )


class SelectedStack(ClassifierMixin, BaseEstimator):
    """Stack the ``top_n`` members that score best in an inner cross-validation.

    Parameters
    ----------
    members : sequence of (str, estimator)
        Named candidate classifiers (pipelines); cloned, never fitted themselves.
    top_n : int
        Members kept.
    cv : int
        Inner folds (stratified when every class has as many rows).
    random_state : int or None
        Seed of the inner folds and of the final logistic regression.

    Attributes
    ----------
    chosen_ : list of str
        Names of the kept members, best first.
    inner_scores_ : dict of str to float
        Inner weighted F1 of every member.
    estimators_ : list of estimator
        The kept members refitted on all the training rows.
    final_estimator_ : LogisticRegression
        Fitted on the kept members' out-of-fold class scores, shape
        (n_samples, sum of their score columns).
    best_params_ : dict
        ``{"members": chosen_}``, for the run's per-fold record.
    classes_ : ndarray of shape (n_classes,)
    """

    def __init__(
        self,
        members: Sequence[tuple[str, Any]] = (),
        top_n: int = 3,
        cv: int = INNER_FOLDS,
        random_state: int | None = None,
    ) -> None:
        self.members = members
        self.top_n = top_n
        self.cv = cv
        self.random_state = random_state

    def fit(self, X: np.ndarray, y: np.ndarray) -> SelectedStack:
        """Choose, stack and refit the members on ``(X, y)`` alone.

        Parameters
        ----------
        X : ndarray of shape (n_samples, n_features)
        y : ndarray of shape (n_samples,)
        """
        y = np.asarray(y)
        self.classes_ = np.unique(y)
        folds = inner_folds(y, self.cv, self.random_state)
        scores: dict[str, np.ndarray] = {}
        self.inner_scores_ = {}
        for name, member in self.members:
            method = _score_method(member)
            out_of_fold = cross_val_predict(clone(member), X, y, cv=folds, method=method)
            block = self._as_block(out_of_fold, method)
            scores[name] = block
            predicted = self.classes_[np.argmax(block, axis=1)]
            self.inner_scores_[name] = float(f1_score(y, predicted, average="weighted"))
        ranked = sorted(self.inner_scores_, key=lambda n: -self.inner_scores_[n])
        self.chosen_ = ranked[: self.top_n]
        by_name = dict(self.members)
        self.estimators_ = [clone(by_name[name]).fit(X, y) for name in self.chosen_]
        self.final_estimator_ = LogisticRegression(max_iter=2000, random_state=self.random_state)
        self.final_estimator_.fit(np.hstack([scores[name] for name in self.chosen_]), y)
        self.best_params_ = {"members": list(self.chosen_)}
        return self

    def _as_block(self, values: np.ndarray, method: str) -> np.ndarray:
        """Class scores of shape (n_samples, n_classes) whatever the member gives."""
        values = np.asarray(values)
        if method == "predict":
            return (values[:, None] == self.classes_[None, :]).astype(np.float64)
        if values.ndim == 1:  # a binary decision function
            return np.column_stack([-values, values]).astype(np.float64)
        return values.astype(np.float64)

    def _features(self, X: np.ndarray) -> np.ndarray:
        blocks = []
        for member in self.estimators_:
            method = _score_method(member)
            blocks.append(self._as_block(getattr(member, method)(X), method))
        return np.hstack(blocks)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predictions, shape (n_samples,)."""
        return np.asarray(self.final_estimator_.predict(self._features(X)))

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Class probabilities, shape (n_samples, n_classes)."""
        return np.asarray(self.final_estimator_.predict_proba(self._features(X)))


def _score_method(estimator: Any) -> str:
    for method in ("predict_proba", "decision_function"):
        if hasattr(estimator, method):
            return method
    return "predict"
