"""scikit-learn's estimator checks on every estimator touchbench writes for the catalogue."""

from __future__ import annotations

import warnings
from collections.abc import Callable

from sklearn.base import BaseEstimator
from sklearn.utils.estimator_checks import parametrize_with_checks

from touchbench.benchmark.catalogue.boosters import CatBoostNominalClassifier, LightGBMClassifier
from touchbench.benchmark.weka import (
    C45Classifier,
    PARTClassifier,
    WekaIBk,
    WekaNaiveBayes,
    WekaZeroR,
)


@parametrize_with_checks(
    [
        WekaZeroR(),
        WekaNaiveBayes(),
        WekaNaiveBayes(numeric="kernel"),
        WekaNaiveBayes(numeric="discretize"),
        WekaIBk(n_neighbors=3, weighting="inverse"),
        C45Classifier(),
        PARTClassifier(),
        LightGBMClassifier(n_estimators=10),
        CatBoostNominalClassifier(iterations=10),
    ]
)
def test_scikit_learn_estimator_checks(
    estimator: BaseEstimator, check: Callable[[BaseEstimator], None]
) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check(estimator)
