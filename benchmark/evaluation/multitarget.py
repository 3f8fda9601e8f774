"""MEKA's multi-target and multi-label evaluation measures, one fold at a time.

Names and meanings follow MEKA's ``meka.core.Metrics``:

- ``hamming_score``: mean over instances and targets of correct values (MEKA's
  "Hamming score", a.k.a. label accuracy).
- ``exact_match``: fraction of instances with every target right.
- ``hamming_loss`` = 1 - hamming_score; ``zero_one_loss`` = 1 - exact_match.
- ``per_target``: ``{name: {"accuracy", "f1_weighted"}}`` (plus ``"log_loss"`` with
  probabilities); weighted F1 as WEKA weighs it, by the true class frequencies.
- Binary targets only (multi-label data): ``f1_micro`` (F1 over all label decisions),
  ``f1_macro`` (mean of the labels' F1, 0 for a label never true nor predicted, as MEKA),
  ``jaccard`` (mean over instances of |true ∩ predicted| / |true ∪ predicted|, 1 when
  both are empty, MEKA's multi-label "accuracy").
- With probabilities: ``log_loss``, the mean over targets of each target's multi-class
  log loss (natural log).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.metrics import f1_score, jaccard_score, log_loss

from touchbench.benchmark.targets import TargetError, all_binary, validate_targets

#: Scalar keys :func:`multitarget_scores` can return, higher-is-better ones first.
MULTITARGET_METRICS: tuple[str, ...] = (
    "hamming_score",
    "exact_match",
    "f1_micro",
    "f1_macro",
    "jaccard",
    "hamming_loss",
    "zero_one_loss",
    "log_loss",
)
#: The subset of :data:`MULTITARGET_METRICS` only computed for binary targets.
MULTILABEL_METRICS: tuple[str, ...] = ("f1_micro", "f1_macro", "jaccard")
#: The subset of :data:`MULTITARGET_METRICS` where lower is better.
LOSS_METRICS: tuple[str, ...] = ("hamming_loss", "zero_one_loss", "log_loss")


def multitarget_scores(
    Y_true: np.ndarray,
    Y_pred: np.ndarray,
    probas: list[np.ndarray] | None,
    *,
    n_classes: Sequence[int],
    target_names: Sequence[str],
) -> dict[str, Any]:
    """Scores of one fold's multi-target predictions.

    Parameters
    ----------
    Y_true, Y_pred : ndarray of shape (n_samples, n_targets)
        True and predicted class codes.
    probas : list of ndarray or None
        One (n_samples, n_classes[t]) probability matrix per target, or ``None``.
    n_classes : sequence of int
        Declared classes per target.
    target_names : sequence of str
        Names of the targets, keys of ``per_target``.

    Returns
    -------
    dict
        The keys described in the module docstring; floats, and ``per_target`` a dict of
        dicts.

    Raises
    ------
    TargetError
        Shapes, names, class counts and probability matrices that do not agree.
    """
    true, declared = validate_targets(Y_true, n_classes)
    predicted, _ = validate_targets(Y_pred, declared, n_samples=true.shape[0])
    if predicted.shape != true.shape:
        raise TargetError(f"Y_pred has shape {predicted.shape} but Y_true {true.shape}")
    if len(target_names) != true.shape[1]:
        raise TargetError(f"{len(target_names)} target names for {true.shape[1]} targets in Y_true")
    if true.shape[0] == 0:
        raise TargetError("no instances to score")
    correct = true == predicted
    hamming = float(correct.mean())
    exact = float(correct.all(axis=1).mean())
    scores: dict[str, Any] = {
        "hamming_score": hamming,
        "exact_match": exact,
        "hamming_loss": 1.0 - hamming,
        "zero_one_loss": 1.0 - exact,
    }
    per_target: dict[str, dict[str, float]] = {
        name: {
            "accuracy": float(correct[:, t].mean()),
            "f1_weighted": float(
                f1_score(true[:, t], predicted[:, t], average="weighted", zero_division=0.0)
            ),
        }
        for t, name in enumerate(target_names)
    }
    if all_binary(declared):
        scores["f1_micro"] = float(f1_score(true, predicted, average="micro", zero_division=0.0))
        scores["f1_macro"] = float(f1_score(true, predicted, average="macro", zero_division=0.0))
        scores["jaccard"] = float(
            jaccard_score(true, predicted, average="samples", zero_division=1.0)
        )
    if probas is not None:
        scores["log_loss"] = _log_loss(true, probas, declared, target_names, per_target)
    scores["per_target"] = per_target
    return scores


def _log_loss(
    true: np.ndarray,
    probas: list[np.ndarray],
    n_classes: Sequence[int],
    target_names: Sequence[str],
    per_target: dict[str, dict[str, float]],
) -> float:
    """Mean per-target log loss; records each target's in ``per_target``."""
    if len(probas) != true.shape[1]:
        raise TargetError(f"{len(probas)} probability matrices for {true.shape[1]} targets")
    losses = []
    for t, (name, k) in enumerate(zip(target_names, n_classes, strict=True)):
        proba = np.asarray(probas[t], dtype=np.float64)
        if proba.shape != (true.shape[0], k):
            raise TargetError(
                f"probabilities of target '{name}' have shape {proba.shape}, expected "
                f"{(true.shape[0], k)}"
            )
        # Sums of products drift by an ulp beyond [0, 1], which log_loss refuses.
        proba = np.clip(proba, 0.0, 1.0)
        loss = 0.0 if k == 1 else float(log_loss(true[:, t], proba, labels=np.arange(k)))
        per_target[name]["log_loss"] = loss
        losses.append(loss)
    return float(np.mean(losses))
