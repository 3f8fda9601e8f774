"""Per-fold scores of a multi-class classifier, from its predictions and probabilities.

Everything except ROC AUC and log loss derives from the confusion matrix, so one pass over
the predictions serves all metrics and no scikit-learn metric validation runs per fold.
Definitions follow scikit-learn's (``average="weighted"`` weights classes by their support
in ``y_true``; undefined precision counts as 0), with the full label set given, so a class
missing from a test fold never breaks a score.  A score that is undefined on a fold (ROC
AUC with one class present, anything needing probabilities from a model that has none) is
NaN.
"""

from __future__ import annotations

import math

import numpy as np

#: The multi-class metrics of every fold, in display order.
MULTICLASS_METRICS: tuple[str, ...] = (
    "accuracy",
    "balanced_accuracy",
    "f1_weighted",
    "f1_macro",
    "precision_weighted",
    "recall_weighted",
    "kappa",
    "mcc",
    "roc_auc",
    "log_loss",
)

#: The regression metrics of every fold (:mod:`benchmark.evaluation.regression`); the
#: mean Euclidean error only when targets are a position's coordinates.
REGRESSION_METRICS: tuple[str, ...] = ("mae", "rmse", "r2", "euclidean_error")

#: Measurements of cost recorded with every fold.
COST_METRICS: tuple[str, ...] = (
    "fit_time",
    "predict_time",
    "fit_cpu_time",
    "predict_cpu_time",
    "model_size",
)

#: WEKA's error measures on class-probability vectors (kept for the results-ARFF export).
ERROR_METRICS: tuple[str, ...] = ("mean_absolute_error", "root_mean_squared_error")

#: Metrics for which a smaller value is better (everything else: larger is better).
LOWER_IS_BETTER: frozenset[str] = frozenset(
    {
        "log_loss",
        "fit_time",
        "predict_time",
        "fit_cpu_time",
        "predict_cpu_time",
        "model_size",
        "mean_absolute_error",
        "root_mean_squared_error",
        "mae",
        "rmse",
        "euclidean_error",
        "hamming_loss",
        "zero_one_loss",
    }
)

_EPSILON = float(np.finfo(np.float64).eps)


def confusion_matrix(y_true: np.ndarray, y_pred: np.ndarray, *, n_classes: int) -> np.ndarray:
    """Counts of (true, predicted) label pairs.

    Parameters
    ----------
    y_true, y_pred : ndarray of shape (n_samples,)
        Integer labels in ``0..n_classes-1``.
    n_classes : int
        Number of declared labels.

    Returns
    -------
    ndarray of shape (n_classes, n_classes), int64
        Row = true label, column = predicted label (WEKA's and scikit-learn's layout).
    """
    true = np.asarray(y_true, dtype=np.int64)
    pred = np.asarray(y_pred, dtype=np.int64)
    if true.shape != pred.shape or true.ndim != 1:
        raise ValueError(f"y_true {true.shape} and y_pred {pred.shape} must be equal 1-D shapes")
    if true.size and (min(true.min(), pred.min()) < 0 or max(true.max(), pred.max()) >= n_classes):
        raise ValueError(f"labels must lie in 0..{n_classes - 1}")
    flat = np.bincount(true * n_classes + pred, minlength=n_classes * n_classes)
    return flat.reshape(n_classes, n_classes)


def expand_proba(proba: np.ndarray, classes: np.ndarray, *, n_classes: int) -> np.ndarray:
    """Place a model's probability columns into the full label set.

    A model trained on a fold that lacked some classes has ``classes_`` a subset of
    ``0..n_classes-1`` and one ``predict_proba`` column per class it saw.

    Parameters
    ----------
    proba : ndarray of shape (n_samples, len(classes))
        The model's ``predict_proba`` output.
    classes : ndarray of shape (len(classes),)
        The model's ``classes_`` (integer labels).
    n_classes : int
        Number of declared labels.

    Returns
    -------
    ndarray of shape (n_samples, n_classes)
        Zero for the classes the model never saw.
    """
    proba = np.asarray(proba, dtype=np.float64)
    columns = np.asarray(classes, dtype=np.int64)
    if proba.ndim != 2 or proba.shape[1] != columns.size:
        raise ValueError(f"predict_proba returned shape {proba.shape} for {columns.size} classes")
    full = np.zeros((proba.shape[0], n_classes))
    full[:, columns] = proba
    return full


def multiclass_scores(
    y_true: np.ndarray,
    y_pred: np.ndarray,
    proba: np.ndarray | None,
    *,
    n_classes: int,
) -> tuple[dict[str, float], list[list[int]]]:
    """All multi-class metrics of one fold.

    Parameters
    ----------
    y_true, y_pred : ndarray of shape (n_samples,)
        True and predicted integer labels in ``0..n_classes-1``.
    proba : ndarray of shape (n_samples, n_classes) or None
        Class probabilities over the full label set (see :func:`expand_proba`), or
        ``None`` for a model without probabilities.
    n_classes : int
        Number of declared labels.

    Returns
    -------
    scores : dict of str to float
        :data:`MULTICLASS_METRICS` plus :data:`ERROR_METRICS`; NaN where undefined.
    confusion : list of list of int
        The (n_classes, n_classes) confusion matrix, rows true, columns predicted.
    """
    confusion = confusion_matrix(y_true, y_pred, n_classes=n_classes)
    scores = confusion_scores(confusion)
    truth = np.asarray(y_true, dtype=np.int64)
    if proba is not None:
        proba = np.asarray(proba, dtype=np.float64)
        if proba.shape != (truth.size, n_classes):
            raise ValueError(
                f"proba must have shape ({truth.size}, {n_classes}), got {proba.shape}"
            )
    scores["roc_auc"] = weighted_roc_auc(truth, proba) if proba is not None else math.nan
    scores["log_loss"] = log_loss(truth, proba) if proba is not None else math.nan
    distribution = proba if proba is not None else np.eye(n_classes)[np.asarray(y_pred, int)]
    scores.update(probability_errors(truth, distribution))
    return scores, confusion.tolist()


