"""Per-fold scores of a regression: mean absolute error, root mean squared error, R^2 and,
for targets that are a position's coordinates, the mean Euclidean error.

Definitions follow scikit-learn's (``mean_absolute_error``, ``root_mean_squared_error``,
``r2_score``), several targets averaged uniformly (each target's score, then their mean);
R^2 of a target that is constant in the test fold follows scikit-learn too (1 for a perfect
prediction, 0 otherwise).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def regression_scores(
    Y_true: np.ndarray,
    Y_pred: np.ndarray,
    *,
    target_names: Sequence[str],
    coordinates: Sequence[int] = (),
) -> tuple[dict[str, float], dict[str, dict[str, float]] | None]:
    """All regression metrics of one fold.

    Parameters
    ----------
    Y_true, Y_pred : ndarray of shape (n_samples, n_targets) or (n_samples,)
        True and predicted target values.
    target_names : sequence of str
        Name per target.
    coordinates : sequence of int
        Target columns that are a position's coordinates (2 or 3); empty for none.

    Returns
    -------
    scores : dict of str to float
        ``mae``, ``rmse`` and ``r2`` averaged over targets; ``euclidean_error`` (mean
        distance between true and predicted positions) when ``coordinates`` are given.
    per_target : dict or None
        Target name -> its ``mae``, ``rmse`` and ``r2``, for several targets.
    """
    true = np.asarray(Y_true, dtype=np.float64)
    pred = np.asarray(Y_pred, dtype=np.float64)
    true = true.reshape(true.shape[0], -1)
    pred = pred.reshape(true.shape)
    if true.shape[1] != len(target_names):
        raise ValueError(f"{true.shape[1]} target columns but {len(target_names)} names")
    if true.shape[0] == 0:
        raise ValueError("no instances to score")
    error = pred - true
    mae = np.abs(error).mean(axis=0)
    rmse = np.sqrt((error**2).mean(axis=0))
    r2 = _r2(true, error)
    scores = {"mae": float(mae.mean()), "rmse": float(rmse.mean()), "r2": float(r2.mean())}
    if coordinates:
        columns = list(coordinates)
        scores["euclidean_error"] = float(np.linalg.norm(error[:, columns], axis=1).mean())
    per_target = None
    if true.shape[1] > 1:
        per_target = {
            name: {"mae": float(mae[t]), "rmse": float(rmse[t]), "r2": float(r2[t])}
            for t, name in enumerate(target_names)
        }
    return scores, per_target


def _r2(true: np.ndarray, error: np.ndarray) -> np.ndarray:
    """R^2 per target column, with scikit-learn's convention for constant targets."""
    residual = (error**2).sum(axis=0)
    total = ((true - true.mean(axis=0)) ** 2).sum(axis=0)
    defined = total > 0
    out = np.where(residual == 0, 1.0, 0.0)
    out[defined] = 1.0 - residual[defined] / total[defined]
    return out
