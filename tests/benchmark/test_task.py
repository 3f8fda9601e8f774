"""One task run in-process: scores, costs, errors and warnings recorded, JSON round trip."""

from __future__ import annotations

import math
import pickle
import warnings
from dataclasses import replace

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin

from touchbench.benchmark.catalogue import CATALOGUE, get_spec
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.run.folds import Fold, make_folds
from touchbench.benchmark.run.task import (
    TaskContext,
    TaskKey,
    TaskResult,
    execute_task,
    pickled_size,
)


class WarningClassifier(ClassifierMixin, BaseEstimator):
    """Predicts class 0 and warns twice the same way while fitting."""

    def fit(self, X: np.ndarray, y: np.ndarray) -> WarningClassifier:
        self.classes_ = np.unique(y)
        for _ in range(2):
            warnings.warn("deliberate warning", UserWarning, stacklevel=1)
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        return np.zeros(len(X), dtype=np.int64)


class FailingClassifier(ClassifierMixin, BaseEstimator):
    def fit(self, X: np.ndarray, y: np.ndarray) -> FailingClassifier:
        raise ValueError("deliberate failure")


def problem(n: int = 60, n_classes: int = 3, seed: int = 0) -> Problem:
    rng = np.random.default_rng(seed)
    y = np.arange(n) % n_classes
    X = rng.normal(size=(n, 3)) + 2.0 * y[:, None]
    X[::7, 1] = np.nan
    return Problem(X=X, Y=y[:, None], n_classes=(n_classes + 1,), target_names=("gesture",))


def context(p: Problem, n_folds: int = 3, **specs) -> TaskContext:
    folds, _ = make_folds(p.Y, n_folds=n_folds)
    return TaskContext(p, {**CATALOGUE, **specs}, folds, random_state=0)


def test_ok_task_has_scores_costs_and_a_full_confusion_matrix() -> None:
    ctx = context(problem())
    result = execute_task(ctx, TaskKey("nb", 0, 1))
    assert result.status == "ok" and result.error is None
    assert (result.n_train, result.n_test) == (40, 20)
    assert result.metrics["accuracy"] > 0.6
    for name in ("fit_time", "predict_time", "fit_cpu_time", "predict_cpu_time"):
        assert result.metrics[name] >= 0
    assert result.metrics["model_size"] > 100
    # four declared classes, the last never occurs: its row and column are zero
    confusion = result.confusion or []
    assert len(confusion) == 4 and sum(map(sum, confusion)) == 20
    assert confusion[3] == [0, 0, 0, 0]
    assert not math.isnan(result.metrics["roc_auc"]) and not math.isnan(result.metrics["log_loss"])


def test_model_without_probabilities_has_nan_probability_scores() -> None:
    result = execute_task(context(problem()), TaskKey("svm-rbf", 0, 0))
    assert result.status == "ok"
    assert math.isnan(result.metrics["roc_auc"]) and math.isnan(result.metrics["log_loss"])


def test_a_class_missing_from_the_training_fold_is_handled() -> None:
    p = problem()
    train = np.flatnonzero(p.Y[:, 0] != 2)
    fold = Fold(0, 0, train, np.arange(60))
    ctx = TaskContext(p, CATALOGUE, [fold])
    for classifier in ("logistic", "xgb", "rf"):
        result = execute_task(ctx, TaskKey(classifier, 0, 0))
        assert result.status == "ok", result.error
        assert [row[2] for row in result.confusion or []] == [0, 0, 0, 0]  # never predicts class 2


def test_an_exception_becomes_an_error_result_with_its_message() -> None:
    failing = replace(get_spec("zeror"), id="failing", factory=FailingClassifier, params={})
    result = execute_task(context(problem(), failing=failing), TaskKey("failing", 0, 2))
    assert result.status == "error"
    assert str(result.error).startswith("ValueError: deliberate failure (at test_task.py:")
    assert result.metrics == {} and result.confusion is None
    assert (result.n_train, result.n_test) == (40, 20)


def test_distinct_warnings_are_recorded() -> None:
    noisy = replace(
        get_spec("zeror"), id="noisy", factory=WarningClassifier, params={}, probabilities=False
    )
    result = execute_task(context(problem(), noisy=noisy), TaskKey("noisy", 0, 0))
    assert result.status == "ok"
    assert result.warnings == ["UserWarning: deliberate warning"]


def test_multitarget_task_uses_the_multitarget_configurations() -> None:
    rng = np.random.default_rng(1)
    Y = np.column_stack([np.arange(90) % 3, (np.arange(90) // 3) % 2])
    X = rng.normal(size=(90, 4)) + Y @ np.array([[1.0, 0, 0, 0], [0, 0, 2.0, 0]])
    p = Problem(X=X, Y=Y, n_classes=(3, 2), target_names=("gesture", "place"))
    folds, _ = make_folds(Y, n_folds=3)
    result = execute_task(TaskContext(p, {}, folds), TaskKey("cc:nb", 0, 0))
    assert result.status == "ok", result.error
    assert 0.5 < result.metrics["hamming_score"] <= 1.0
    assert set(result.per_target or {}) == {"gesture", "place"}
    assert [len(m) for m in result.confusion or []] == [3, 2]
    assert result.metrics["fit_time"] >= 0 and result.metrics["model_size"] > 0
    bins = (result.calibration or {})["targets"]  # each target's own reliability bins
    assert set(bins) == {"gesture", "place"}
    assert all(sum(b["count"]) == result.n_test for b in bins.values())


def test_json_round_trip_keeps_nan_as_null() -> None:
    result = execute_task(context(problem()), TaskKey("svm-rbf", 0, 0))
    data = result.to_json()
    assert data["metrics"]["roc_auc"] is None
    again = TaskResult.from_json(data)
    assert again.key == result.key and again.confusion == result.confusion
    assert math.isnan(again.metrics["roc_auc"])
    assert again.metrics["accuracy"] == result.metrics["accuracy"]


def test_pickled_size_counts_bytes_and_is_nan_for_unpicklable_objects() -> None:
    assert pickled_size(b"x" * 1000) > 1000
    large = np.arange(300_000, dtype=np.float64)  # pickled through protocol 5 buffers
    assert pickled_size(large) == len(pickle.dumps(large, protocol=pickle.HIGHEST_PROTOCOL))
    assert math.isnan(pickled_size(lambda: None))


@pytest.mark.parametrize("bad", [{"Y": [[0], [5]]}, {"Y": [[0.5], [1]]}, {"n_classes": (2, 2)}])
def test_problem_validates_its_targets(bad: dict) -> None:
    from touchbench.benchmark.errors import ConfigurationError

    args = {"X": np.zeros((2, 1)), "Y": [[0], [1]], "n_classes": (2,), "target_names": ("t",)}
    with pytest.raises(ConfigurationError):
        Problem(**{**args, **bad})
