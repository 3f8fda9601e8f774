"""A fold's scores from its predictions: what a task computes once its model has predicted,
and what re-scores a stored task from its fold predictions alone.

One function serves both, so that a finished run's fold predictions re-score to its stored
metrics exactly (:func:`score_fold`): multi-class (confusion matrix, probabilities, the
reliability bins), multi-target (per target) and regression, pooled per recording when the
run scored recordings rather than windows (:mod:`benchmark.evaluation.recordings`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from touchbench.benchmark.evaluation.calibration import PER_TARGET, reliability
from touchbench.benchmark.evaluation.metrics import confusion_matrix, multiclass_scores
from touchbench.benchmark.evaluation.recordings import Recordings
from touchbench.benchmark.predictions import FoldPredictions
from touchbench.benchmark.problem import Problem

__all__ = ["FoldScores", "score_fold"]


@dataclass
class FoldScores:
    """What :func:`score_fold` found (the fields of a task's result it fills).

    Attributes
    ----------
    metrics : dict of str to float
        The scores, without the costs.
    confusion : list or None
        Multi-class: the (n_classes, n_classes) matrix; multi-target: one per target;
        regression: ``None``.
    per_target : dict or None
        Multi-target and regression: scores per target name.
    calibration : dict or None
        The reliability bins of the probabilities, if any (per target for several).
    """

    metrics: dict[str, float]
    confusion: list[Any] | None
    per_target: dict[str, dict[str, float]] | None
    calibration: dict[str, Any] | None


def score_fold(
    problem: Problem, predictions: FoldPredictions, *, by_recording: bool = False
) -> FoldScores:
    """Score ``predictions`` against the problem's truth of the same rows.

    Parameters
    ----------
    problem : Problem
        Its targets (``Y``) at ``predictions.indices`` are the truth; its groups pool the
        windows of a recording when ``by_recording``.
    predictions : FoldPredictions
        A task's test-fold predictions (labels and probabilities, or values).
    by_recording : bool
        Score each recording once: the mean of its windows' probabilities (or the majority
        of their labels, or the mean of their values) against its one label.
    """
    rows = predictions.indices
    recordings = (
        Recordings.of(problem.groups[rows]) if by_recording and problem.groups is not None else None
    )
    if problem.kind == "regression":
        return _regression(problem, predictions, recordings)
    if problem.kind == "multiclass":
        return _multiclass(problem, predictions, recordings)
    return _multitarget(problem, predictions, recordings)


def _multiclass(
    problem: Problem, predictions: FoldPredictions, recordings: Recordings | None
) -> FoldScores:
    n_classes = problem.n_classes[0]
    y_test = problem.Y[predictions.indices, 0]
    y_pred, proba = predictions.label, predictions.probabilities
    if recordings is not None:
        y_test = recordings.truth(y_test)
        y_pred, proba = recordings.classes(y_pred, proba, n_classes)
    scores, confusion = multiclass_scores(y_test, y_pred, proba, n_classes=n_classes)
    # the bins, not the probabilities: they add up over folds, 30 numbers a fold
    calibration = None if proba is None else reliability(y_test, proba).to_json()
    return FoldScores(scores, confusion, None, calibration)


def _regression(
    problem: Problem, predictions: FoldPredictions, recordings: Recordings | None
) -> FoldScores:
    from touchbench.benchmark.evaluation.regression import regression_scores

    assert predictions.values is not None
    Y_test, Y_pred = problem.Y[predictions.indices], predictions.values
    if recordings is not None:
        Y_test, Y_pred = recordings.truth(Y_test), recordings.mean(Y_pred)
    metrics, per_target = regression_scores(
        Y_test, Y_pred, target_names=problem.target_names, coordinates=problem.coordinates
    )
    return FoldScores(metrics, None, per_target, None)


def _multitarget(
    problem: Problem, predictions: FoldPredictions, recordings: Recordings | None
) -> FoldScores:
    from touchbench.benchmark.evaluation.multitarget import multitarget_scores

    assert predictions.labels is not None
    Y_test, Y_pred = problem.Y[predictions.indices], predictions.labels
    probas = None if predictions.proba is None else list(predictions.proba)
    if recordings is not None:
        Y_test, Y_pred, probas = _pooled_targets(recordings, Y_test, Y_pred, probas, problem)
    scores = dict(
        multitarget_scores(
            Y_test, Y_pred, probas, n_classes=problem.n_classes, target_names=problem.target_names
        )
    )
    per_target = scores.pop("per_target", None)
    metrics = {name: float(v) for name, v in scores.items() if isinstance(v, int | float)}
    confusion = [
        confusion_matrix(Y_test[:, t], Y_pred[:, t], n_classes=k).tolist()
        for t, k in enumerate(problem.n_classes)
    ]
    # per target, the bins of its top label's confidence (as a multi-class fold keeps)
    calibration = (
        None
        if probas is None
        else {
            PER_TARGET: {
                name: reliability(Y_test[:, t], probas[t]).to_json()
                for t, name in enumerate(problem.target_names)
            }
        }
    )
    return FoldScores(metrics, confusion, per_target, calibration)


def _pooled_targets(
    recordings: Recordings,
    Y_test: np.ndarray,
    Y_pred: np.ndarray,
    probas: list[np.ndarray] | None,
    problem: Problem,
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray] | None]:
    """Each target's windows pooled per recording: truth, predictions and probabilities
    (shapes (n_recordings, n_targets) and n_targets x (n_recordings, n_classes))."""
    pooled = [
        recordings.classes(Y_pred[:, t], None if probas is None else probas[t], k)
        for t, k in enumerate(problem.n_classes)
    ]
    labels = np.stack([p[0] for p in pooled], axis=1)
    means = [p[1] for p in pooled]
    kept = None if any(m is None for m in means) else [m for m in means if m is not None]
    return recordings.truth(Y_test), labels, kept
