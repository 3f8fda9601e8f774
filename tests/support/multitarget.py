"""Tiny synthetic multi-target problems and the meta-classifiers under test."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from sklearn.linear_model import LogisticRegression
from sklearn.tree import DecisionTreeClassifier

from touchbench.benchmark.multitarget import (
    BayesianClassifierChain,
    ClassifierChain,
    ClassRelevance,
    EnsembleClassifierChains,
    EnsemblePrunedSets,
    LabelCombination,
    MultiTargetClassifier,
    NearestSetReplacement,
    ProbabilisticClassifierChain,
    PrunedSets,
    RAkELd,
    SuperClassClassifier,
)

#: Every MEKA meta-classifier, built from a base estimator (small settings keep tests fast).
META_FACTORIES: dict[str, Callable[[Any], MultiTargetClassifier]] = {
    "cr": lambda base: ClassRelevance(base),
    "cc": lambda base: ClassifierChain(base, random_state=0),
    "bcc": lambda base: BayesianClassifierChain(base, random_state=0),
    "pcc": lambda base: ProbabilisticClassifierChain(base, random_state=0),
    "lc": lambda base: LabelCombination(base),
    "ps": lambda base: PrunedSets(base, pruning=1, n_replacements=2),
    "nsr": lambda base: NearestSetReplacement(base, pruning=1, n_replacements=2),
    "eps": lambda base: EnsemblePrunedSets(base, n_estimators=3, random_state=0),
    "ecc": lambda base: EnsembleClassifierChains(base, n_estimators=3, random_state=0),
    "rakeld": lambda base: RAkELd(base, subset_size=2, random_state=0),
    "scc": lambda base: SuperClassClassifier(base, n_iterations=50, random_state=0),
}


def three_targets(n_samples: int = 120, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Features (n, 4) and targets (n, 3) with 3, 2 and 3 classes, each learnable.

    Target 0 follows features 0 and 1, target 1 feature 2, target 2 feature 3.
    """
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n_samples, 4))
    Y = np.column_stack(
        [
            (X[:, 0] > 0).astype(int) + (X[:, 1] > 0.5),
            (X[:, 2] > 0).astype(int),
            np.digitize(X[:, 3], [-0.4, 0.4]),
        ]
    )
    return X, Y


def logistic() -> LogisticRegression:
    return LogisticRegression(max_iter=500)


def tree() -> DecisionTreeClassifier:
    return DecisionTreeClassifier(random_state=0)