def confusion_scores(confusion: np.ndarray) -> dict[str, float]:
    """The metrics that follow from a confusion matrix alone.

    Parameters
    ----------
    confusion : ndarray of shape (n_classes, n_classes)
        Rows true labels, columns predicted labels.

    Returns
    -------
    dict of str to float
        accuracy, balanced_accuracy, f1_weighted, f1_macro, precision_weighted,
        recall_weighted, kappa and mcc.  ``f1_macro`` and ``balanced_accuracy`` average
        over the classes that occur (in the truth or the predictions, resp. in the truth),
        as scikit-learn does without an explicit label list.  Kappa is NaN and MCC 0 when
        truth and predictions both hold a single class (scikit-learn's conventions).
    """
    c = np.asarray(confusion, dtype=np.float64)
    n = c.sum()
    if n == 0:
        raise ValueError("no instances to score")
    hits = np.diag(c)
    support = c.sum(axis=1)
    predicted = c.sum(axis=0)
    precision = _divide(hits, predicted)
    recall = _divide(hits, support)
    f1 = _divide(2 * precision * recall, precision + recall)
    weights = support / n
    occurring = (support > 0) | (predicted > 0)
    accuracy = hits.sum() / n
    expected = float(support @ predicted) / (n * n)
    return {
        "accuracy": float(accuracy),
        "balanced_accuracy": float(recall[support > 0].mean()),
        "f1_weighted": float(weights @ f1),
        "f1_macro": float(f1[occurring].mean()),
        "precision_weighted": float(weights @ precision),
        "recall_weighted": float(weights @ recall),
        "kappa": _ratio(accuracy - expected, 1.0 - expected, undefined=math.nan),
        "mcc": _ratio(
            hits.sum() * n - support @ predicted,
            math.sqrt((n * n - support @ support) * (n * n - predicted @ predicted)),
            undefined=0.0,
        ),
    }


def weighted_roc_auc(y_true: np.ndarray, proba: np.ndarray) -> float:
    """One-vs-rest ROC AUC averaged with weights proportional to class support.

    Parameters
    ----------
    y_true : ndarray of shape (n_samples,)
        Integer labels.
    proba : ndarray of shape (n_samples, n_classes)
        Class probabilities (any scores that rank instances).

    Returns
    -------
    float
        The support-weighted mean of the per-class AUCs (Mann-Whitney statistic, ties
        counted half) over classes present in ``y_true``; NaN when fewer than two classes
        are present.  Absent classes have zero weight, as in scikit-learn's
        ``roc_auc_score(average="weighted", multi_class="ovr")``.
    """
    # imported here: loading SciPy's statistics would slow every command and page that
    # only reads scores
    from scipy.stats import rankdata

    n = y_true.size
    present = np.unique(y_true)
    if present.size < 2:
        return math.nan
    total = 0.0
    for label in present:
        positive = y_true == label
        n_pos = int(positive.sum())
        ranks = rankdata(proba[:, label])
        auc = (ranks[positive].sum() - n_pos * (n_pos + 1) / 2) / (n_pos * (n - n_pos))
        total += n_pos * auc
    return float(total / n)


def log_loss(y_true: np.ndarray, proba: np.ndarray) -> float:
    """Mean negative log-probability of the true label (probabilities clipped to [eps, 1]).

    Parameters
    ----------
    y_true : ndarray of shape (n_samples,)
    proba : ndarray of shape (n_samples, n_classes)
        Rows are normalised to sum to 1 first.
    """
    totals = proba.sum(axis=1, keepdims=True)
    normalised = np.divide(proba, totals, out=np.zeros_like(proba), where=totals > 0)
    picked = np.clip(normalised[np.arange(y_true.size), y_true], _EPSILON, 1.0)
    return float(-np.log(picked).mean())


def probability_errors(y_true: np.ndarray, distribution: np.ndarray) -> dict[str, float]:
    """WEKA's mean absolute and root mean squared error of class-probability vectors.

    Parameters
    ----------
    y_true : ndarray of shape (n_samples,)
    distribution : ndarray of shape (n_samples, n_classes)
        Predicted class distribution (one-hot predictions for models without
        probabilities, as WEKA does).

    Returns
    -------
    dict
        ``mean_absolute_error``: mean over instances and classes of |p - 1[y = c]|;
        ``root_mean_squared_error``: the square root of the mean squared difference.
    """
    target = np.zeros_like(distribution)
    target[np.arange(y_true.size), y_true] = 1.0
    difference = distribution - target
    return {
        "mean_absolute_error": float(np.abs(difference).mean()),
        "root_mean_squared_error": float(np.sqrt((difference**2).mean())),
    }


def _divide(numerator: np.ndarray, denominator: np.ndarray) -> np.ndarray:
    return np.divide(numerator, denominator, out=np.zeros_like(numerator), where=denominator > 0)


def _ratio(numerator: float, denominator: float, *, undefined: float) -> float:
    """``numerator / denominator``, or ``undefined`` (scikit-learn's choice) when it is 0."""
    if denominator == 0:
        return undefined
    return float(numerator / denominator)
