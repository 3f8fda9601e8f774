"""CR: class relevance, one independent classifier per target."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from touchbench.benchmark.multitarget._network import TargetNetwork


class ClassRelevance(TargetNetwork):
    """One independent multi-class classifier per target (MEKA's ``multitarget.CR``).

    The multi-target counterpart of binary relevance: target ``t`` is predicted from the
    features alone, ignoring the other targets.  No departure from MEKA, except that
    every classifier goes through :class:`TargetClassifier` (classes a fold lacks get
    probability 0, a one-valued target needs no base).

    Parameters
    ----------
    estimator : classifier
        Base classifier over int labels ``0 .. k - 1``; cloned once per target.
    n_classes : sequence of int, optional
        Classes per target; by default ``max(code) + 1`` per target of the training data.
        Pass the declared counts so that probabilities cover classes a fold lacks.

    Attributes
    ----------
    estimators_ : list of TargetClassifier
        The fitted classifier of each target.
    order_ : ndarray of shape (n_targets,)
        ``0 .. n_targets - 1`` (irrelevant to the result).
    parents_ : list of tuple
        Empty for every target.
    n_classes_, classes_, n_targets_, n_features_in_
        See :class:`~benchmark.multitarget._base.MultiTargetClassifier`.
    """

    def __init__(self, estimator: Any, *, n_classes: Sequence[int] | None = None) -> None:
        self.estimator = estimator
        self.n_classes = n_classes

    def _structure(self, X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, list[tuple[int, ...]]]:
        n_targets = Y.shape[1]
        return np.arange(n_targets), [() for _ in range(n_targets)]
