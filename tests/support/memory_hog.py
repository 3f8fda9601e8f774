"""A classifier that asks for more memory than a task is allowed: the memory cap's tests.

It reaches the CLI's worker processes as a plugin (:mod:`benchmark.catalogue.plugins`,
``TOUCHBENCH_PLUGINS=tests.support.memory_hog``).  Its fit reserves 1 GiB without touching it,
so that it fails at once under a smaller cap and costs nothing without one.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin

from touchbench.benchmark.catalogue.spec import ClassifierSpec

#: Bytes the fit asks for.
HOG_BYTES = 2**30


class MemoryHogClassifier(ClassifierMixin, BaseEstimator):
    """Majority class, after reserving :data:`HOG_BYTES` (virtual memory, never touched)."""

    def __init__(self, random_state: int | None = None) -> None:
        self.random_state = random_state

    def fit(self, X: Any, y: Any) -> MemoryHogClassifier:
        self.reserved_ = np.empty(HOG_BYTES // 8).size
        labels, counts = np.unique(np.asarray(y), return_counts=True)
        self.classes_ = labels
        self.majority_ = labels[int(np.argmax(counts))]
        return self

    def predict(self, X: Any) -> np.ndarray:
        return np.full(len(X), self.majority_)


CLASSIFIERS = (
    ClassifierSpec(
        id="hog",
        weka_command=None,
        family="test",
        description="Test only: reserves 1 GiB in its fit, then predicts the majority class",
        factory=MemoryHogClassifier,
        params={},
        probabilities=False,
        needs_scaling=False,
        handles_missing=True,
        handles_nominal=False,
        cost="fast",
        suites=frozenset(),
    ),
)
