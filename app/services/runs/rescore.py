"""A finished run's results scored again from its stored test-fold predictions, per
recording or per window, without fitting anything again.

A run keeps what each task predicted for its test fold (:mod:`app.store.predictions`), and
:func:`benchmark.evaluation.fold_scores.score_fold` scores those predictions exactly as the
task did.  So a run scored per window gives its per-recording scores (and the other way
round) from the store alone: the run's problem is rebuilt from its data set, as a resume
rebuilds it, and every stored fold is scored again the other way.  Its costs (fitting and
predicting times, model sizes) stay the ones measured.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import cast, get_args

from touchbench.app.errors import FieldError
from touchbench.app.schemas.runs import Aggregate
from touchbench.app.services.runs.problem import prepare_problem
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import count_groups, load_dataset
from touchbench.app.store.predictions import load_predictions
from touchbench.app.store.runs import RunInfo, load_results
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.fold_scores import score_fold
from touchbench.benchmark.evaluation.metrics import COST_METRICS
from touchbench.benchmark.evaluation.recordings import check_one_label
from touchbench.benchmark.results import TaskResult

#: Aggregations a leaderboard may be re-scored to.
AGGREGATES: tuple[str, ...] = get_args(Aggregate)
#: Metrics of a fold that measure its costs, not its predictions: kept as measured.
_INNER_COSTS = ("inner_time", "inner_cpu_time")


def check_aggregate(aggregate: str | None) -> Aggregate | None:
    """``aggregate`` if it is one of :data:`AGGREGATES`; ``None`` (as the run scored) if
    ``None``.

    Raises
    ------
    FieldError
        For ``aggregate``: another value.
    """
    if aggregate is not None and aggregate not in AGGREGATES:
        raise FieldError("aggregate", f"Input should be {' or '.join(repr(a) for a in AGGREGATES)}")
    return cast(Aggregate | None, aggregate)


def check_rescorable(run: RunInfo, aggregate: Aggregate) -> None:
    """Refuse what ``run``'s record alone says cannot be scored per ``aggregate``: an
    imported run (it holds scores, not predictions).  Cheap: callers check it before they
    read the run's results, which for an imported run may be tens of thousands.

    Raises
    ------
    FieldError
        For ``aggregate``.
    """
    if run.config.imported:
        raise FieldError(
            "aggregate",
            f"run {run.id} was imported: it holds its scores, not the fold predictions "
            f"they were computed from, so it cannot be scored per {aggregate}",
        )


def as_asked(
    store: Store, run: RunInfo, results: Sequence[TaskResult], aggregate: Aggregate | None
) -> list[TaskResult]:
    """``results`` of ``run`` scored per ``aggregate``: as stored where the run scored so
    (or nothing was asked), else :func:`rescored_results`."""
    if aggregate is None or aggregate == run.config.aggregate:
        return list(results)
    return rescored_results(store, run, results, aggregate)


def results_as_asked(
    store: Store, run: RunInfo, aggregate: Aggregate | None, *, confusion: bool = True
) -> list[TaskResult]:
    """``run``'s stored results scored per ``aggregate`` (:func:`as_asked`); a run that
    cannot be scored so refused before they are read (:func:`check_rescorable`).

    Parameters
    ----------
    confusion : bool
        Read the results' confusion matrices (:func:`~app.store.runs.load_results`).

    Raises
    ------
    FieldError
        For ``aggregate``: as :func:`rescored_results`.
    """
    if aggregate is not None and aggregate != run.config.aggregate:
        check_rescorable(run, aggregate)
    return as_asked(store, run, load_results(store, run.id, confusion=confusion), aggregate)


def rescorable(store: Store, run: RunInfo) -> bool:
    """Whether ``run``'s leaderboard may be asked per recording as well as per window: a run
    touchbench carried out (an imported one holds no predictions) on a data set whose
    instances fall into recordings (groups).  What only scoring finds out (a recording of
    several labels, a run stored before predictions were kept) :func:`rescored_results`
    refuses."""
    if run.config.imported or run.dataset_id is None:
        return False
    return count_groups(store, run.dataset_id) > 0


def rescored_results(
    store: Store, run: RunInfo, results: Sequence[TaskResult], aggregate: Aggregate
) -> list[TaskResult]:
    """``results`` of ``run`` with their scores computed again from the run's stored
    test-fold predictions, pooled per recording (``aggregate="recording"``) or per window.

    Parameters
    ----------
    store : Store
    run : RunInfo
        A run touchbench carried out.
    results : sequence of TaskResult
        The run's stored results; those that failed are kept as they are.
    aggregate : {"window", "recording"}

    Returns
    -------
    list of TaskResult
        The same tasks in the same order: their scores, confusion matrices, per-target
        scores and reliability bins as :func:`~benchmark.evaluation.fold_scores.score_fold`
        finds them, their costs as measured.

    Raises
    ------
    FieldError
        For ``aggregate``: an imported run (it holds scores, not predictions); per
        recording, a data set without recording groups or a recording whose windows carry
        several labels (:func:`~benchmark.evaluation.recordings.check_one_label`); a task
        of the run whose predictions were not stored (a run of an older version).
    """
    check_rescorable(run, aggregate)
    prepared = prepare_problem(
        load_dataset(store, run.dataset_id), run.config.targets_given, run.config.position or ()
    )
    problem = prepared.problem
    by_recording = aggregate == "recording"
    if by_recording:
        try:
            check_one_label(problem.Y, problem.groups, prepared.target_names, run.dataset_name)
        except ConfigurationError as error:
            raise FieldError("aggregate", str(error)) from None
    stored = load_predictions(store, run.id)
    missing = [r.key for r in results if r.ok and r.key not in stored]
    if missing:
        first = missing[0]
        raise FieldError(
            "aggregate",
            f"run {run.id} has no stored fold predictions for {len(missing)} of its "
            f"{sum(r.ok for r in results)} finished task(s) (first: {first.classifier}, "
            f"fold {first.fold}): it ran before touchbench kept them; run the benchmark "
            f"again to score it per {aggregate}",
        )
    costs = (*COST_METRICS, *_INNER_COSTS)
    out = []
    for result in results:
        if not result.ok:
            out.append(result)
            continue
        scores = score_fold(problem, stored[result.key], by_recording=by_recording)
        measured = {name: result.metrics[name] for name in costs if name in result.metrics}
        out.append(
            replace(
                result,
                metrics={**scores.metrics, **measured},
                confusion=scores.confusion,
                per_target=scores.per_target,
                calibration=scores.calibration,
                predictions=stored[result.key],
            )
        )
    return out
