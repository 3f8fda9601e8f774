"""The folds of a run's derived entries, computed from its workers' fold predictions.

:class:`Combiner` runs in the engine's own process.  It takes each worker result as it
arrives (and those of an earlier execution of the run), and as soon as every member of a
derived entry (:mod:`benchmark.run.members`) has a result on a fold, computes that entry's
fold: a vote from the members' test-fold predictions, a stack or an ensemble selection from
their inner out-of-fold predictions of the training fold, then their test-fold predictions.
The functions that combine are the catalogue's (:mod:`benchmark.catalogue.ensembles`,
:mod:`benchmark.catalogue.stacking`), those an ensemble fitted on its own uses, so that the
fold is what the refitted ensemble predicts with the same fitted members.

A derived fold is scored as a task's (:func:`benchmark.run.task.scored_result`).  Its costs
are what it costs on its own: its members' fits and predictions (a stack's or selection's
inner predictions of every candidate, and the fits of the kept), plus its own combination;
the run spends only the last, the members' folds being the members' own.  A member that
failed fails a vote's fold; a stack or selection leaves it out, and fails only when too few
candidates are left.
"""

from __future__ import annotations

import time
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from touchbench.benchmark.catalogue.ensembles import (
    blend,
    class_scores,
    greedy_selection,
    hard_vote,
    soft_vote,
)
from touchbench.benchmark.catalogue.stacking import choose_and_stack
from touchbench.benchmark.evaluation.metrics import expand_proba
from touchbench.benchmark.predictions import FoldPredictions
from touchbench.benchmark.results import TaskKey, TaskResult
from touchbench.benchmark.run.folds import Fold
from touchbench.benchmark.run.members import Derived, RunPlan
from touchbench.benchmark.run.task import TaskContext, failed_result, pickled_size, scored_result

__all__ = ["Combiner"]

Round = tuple[int, int]


@dataclass(frozen=True)
class _Output:
    """An entry's result on a fold, and the predictions its derived entries read."""

    result: TaskResult
    outer: FoldPredictions | None
    inner: FoldPredictions | None


@dataclass(frozen=True)
class _Choice:
    """A derived fold's predictions and what made them.

    Attributes
    ----------
    predictions : FoldPredictions
    params : dict or None
        What it chose on the training fold (the result's ``params``).
    used : list of _Output
        The members whose fitted models it predicts with.
    candidates : list of _Output
        The members whose inner predictions it read.
    size : float
        Bytes of its own fitted part (a stack's logistic regression).
    """

    predictions: FoldPredictions
    params: dict[str, Any] | None
    used: list[_Output]
    candidates: list[_Output]
    size: float = 0.0


class _CannotCombineError(Exception):
    """A derived fold that cannot be computed (its members' failures)."""


