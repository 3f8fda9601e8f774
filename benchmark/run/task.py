"""One task (one classifier on one fold), run in the current process.

The engine runs :func:`execute_task` inside worker processes; everything a worker needs is
in a :class:`TaskContext`, sent to each worker once.  A classifier that raises is recorded
as an ``error`` result here; timeouts and crashes are the engine's business.
"""

from __future__ import annotations

import math
import pickle
import time
import traceback
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from touchbench.benchmark.catalogue import ClassifierSpec
from touchbench.benchmark.catalogue.inner import inner_splits, out_of_fold
from touchbench.benchmark.catalogue.predicting import labels_and_probabilities
from touchbench.benchmark.estimators import build_estimator, group_fit_params
from touchbench.benchmark.evaluation.fold_scores import score_fold
from touchbench.benchmark.evaluation.metrics import expand_proba
from touchbench.benchmark.predictions import FoldPredictions
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.results import Status, TaskKey, TaskResult
from touchbench.benchmark.run.choices import chosen_params
from touchbench.benchmark.run.folds import Fold

#: At most this many distinct warnings are kept per task.
MAX_WARNINGS = 5


@dataclass(frozen=True, eq=False)
class TaskContext:
    """Everything a worker needs to run any task of one run.

    Parameters
    ----------
    problem : Problem
    specs : mapping of str to ClassifierSpec
        Multi-class classifiers by id (catalogue entries and any extra ones).
    folds : sequence of Fold
    random_state : int
        Seed of every classifier.
    by_recording : bool
        Score each test recording (``problem.groups``) as one prediction, pooled over its
        windows (:mod:`benchmark.evaluation.recordings`), rather than each window.
    inner : frozenset of str
        Entries whose tasks also predict their training fold out of fold, on the run's
        inner folds (for the run's stacks and ensemble selection).
    """

    problem: Problem
    specs: Mapping[str, ClassifierSpec]
    folds: Sequence[Fold]
    random_state: int = 0
    by_recording: bool = False
    inner: frozenset[str] = frozenset()

    def fold(self, repeat: int, fold: int) -> Fold:
        for candidate in self.folds:
            if candidate.repeat == repeat and candidate.fold == fold:
                return candidate
        raise KeyError(f"no fold {fold} in repeat {repeat}")


def failed_result(key: TaskKey, status: Status, error: str, fold: Fold | None) -> TaskResult:
    """A result for a task that produced no scores."""
    return TaskResult(
        key=key,
        status=status,
        error=error,
        metrics={},
        confusion=None,
        n_train=0 if fold is None else int(fold.train.size),
        n_test=0 if fold is None else int(fold.test.size),
    )


def execute_task(context: TaskContext, key: TaskKey) -> TaskResult:
    """Fit, predict and score one classifier on one fold; exceptions become errors."""
    fold = context.fold(key.repeat, key.fold)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            if context.problem.kind == "multiclass":
                result = _run_multiclass(context, key, fold)
            elif context.problem.kind == "regression":
                result = _run_regression(context, key, fold)
            else:
                result = _run_multitarget(context, key, fold)
        except MemoryError as exc:
            result = failed_result(key, "error", f"MemoryError: out of memory {exc}".strip(), fold)
        except Exception as exc:
            result = failed_result(key, "error", describe_exception(exc), fold)
    result.warnings = _distinct_warnings(caught)
    return result


def describe_exception(exc: BaseException) -> str:
    """``"Type: message (at file:line in function)"`` for the innermost frame."""
    text = f"{type(exc).__name__}: {exc}".rstrip(": ")
    frames = traceback.extract_tb(exc.__traceback__)
    if frames:
        last = frames[-1]
        text += f" (at {last.filename.rsplit('/', 1)[-1]}:{last.lineno} in {last.name})"
    return text


def _run_multiclass(context: TaskContext, key: TaskKey, fold: Fold) -> TaskResult:
    problem = context.problem
    n_classes = problem.n_classes[0]
    model = build_estimator(
        key.classifier, problem, random_state=context.random_state, extra_specs=context.specs
    )
    y = problem.Y[:, 0]
    timer = _Timer()
    model.fit(problem.X[fold.train], y[fold.train], **_groups(model, problem, fold.train))
    fit_time, fit_cpu = timer.lap()
    probabilities = context.specs[key.classifier].probabilities
    y_pred, proba = labels_and_probabilities(
        model, problem.X[fold.test], probabilities=probabilities
    )
    if proba is not None:
        proba = expand_proba(proba, model.classes_, n_classes=n_classes)
    predict_time, predict_cpu = timer.lap()
    costs = _costs(fit_time, fit_cpu, predict_time, predict_cpu, model)
    result = scored_result(
        context,
        key,
        fold,
        FoldPredictions.of_classes(fold.test, y_pred, proba),
        costs,
        params=chosen_params(model),
    )
    if key.classifier in context.inner:
        result.inner_predictions = _inner_predictions(context, model, fold, probabilities)
        inner_time, inner_cpu = timer.lap()
        result.metrics.update({"inner_time": inner_time, "inner_cpu_time": inner_cpu})
    return result


