"""Target matrices: validation, class counts, one-hot codes, joint combinations, subsets.

A multi-target matrix ``Y`` has shape (n_samples, n_targets) and holds, for each target
``t``, integer codes ``0 .. n_classes[t] - 1`` (WEKA's nominal encoding).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from touchbench.benchmark.errors import ConfigurationError


class TargetError(ConfigurationError, ValueError):
    """A target matrix that a multi-target method cannot learn from.

    It is a :class:`~benchmark.errors.ConfigurationError` for the CLI (exit status 2) and
    a ``ValueError`` for scikit-learn's own tooling.
    """


def validate_targets(
    Y: object, n_classes: Sequence[int] | None = None, *, n_samples: int | None = None
) -> tuple[np.ndarray, tuple[int, ...]]:
    """Check a target matrix and settle how many classes each target has.

    Parameters
    ----------
    Y : array-like of shape (n_samples, n_targets)
        Integer class codes (floats holding whole numbers are accepted).
    n_classes : sequence of int, optional
        Number of declared classes per target; by default ``max(code) + 1`` per target.
    n_samples : int, optional
        The number of rows ``X`` has, checked against ``Y``.

    Returns
    -------
    Y : ndarray of shape (n_samples, n_targets), int64
    n_classes : tuple of int, length n_targets

    Raises
    ------
    TargetError
        ``Y`` is not 2-D, has missing or non-integer or negative codes, a code beyond its
        target's ``n_classes``, or a row count different from ``X``.
    """
    if Y is None:
        raise TargetError(
            "a multi-target classifier requires y to be passed, but the target y is None"
        )
    values = np.asarray(Y)
    if values.dtype.kind not in "iub":
        if values.dtype.kind != "f":
            raise TargetError(
                f"Unknown label type: Y must hold integer class codes, got dtype {values.dtype}"
            )
        missing = np.isnan(values)
        if missing.any():
            first = np.argwhere(missing)[0].tolist()
            raise TargetError(
                f"Y has {int(missing.sum())} missing target value(s) (first at index "
                f"{first}); multi-target methods need every target value"
            )
        if not np.array_equal(values, np.round(values)):
            raise TargetError(
                "Unknown label type: Y must hold integer class codes, got non-integer values"
            )
    if values.ndim != 2:
        raise TargetError(
            f"Y must be a 2-D matrix (n_samples, n_targets) of class codes, got shape "
            f"{values.shape}"
        )
    if values.shape[1] == 0:
        raise TargetError("Y has no target columns")
    if n_samples is not None and values.shape[0] != n_samples:
        raise TargetError(f"X has {n_samples} rows but Y has {values.shape[0]}")
    codes = values.astype(np.int64)
    if codes.size and codes.min() < 0:
        raise TargetError(f"Y holds a negative class code ({codes.min()})")
    observed = codes.max(axis=0) + 1 if codes.size else np.ones(codes.shape[1], dtype=int)
    if n_classes is None:
        return codes, tuple(int(k) for k in observed)
    declared = tuple(int(k) for k in n_classes)
    if len(declared) != codes.shape[1]:
        raise TargetError(
            f"n_classes has {len(declared)} entries but Y has {codes.shape[1]} targets"
        )
    for target, (k, seen) in enumerate(zip(declared, observed, strict=True)):
        if k < 1:
            raise TargetError(f"n_classes[{target}] must be at least 1, got {k}")
        if seen > k:
            raise TargetError(
                f"target {target} holds class code {seen - 1} but n_classes[{target}] is {k}"
            )
    return codes, declared


def one_hot(codes: np.ndarray, n_classes: int) -> np.ndarray:
    """One-hot encode class codes.

    Parameters
    ----------
    codes : ndarray of shape (n_samples,), int
    n_classes : int

    Returns
    -------
    ndarray of shape (n_samples, n_classes), float64
    """
    encoded = np.zeros((codes.shape[0], n_classes), dtype=np.float64)
    encoded[np.arange(codes.shape[0]), codes] = 1.0
    return encoded


def combination_marginals(
    combination_proba: np.ndarray, combinations: np.ndarray, n_classes: Sequence[int]
) -> list[np.ndarray]:
    """Per-target probabilities from probabilities over joint combinations.

    Parameters
    ----------
    combination_proba : ndarray of shape (n_samples, n_combinations)
        Probability of each combination.
    combinations : ndarray of shape (n_combinations, n_targets), int
        The value of every target in each combination.
    n_classes : sequence of int, length n_targets

    Returns
    -------
    list of ndarray, one of shape (n_samples, n_classes[t]) per target
        ``P(y_t = v) = sum of the probabilities of the combinations with y_t = v``.
    """
    return [combination_proba @ one_hot(combinations[:, t], k) for t, k in enumerate(n_classes)]


def all_binary(n_classes: Sequence[int]) -> bool:
    """Whether every target has at most two classes (a multi-label problem)."""
    return all(k <= 2 for k in n_classes)


def random_partition(
    n_targets: int, subset_size: int, rng: np.random.RandomState
) -> list[np.ndarray]:
    """Random disjoint subsets of the targets, of near-equal size (RAkELd's partition).

    Parameters
    ----------
    n_targets : int
    subset_size : int
        Targets per subset, at least 1; the targets are split into
        ``ceil(n_targets / subset_size)`` subsets whose sizes differ by at most one.
    rng : RandomState
        Draws the shuffle of the targets.

    Returns
    -------
    list of ndarray
        The target indices of each subset, in shuffled order.
    """
    shuffled = rng.permutation(n_targets)
    return list(np.array_split(shuffled, math.ceil(n_targets / subset_size)))