class Combiner:
    """Computes derived folds as their members' results arrive.

    Parameters
    ----------
    plan : RunPlan
    context : TaskContext
        The run's problem, folds, seed and scoring (as its tasks score).
    done : collection of TaskKey
        Tasks stored by an earlier execution: their derived folds are not computed again
        unless another derived fold still to compute reads them.
    """

    def __init__(self, plan: RunPlan, context: TaskContext, *, done: Collection[TaskKey]) -> None:
        self._plan = plan
        self._context = context
        self._folds = {(f.repeat, f.fold): f for f in context.folds}
        self._done = set(done)
        self._needed = frozenset().union(*(plan.needs(d) for d in plan.derived), plan.derived)
        self._outputs: dict[Round, dict[str, _Output]] = {}
        self._finished: set[Round] = set()

    def add(self, result: TaskResult) -> list[TaskResult]:
        """Take a worker's result; return the derived folds it completes, members first
        (those stored already are computed only for the others that read them)."""
        round_ = (result.key.repeat, result.key.fold)
        entry = result.key.classifier
        if round_ in self._finished or entry not in self._needed or entry in self._plan.derived:
            return []
        if result.ok and (
            result.predictions is None
            or (entry in self._plan.inner and result.inner_predictions is None)
        ):
            return []  # read back without its predictions: it runs again for them
        outputs = self._outputs.setdefault(round_, {})
        outputs[entry] = _Output(result, result.predictions, result.inner_predictions)
        wanted = self._wanted(round_)
        fresh = []
        for name, derived in self._plan.derived.items():
            if name in outputs or name not in wanted:
                continue
            if any(member not in outputs for member in derived.members):
                continue
            outputs[name] = self._combine(derived, self._folds[round_], outputs)
            if TaskKey(name, *round_) not in self._done:
                fresh.append(outputs[name].result)
        if all(name in outputs for name in wanted):
            self._finished.add(round_)
            del self._outputs[round_]
        return fresh

    def _wanted(self, round_: Round) -> set[str]:
        """The derived entries to compute on ``round_``: those not stored yet, and the
        derived members they read."""
        wanted: set[str] = set()

        def want(name: str) -> None:
            if name in self._plan.derived and name not in wanted:
                wanted.add(name)
                for member in self._plan.derived[name].members:
                    want(member)

        for name in self._plan.derived:
            if TaskKey(name, *round_) not in self._done:
                want(name)
        return wanted

    # one derived fold ----------------------------------------------------------------

    def _combine(self, derived: Derived, fold: Fold, outputs: Mapping[str, _Output]) -> _Output:
        key = TaskKey(derived.id, fold.repeat, fold.fold)
        started, cpu = time.perf_counter(), time.process_time()
        try:
            if derived.reads_inner:
                choice = self._choose(derived, fold, outputs)
            else:
                used = [outputs[m] for m in derived.members]
                _check_ok(derived, used)
                choice = _Choice(_vote(derived, used, self.n_classes), None, used, [])
        except _CannotCombineError as failure:
            return _Output(failed_result(key, "error", str(failure), fold), None, None)
        inner = None
        if derived.id in self._plan.inner:  # a vote among a stack's or selection's candidates
            members = [outputs[m] for m in derived.members]
            inner = _vote(derived, members, self.n_classes, inner=True)
        own = (time.perf_counter() - started, time.process_time() - cpu)
        result = scored_result(
            self._context, key, fold, choice.predictions, _costs(choice, own), params=choice.params
        )
        return _Output(result, choice.predictions, inner)

    @property
    def n_classes(self) -> int:
        return self._context.problem.n_classes[0]

    def _choose(self, derived: Derived, fold: Fold, outputs: Mapping[str, _Output]) -> _Choice:
        """A stack's or a selection's fold: chosen on the candidates' inner predictions of
        the training fold, applied to their test-fold predictions."""
        y = self._context.problem.Y[fold.train, 0]
        classes = np.unique(y)
        usable = {}
        left_out = dict(derived.left_out)
        for member in derived.members:
            output = outputs[member]
            if output.result.ok and output.inner is not None and output.outer is not None:
                if not np.array_equal(output.inner.indices, fold.train):
                    raise ValueError(f"inner predictions of '{member}' for other rows")
                usable[member] = output
            else:
                left_out[member] = output.result.error or "no inner predictions"
        spec = derived.spec
        seed = self._context.random_state
        blocks = {m: _scores(o.inner, classes) for m, o in usable.items()}
        if derived.combine == "stack":
            assert spec.stacking is not None
            top_n = spec.stacking.top_n
            if len(usable) < top_n:
                raise _CannotCombineError(_too_few(top_n, len(usable), left_out))
            chosen, _, final = choose_and_stack(blocks, y, classes, top_n, seed)
            features = np.hstack([_scores(usable[m].outer, classes) for m in chosen])
            labels = np.asarray(final.predict(features), dtype=np.int64)
            proba = expand_proba(
                final.predict_proba(features), final.classes_, n_classes=self.n_classes
            )
            params: dict[str, Any] = {"members": list(chosen)}
            kept = [usable[m] for m in chosen]
            size = pickled_size(final)
        else:
            assert spec.ensemble is not None
            if not usable:
                raise _CannotCombineError(_too_few(1, 0, left_out))
            counts = greedy_selection(list(blocks.values()), y, classes, spec.ensemble.rounds)
            picked = [(m, c) for m, c in zip(usable, counts, strict=True) if c]
            mean = blend(
                [_scores(usable[m].outer, classes) for m, _ in picked], [c for _, c in picked]
            )
            labels = classes[np.argmax(mean, axis=1)].astype(np.int64)
            proba = np.zeros((len(labels), self.n_classes))
            proba[:, classes] = mean
            params = {"weights": {m: c / spec.ensemble.rounds for m, c in picked}}
            kept = [usable[m] for m, _ in picked]
            size = 0.0
        if left_out:
            params["left_out"] = left_out
        predictions = FoldPredictions.of_classes(fold.test, labels, proba)
        return _Choice(predictions, params, kept, list(usable.values()), size)


