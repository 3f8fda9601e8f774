"""Which sensor can go: the run's classifiers cross-validated again with a group of features
removed (a channel, a feature family), on the run's own folds.

Permutation importance (:mod:`benchmark.run.importance`) asks how much a fitted classifier
leans on a group; an ablation asks what a classifier fitted without it scores, which is the
question of a robot that would carry one microphone fewer: another feature may stand in.
The full set's scores are the run's own; each ablation is one more cross-validation of a
:func:`without_columns` problem through the engine, fold for fold against them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.results import TaskResult
from touchbench.benchmark.run.folds import Fold
from touchbench.benchmark.sequence import SequenceLayout


def without_columns(problem: Problem, columns: Sequence[int]) -> Problem:
    """``problem`` with the feature ``columns`` removed.

    Nominal columns keep their label counts at their new positions; a sequence block loses
    the channels whose columns are all removed (a block left partly cut, or with no channel,
    is no sequence any more, and sequence classifiers refuse the problem).

    Raises
    ------
    ConfigurationError
        A column out of range, or every column removed.
    """
    removed = np.unique(np.asarray(columns, dtype=np.int64))
    n = problem.n_features
    if removed.size and (removed[0] < 0 or removed[-1] >= n):
        raise ConfigurationError(f"columns to remove must lie in 0..{n - 1}")
    keep = np.setdiff1d(np.arange(n), removed)
    if keep.size == 0:
        raise ConfigurationError("removing these columns leaves no feature")
    position = {int(old): new for new, old in enumerate(keep)}
    nominal = {position[c]: k for c, k in problem.nominal_features.items() if c in position}
    return replace(
        problem,
        X=problem.X[:, keep],
        nominal_features=nominal,
        sequence=_sequence_without(problem.sequence, removed),
    )


def _sequence_without(layout: SequenceLayout | None, removed: np.ndarray) -> SequenceLayout | None:
    if layout is None:
        return None
    before = int(np.count_nonzero(removed < layout.start))
    inside = removed[(removed >= layout.start) & (removed < layout.stop)]
    if inside.size == 0:
        return replace(layout, start=layout.start - before)
    cut = set(((inside - layout.start) // layout.length).tolist())
    whole = all(
        np.isin(layout.start + c * layout.length + np.arange(layout.length), inside).all()
        for c in cut
    )
    channels = tuple(name for c, name in enumerate(layout.channels) if c not in cut)
    if not whole or not channels:
        return None
    return SequenceLayout(start=layout.start - before, channels=channels, length=layout.length)


def ablate(
    problem: Problem,
    classifiers: Sequence[str],
    folds: Sequence[Fold],
    groups: Mapping[str, Sequence[int]],
    *,
    on_result: Callable[[str, TaskResult], None] = lambda group, result: None,
    **engine: Any,
) -> dict[str, list[TaskResult]]:
    """Cross-validate ``classifiers`` once per group with that group's columns removed.

    Parameters
    ----------
    problem : Problem
    classifiers : sequence of str
    folds : sequence of Fold
        The folds of the full set's scores (the same ones, so that the scores pair).
    groups : mapping of str to sequence of int
        Group name -> its feature columns.
    on_result : callable
        Hears (group, result) as each task ends.
    **engine
        Passed to :func:`benchmark.run.engine.run_tasks` (``timeout`` is required there;
        ``jobs``, ``random_state``, ``extra_specs``, ``stop``...).

    Returns
    -------
    dict of str to list of TaskResult
        Per group, the engine's results (classifier-major).
    """
    from touchbench.benchmark.run.engine import run_tasks

    out: dict[str, list[TaskResult]] = {}
    for name, columns in groups.items():
        reduced = without_columns(problem, columns)
        out[name] = run_tasks(
            reduced,
            classifiers,
            folds,
            on_result=lambda result, name=name: on_result(name, result),  # type: ignore[misc]
            **engine,
        )
    return out
