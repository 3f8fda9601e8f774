"""The inner folds of a training fold: one plan for tuning, stacking and ensemble selection.

Whatever chooses something inside an outer training fold (a tuned twin's search, a stack's
members and its combiner, an ensemble selection's weights) cross-validates that training
fold only, on the same :data:`INNER_FOLDS` shuffled folds: :func:`inner_folds`, stratified
when every class has as many rows, seeded by the run's seed.  So the inner out-of-fold
predictions of an entry (:func:`out_of_fold`) are the same whichever asks for them, and a
run computes them once per entry and outer fold, for its stacks and its ensemble selection
alike.  The outer test fold never takes part.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from sklearn.base import clone
from sklearn.model_selection import KFold, StratifiedKFold

from touchbench.benchmark.catalogue.predicting import labels_and_probabilities

#: Inner folds of every choice made inside a training fold.
INNER_FOLDS = 3

#: Extra ``fit`` arguments for the rows of an inner training fold (their recording groups,
#: for the networks that hold recordings out for early stopping).
FitParams = Callable[[np.ndarray], dict[str, Any]]


def inner_folds(
    y: np.ndarray, cv: int = INNER_FOLDS, seed: int | None = None
) -> KFold | StratifiedKFold:
    """Shuffled inner folds of a training fold, stratified when every class has ``cv`` rows."""
    _, counts = np.unique(y, return_counts=True)
    if counts.min() >= cv:
        return StratifiedKFold(cv, shuffle=True, random_state=seed)
    return KFold(cv, shuffle=True, random_state=seed)


def inner_splits(
    y: np.ndarray, seed: int | None, cv: int = INNER_FOLDS
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The (train, test) positions within a training fold of labels ``y`` (shape (n,)),
    as :func:`inner_folds` splits them."""
    return [
        (np.asarray(train), np.asarray(test))
        for train, test in inner_folds(y, cv, seed).split(np.zeros((len(y), 1)), y)
    ]


def out_of_fold(
    estimator: Any,
    X: np.ndarray,
    y: np.ndarray,
    splits: list[tuple[np.ndarray, np.ndarray]],
    *,
    classes: np.ndarray,
    probabilities: bool,
    fit_params: FitParams | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Each row's prediction by a clone of ``estimator`` fitted on the other inner folds.

    Parameters
    ----------
    estimator : estimator
        Unfitted; cloned for each inner fold.
    X : ndarray of shape (n, n_features)
    y : ndarray of shape (n,)
        The training fold's rows and labels.
    splits : list of (ndarray, ndarray)
        :func:`inner_splits` of ``y``.
    classes : ndarray of shape (n_columns,)
        The label codes of the probability columns (a class an inner model never saw has
        probability 0).
    probabilities : bool
        Whether to ask for ``predict_proba``.
    fit_params : callable, optional
        ``fit``'s extra arguments for the positions of an inner training fold.

    Returns
    -------
    labels : ndarray of shape (n,), int64
    proba : ndarray of shape (n, n_columns), float64, or None
    """
    labels = np.zeros(len(y), dtype=np.int64)
    proba = np.zeros((len(y), len(classes))) if probabilities else None
    for train, test in splits:
        extra = fit_params(train) if fit_params is not None else {}
        model = clone(estimator).fit(X[train], y[train], **extra)
        labels[test], inner = labels_and_probabilities(model, X[test], probabilities=probabilities)
        if proba is not None and inner is not None:
            columns = np.searchsorted(classes, np.asarray(model.classes_, dtype=np.int64))
            proba[np.ix_(test, columns)] = inner
    return labels, proba