def _vote(
    derived: Derived, members: list[_Output], n_classes: int, *, inner: bool = False
) -> FoldPredictions:
    """The soft or hard vote of the members' test-fold (or inner) predictions."""
    parts = [m.inner if inner else m.outer for m in members]
    if any(p is None for p in parts):
        raise _CannotCombineError(f"a member of '{derived.id}' has no predictions")
    rows = parts[0].indices  # type: ignore[union-attr]
    if derived.combine == "soft":
        probas = [p.probabilities for p in parts]  # type: ignore[union-attr]
        missing = [m for m, p in zip(derived.members, probas, strict=True) if p is None]
        if missing:
            raise _CannotCombineError(f"member '{missing[0]}' has no probabilities to average")
        labels, mean = soft_vote(probas)  # type: ignore[arg-type]
        return FoldPredictions.of_classes(rows, labels, mean)
    labels = hard_vote([p.label for p in parts], n_classes)  # type: ignore[union-attr]
    return FoldPredictions.of_classes(rows, labels, None)


def _check_ok(derived: Derived, members: list[_Output]) -> None:
    for name, output in zip(derived.members, members, strict=True):
        if not output.result.ok:
            raise _CannotCombineError(f"member '{name}' failed on this fold: {output.result.error}")


def _scores(predictions: FoldPredictions | None, classes: np.ndarray) -> np.ndarray:
    """Class scores over the training fold's ``classes``: probabilities, or labels one-hot."""
    assert predictions is not None
    proba = predictions.probabilities
    return class_scores(predictions.label, None if proba is None else proba[:, classes], classes)


def _too_few(needed: int, usable: int, left_out: Mapping[str, str]) -> str:
    reasons = "; ".join(f"{m}: {why}" for m, why in left_out.items())
    return f"needs {needed} candidates with inner predictions, {usable} left ({reasons})"


#: Cost metrics a derived fold adds up from its members', and what each adds for it.
_SUMMED = ("fit_time", "fit_cpu_time", "predict_time", "predict_cpu_time", "model_size")
_INNER = {"fit_time": "inner_time", "fit_cpu_time": "inner_cpu_time"}


def _costs(choice: _Choice, own: tuple[float, float]) -> dict[str, float]:
    """What the derived fold costs on its own: the used members' costs, every candidate's
    inner predictions, and its own combination (counted as fitting)."""
    costs = {name: sum(o.result.metrics.get(name, 0.0) for o in choice.used) for name in _SUMMED}
    for name, inner in _INNER.items():
        costs[name] += sum(o.result.metrics.get(inner, 0.0) for o in choice.candidates)
    costs["fit_time"] += own[0]
    costs["fit_cpu_time"] += own[1]
    costs["model_size"] += choice.size
    return costs
