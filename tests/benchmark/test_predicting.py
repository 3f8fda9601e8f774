"""Labels read off the probabilities are what ``predict`` says, and cost one pass."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sklearn.ensemble import BaggingClassifier
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

from touchbench.benchmark.catalogue import get_spec, suite
from touchbench.benchmark.catalogue.predicting import (
    labels_and_probabilities,
    predicts_most_probable,
)
from touchbench.benchmark.estimators import build_estimator, reads_sequences
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.problem import Problem, problem_from_dataset, restrict_targets
from touchbench.benchmark.weka.ibk import WekaIBk


class CountingIBk(WekaIBk):
    """IBk that counts its probability passes."""

    passes = 0

    def predict_proba(self, X: Any) -> np.ndarray:
        type(self).passes += 1
        return super().predict_proba(X)


class OwnPredictIBk(WekaIBk):
    """IBk whose labels are not its probabilities' argmax (always the last class)."""

    def predict(self, X: Any) -> np.ndarray:
        return np.full(len(X), self.classes_[-1])


def ties() -> tuple[np.ndarray, np.ndarray]:
    """Duplicated rows of different classes: probabilities tied between classes."""
    rng = np.random.default_rng(3)
    X = np.repeat(rng.integers(0, 3, size=(40, 2)).astype(float), 2, axis=0)
    y = np.arange(80) % 4
    return X, y


def test_a_weka_classifier_predicts_in_one_pass_what_predict_says() -> None:
    X, y = ties()
    model = CountingIBk(n_neighbors=2).fit(X, y)
    expected = model.predict(X)
    CountingIBk.passes = 0
    labels, proba = labels_and_probabilities(model, X, probabilities=True)
    assert CountingIBk.passes == 1
    assert labels.dtype == np.int64
    np.testing.assert_array_equal(labels, expected)
    assert proba is not None
    np.testing.assert_array_equal(proba, model.predict_proba(X))
    # ties do occur, and the first class of highest probability is the label
    assert (np.sort(proba, axis=1)[:, -1] == np.sort(proba, axis=1)[:, -2]).any()


def test_a_pipeline_is_judged_by_its_last_step() -> None:
    X, y = ties()
    pipeline = make_pipeline(StandardScaler(), CountingIBk(n_neighbors=2)).fit(X, y)
    assert predicts_most_probable(pipeline)
    CountingIBk.passes = 0
    labels, _ = labels_and_probabilities(pipeline, X, probabilities=True)
    assert CountingIBk.passes == 1
    np.testing.assert_array_equal(labels, pipeline.predict(X))
    assert predicts_most_probable(BaggingClassifier(n_estimators=3))
    assert not predicts_most_probable(make_pipeline(StandardScaler(), SVC(probability=True)))


def test_a_subclass_that_predicts_in_its_own_way_is_asked_to_predict() -> None:
    X, y = ties()
    model = OwnPredictIBk().fit(X, y)
    assert not predicts_most_probable(model)
    labels, _ = labels_and_probabilities(model, X, probabilities=True)
    assert (labels == y.max()).all()


def test_without_probabilities_only_predict_is_asked() -> None:
    X, y = ties()
    model = CountingIBk().fit(X, y)
    CountingIBk.passes = 0
    labels, proba = labels_and_probabilities(model, X, probabilities=False)
    assert proba is None
    assert CountingIBk.passes == 1  # NanClassifier.predict's own pass
    np.testing.assert_array_equal(labels, model.predict(X))


def _mini(shared: Path, rows: int) -> Problem:
    """About ``rows`` of Mini's touches, every k-th, with the gesture as the target."""
    data = restrict_targets(
        read_arff(shared / "uc3m-touch" / "mini" / "gesture_and_place.arff"), ["gesture"]
    )
    problem, _ = problem_from_dataset(data)
    take = np.arange(0, problem.X.shape[0], max(1, problem.X.shape[0] // rows))
    return replace(problem, X=problem.X[take], Y=problem.Y[take])


@pytest.mark.shared
def test_every_default_entry_read_off_its_probabilities_agrees_with_predict(
    shared_datasets: Path,
) -> None:
    """On real data (Mini's gesture, a subset), each default entry whose labels are read
    off its probabilities gives exactly ``predict``'s labels."""
    problem = _mini(shared_datasets, 400)
    rows = np.arange(problem.X.shape[0])
    train, test = rows[rows % 4 != 0], rows[rows % 4 == 0]
    checked = []
    for entry in suite("default"):
        spec = get_spec(entry)
        if reads_sequences(entry) or spec.ensemble is not None or not spec.probabilities:
            continue
        model = build_estimator(entry, problem, random_state=0)
        if not predicts_most_probable(model):
            continue
        model.fit(problem.X[train], problem.Y[train, 0])
        labels, proba = labels_and_probabilities(model, problem.X[test], probabilities=True)
        np.testing.assert_array_equal(labels, model.predict(problem.X[test]), err_msg=entry)
        np.testing.assert_array_equal(proba, model.predict_proba(problem.X[test]))
        checked.append(entry)
    # the WEKA classifiers, the forests and bagging among them
    assert {"ibk", "ibk-w", "nb-kernel", "j48", "rf", "extra-trees", "bagging"} <= set(checked)
