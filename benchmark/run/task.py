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
from touchbench.benchmark.estimators import build_estimator, group_fit_params
from touchbench.benchmark.evaluation.calibration import PER_TARGET, reliability
from touchbench.benchmark.evaluation.metrics import (
    confusion_matrix,
    expand_proba,
    multiclass_scores,
)
from touchbench.benchmark.evaluation.recordings import Recordings
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
    """

    problem: Problem
    specs: Mapping[str, ClassifierSpec]
    folds: Sequence[Fold]
    random_state: int = 0
    by_recording: bool = False

    def recordings(self, fold: Fold) -> Recordings | None:
        """The recordings of ``fold``'s test windows when scored per recording."""
        if not self.by_recording or self.problem.groups is None:
            return None
        return Recordings.of(self.problem.groups[fold.test])

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
    model.fit(problem.X[fold.train], y[fold.train], **_groups(model, problem, fold))
    fit_time, fit_cpu = timer.lap()
    X_test = problem.X[fold.test]
    y_pred = np.asarray(model.predict(X_test), dtype=np.int64)
    proba = None
    if context.specs[key.classifier].probabilities:
        proba = expand_proba(model.predict_proba(X_test), model.classes_, n_classes=n_classes)
    predict_time, predict_cpu = timer.lap()
    y_test = y[fold.test]
    recordings = context.recordings(fold)
    if recordings is not None:
        y_test = recordings.truth(y_test)
        y_pred, proba = recordings.classes(y_pred, proba, n_classes)
    scores, confusion = multiclass_scores(y_test, y_pred, proba, n_classes=n_classes)
    scores.update(_costs(fit_time, fit_cpu, predict_time, predict_cpu, model))
    return TaskResult(
        key,
        "ok",
        None,
        scores,
        confusion,
        int(fold.train.size),
        int(fold.test.size),
        params=chosen_params(model),
        # the bins, not the probabilities: they add up over folds, 30 numbers a fold
        calibration=None if proba is None else reliability(y_test, proba).to_json(),
    )


def _groups(model: Any, problem: Problem, fold: Fold) -> dict[str, np.ndarray]:
    """The training fold's groups for a model whose fit takes them (:func:`group_fit_params`)."""
    groups = None if problem.groups is None else problem.groups[fold.train]
    return group_fit_params(model, groups)


def _run_regression(context: TaskContext, key: TaskKey, fold: Fold) -> TaskResult:
    from touchbench.benchmark.evaluation.regression import regression_scores

    problem = context.problem
    model = build_estimator(key.classifier, problem, random_state=context.random_state)
    Y = problem.Y if problem.n_targets > 1 else problem.Y[:, 0]
    timer = _Timer()
    model.fit(problem.X[fold.train], Y[fold.train], **_groups(model, problem, fold))
    fit_time, fit_cpu = timer.lap()
    Y_pred = np.asarray(model.predict(problem.X[fold.test]), dtype=np.float64)
    predict_time, predict_cpu = timer.lap()
    Y_test, Y_pred = problem.Y[fold.test], Y_pred.reshape(len(fold.test), -1)
    recordings = context.recordings(fold)
    if recordings is not None:
        Y_test, Y_pred = recordings.truth(Y_test), recordings.mean(Y_pred)
    metrics, per_target = regression_scores(
        Y_test,
        Y_pred,
        target_names=problem.target_names,
        coordinates=problem.coordinates,
    )
    metrics.update(_costs(fit_time, fit_cpu, predict_time, predict_cpu, model))
    return TaskResult(
        key,
        "ok",
        None,
        metrics,
        None,
        int(fold.train.size),
        int(fold.test.size),
        per_target=per_target,
    )


def _run_multitarget(context: TaskContext, key: TaskKey, fold: Fold) -> TaskResult:
    from touchbench.benchmark.multitarget import multitarget_scores

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
            probas = [np.asarray(p, dtype=np.float64) for p in model.predict_proba(X_test)]
        except (AttributeError, NotImplementedError):
            probas = None
    predict_time, predict_cpu = timer.lap()
    Y_test = problem.Y[fold.test]
    recordings = context.recordings(fold)
    if recordings is not None:
        Y_test, Y_pred, probas = _pooled_targets(recordings, Y_test, Y_pred, probas, problem)
    scores = dict(
        multitarget_scores(
            Y_test,
            Y_pred,
            probas,
            n_classes=problem.n_classes,
            target_names=problem.target_names,
        )
    )
    per_target = scores.pop("per_target", None)
    metrics = {name: float(v) for name, v in scores.items() if isinstance(v, int | float)}
    metrics.update(_costs(fit_time, fit_cpu, predict_time, predict_cpu, model))
    confusion = [
        confusion_matrix(Y_test[:, t], Y_pred[:, t], n_classes=k).tolist()
        for t, k in enumerate(problem.n_classes)
    ]
    return TaskResult(
        key,
        "ok",
        None,
        metrics,
        confusion,
        int(fold.train.size),
        int(fold.test.size),
        per_target=per_target,
        params=chosen_params(model, problem.target_names),
        # per target, the bins of its top label's confidence (as a multi-class fold keeps)
        calibration=None
        if probas is None
        else {
            PER_TARGET: {
                name: reliability(Y_test[:, t], probas[t]).to_json()
                for t, name in enumerate(problem.target_names)
            }
        },
    )


def _pooled_targets(
    recordings: Recordings,
    Y_test: np.ndarray,
    Y_pred: np.ndarray,
    probas: list[np.ndarray] | None,
    problem: Problem,
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray] | None]:
    """Each target's windows pooled per recording: truth, predictions and probabilities
    (shapes (n_recordings, n_targets) and n_targets x (n_recordings, n_classes))."""
    pooled = [
        recordings.classes(Y_pred[:, t], None if probas is None else probas[t], k)
        for t, k in enumerate(problem.n_classes)
    ]
    labels = np.stack([p[0] for p in pooled], axis=1)
    means = [p[1] for p in pooled]
    kept = None if any(m is None for m in means) else [m for m in means if m is not None]
    return recordings.truth(Y_test), labels, kept


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