def scored_result(
    context: TaskContext,
    key: TaskKey,
    fold: Fold,
    predictions: FoldPredictions,
    costs: dict[str, float],
    *,
    params: dict[str, Any] | None = None,
) -> TaskResult:
    """The ``ok`` result of a task whose model predicted ``predictions`` of the test fold,
    scored as the run scores (:func:`benchmark.evaluation.fold_scores.score_fold`)."""
    scores = score_fold(context.problem, predictions, by_recording=context.by_recording)
    return TaskResult(
        key,
        "ok",
        None,
        {**scores.metrics, **costs},
        scores.confusion,
        int(fold.train.size),
        int(fold.test.size),
        per_target=scores.per_target,
        params=params,
        calibration=scores.calibration,
        predictions=predictions,
    )


def _inner_predictions(
    context: TaskContext, model: Any, fold: Fold, probabilities: bool
) -> FoldPredictions:
    """The model's out-of-fold predictions of the training fold's rows, on the run's inner
    folds of it (:mod:`benchmark.catalogue.inner`), rows in the training fold's order."""
    problem = context.problem
    y = problem.Y[fold.train, 0]
    labels, proba = out_of_fold(
        model,
        problem.X[fold.train],
        y,
        inner_splits(y, context.random_state),
        classes=np.arange(problem.n_classes[0]),
        probabilities=probabilities,
        fit_params=lambda rows: _groups(model, problem, fold.train[rows]),
    )
    return FoldPredictions.of_classes(fold.train, labels, proba)


def _groups(model: Any, problem: Problem, rows: np.ndarray) -> dict[str, np.ndarray]:
    """The training rows' groups for a model whose fit takes them (:func:`group_fit_params`)."""
    groups = None if problem.groups is None else problem.groups[rows]
    return group_fit_params(model, groups)


def _run_regression(context: TaskContext, key: TaskKey, fold: Fold) -> TaskResult:
    problem = context.problem
    model = build_estimator(key.classifier, problem, random_state=context.random_state)
    Y = problem.Y if problem.n_targets > 1 else problem.Y[:, 0]
    timer = _Timer()
    model.fit(problem.X[fold.train], Y[fold.train], **_groups(model, problem, fold.train))
    fit_time, fit_cpu = timer.lap()
    Y_pred = np.asarray(model.predict(problem.X[fold.test]), dtype=np.float64)
    predict_time, predict_cpu = timer.lap()
    predictions = FoldPredictions(fold.test, values=Y_pred.reshape(len(fold.test), -1))
    costs = _costs(fit_time, fit_cpu, predict_time, predict_cpu, model)
    return scored_result(context, key, fold, predictions, costs)


def _run_multitarget(context: TaskContext, key: TaskKey, fold: Fold) -> TaskResult:
    problem = context.problem
    model = build_estimator(
        key.classifier, problem, random_state=context.random_state, extra_specs=context.specs
    )
    timer = _Timer()
    model.fit(problem.X[fold.train], problem.Y[fold.train])
    fit_time, fit_cpu = timer.lap()
    X_test = problem.X[fold.test]
    Y_pred = np.asarray(model.predict(X_test), dtype=np.int64).reshape(len(fold.test), -1)
    probas = None
    if hasattr(model, "predict_proba"):
        try:
            probas = tuple(np.asarray(p, dtype=np.float64) for p in model.predict_proba(X_test))
        except (AttributeError, NotImplementedError):
            probas = None
    predict_time, predict_cpu = timer.lap()
    costs = _costs(fit_time, fit_cpu, predict_time, predict_cpu, model)
    return scored_result(
        context,
        key,
        fold,
        FoldPredictions(fold.test, Y_pred, probas),
        costs,
        params=chosen_params(model, problem.target_names),
    )


class _Timer:
    """Wall and CPU seconds since the previous lap."""

    def __init__(self) -> None:
        self._wall = time.perf_counter()
        self._cpu = time.process_time()

    def lap(self) -> tuple[float, float]:
        wall, cpu = time.perf_counter(), time.process_time()
        laps = (wall - self._wall, cpu - self._cpu)
        self._wall, self._cpu = wall, cpu
        return laps


class _ByteCounter:
    """A write-only file that only counts what is written to it."""

    def __init__(self) -> None:
        self.size = 0

    def write(self, data: bytes | pickle.PickleBuffer) -> int:
        # Protocol 5 hands large buffers over as PickleBuffer objects, which have no len().
        size = memoryview(data).nbytes
        self.size += size
        return size


def pickled_size(obj: object) -> float:
    """Bytes of ``obj`` pickled with the highest protocol; NaN if it cannot be pickled."""
    counter = _ByteCounter()
    try:
        pickle.dump(obj, counter, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:
        return math.nan
    return float(counter.size)


def _costs(
    fit_time: float, fit_cpu: float, predict_time: float, predict_cpu: float, model: object
) -> dict[str, float]:
    return {
        "fit_time": fit_time,
        "predict_time": predict_time,
        "fit_cpu_time": fit_cpu,
        "predict_cpu_time": predict_cpu,
        "model_size": pickled_size(model),
    }


def _distinct_warnings(caught: Sequence[warnings.WarningMessage]) -> list[str]:
    seen: list[str] = []
    for message in caught:
        text = f"{message.category.__name__}: {message.message}"
        if text not in seen:
            seen.append(text)
        if len(seen) == MAX_WARNINGS:
            break
    return seen
