"""Stacking over the best of a run, chosen inside each training fold.

``stack-top3``: in each outer training fold, every member's out-of-fold class scores on
that fold's inner folds (:mod:`benchmark.catalogue.inner`; its probabilities, or its labels
one-hot) choose the ``top_n`` best by the inner weighted F1, a logistic regression learns
from the kept members' scores, and the kept members fitted on the whole training fold
give it their scores of the test rows. The outer test fold chooses nothing. The fixed
entry ``stacking`` is the same over four given entries, all kept.

In a run, the engine computes a stack from its members' fold predictions
(:mod:`benchmark.run.combine`): each member's inner predictions are computed once per outer
fold, in the member's own task, and serve every stack and the ensemble selection of the run;
the members' fits on the whole training fold are their own tasks'. Alone (a model trained
on all the data), :class:`SelectedStack` does the same itself: ``cv`` fits of every member
on (cv - 1)/cv of the rows, then ``top_n`` refits, each member at its own cost (a tuned
member brings its search along).  Both go through :func:`choose_and_stack`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from sklearn.base import clone
from sklearn.linear_model import LogisticRegression
from sklearn.metrics import f1_score

from touchbench.benchmark.catalogue.ensembles import InnerChoice, member_scores
from touchbench.benchmark.catalogue.inner import INNER_FOLDS
from touchbench.benchmark.catalogue.spec import ClassifierSpec, Stacking
from touchbench.benchmark.errors import ConfigurationError

#: Most members a stack may keep.
MAX_TOP_N = 20


def stack_id(top_n: int) -> str:
    """``3`` -> ``"stack-top3"``."""
    return f"stack-top{top_n}"


def stacked_spec(
    members: Sequence[ClassifierSpec],
    top_n: int,
    *,
    id: str | None = None,
    description: str | None = None,
    suites: frozenset[str] = frozenset(),
) -> ClassifierSpec:
    """The spec of a stack over ``members`` that keeps the ``top_n`` best per fold.

    ``id`` (default ``stack-topN``), ``description`` and ``suites`` name a catalogue entry.

    Raises
    ------
    ConfigurationError
        ``top_n`` below 1, above :data:`MAX_TOP_N` or above the number of members.
    """
    check_top_n(top_n, len(members))
    return ClassifierSpec(
        id=id or stack_id(top_n),
        weka_command=None,
        family="stacking",
        description=description
        or f"Logistic regression over the {top_n} best of {len(members)} members, "
        "chosen by inner cross-validation in each training fold",
        factory=LogisticRegression,
        params={},
        probabilities=True,
        needs_scaling=False,
        handles_missing=True,
        handles_nominal=True,
        cost="slow",
        suites=suites,
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


class SelectedStack(InnerChoice):
    """Stack the ``top_n`` members that score best in an inner cross-validation.

    Parameters
    ----------
    members : sequence of (str, estimator)
        Named candidate classifiers (pipelines); cloned, never fitted themselves.
    top_n : int
        Members kept.
    cv : int
        Inner folds (:func:`benchmark.catalogue.inner.inner_folds`).
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
        (n_samples, n_kept * n_classes).
    best_params_ : dict
        ``{"members": chosen_}``, for the run's per-fold record.
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

    def _choose(self, blocks: dict[str, np.ndarray], X: np.ndarray, y: np.ndarray) -> None:
        choice = choose_and_stack(blocks, y, self.classes_, self.top_n, self.random_state)
        self.chosen_, self.inner_scores_, self.final_estimator_ = choice
        by_name = dict(self.members)
        self.estimators_ = [clone(by_name[name]).fit(X, y) for name in self.chosen_]
        self.best_params_ = {"members": list(self.chosen_)}

    def _features(self, X: np.ndarray) -> np.ndarray:
        return np.hstack([member_scores(member, X, self.classes_) for member in self.estimators_])

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predictions, shape (n_samples,)."""
        return np.asarray(self.final_estimator_.predict(self._features(X)))

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Class probabilities, shape (n_samples, n_classes)."""
        return np.asarray(self.final_estimator_.predict_proba(self._features(X)))


def choose_and_stack(
    blocks: Mapping[str, np.ndarray],
    y: np.ndarray,
    classes: np.ndarray,
    top_n: int,
    seed: int | None,
) -> tuple[list[str], dict[str, float], LogisticRegression]:
    """Keep the ``top_n`` members of best inner weighted F1 and fit the logistic regression
    over their out-of-fold class scores.

    Parameters
    ----------
    blocks : mapping of str to ndarray of shape (n, len(classes))
        Each member's out-of-fold class scores of the training rows (probabilities, or
        labels one-hot), in the members' order.
    y : ndarray of shape (n,)
    classes : ndarray
        The label codes of the columns (the training rows' classes).
    top_n : int
    seed : int or None
        Seed of the logistic regression.

    Returns
    -------
    chosen : list of str
        Best first (ties: the members' order).
    inner_scores : dict of str to float
        Every member's inner weighted F1.
    final : LogisticRegression
        Fitted on the chosen members' blocks side by side, best first.
    """
    inner_scores = {
        name: float(f1_score(y, classes[np.argmax(block, axis=1)], average="weighted"))
        for name, block in blocks.items()
    }
    chosen = sorted(inner_scores, key=lambda n: -inner_scores[n])[:top_n]
    final = LogisticRegression(max_iter=2000, random_state=seed)
    final.fit(np.hstack([blocks[name] for name in chosen]), y)
    return chosen, inner_scores, final
