"""A run's leaderboard from its stored results: ranked, marked against a baseline, with runs
beside it, per-target scores and what the race, the budget or a stop left out.

The web page asks for the same run's leaderboard again and again (its fragments, each
sort, each visitor): :func:`ranked_run` ranks a run once per version of its results and
keeps the ranking without the fold results, so that a run of thousands of classifiers (an
imported results file) costs its statistics once, not on every fragment.
"""

from __future__ import annotations

# Imports inside functions: start-up time: the statistics (scipy) load when a leaderboard
# is first built, not when the API's routes or the listing commands import this module.
import gc
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar, cast

import numpy as np

from touchbench.app.schemas.runs import (
    PER_RECORDING_NOTE,
    Aggregate,
    BudgetSchema,
    FoldChoiceSchema,
    LeaderboardRowSchema,
    LeaderboardSchema,
    MarkSummary,
    RaceSchema,
    TunedComparisonSchema,
)
from touchbench.app.schemas.status import UNFINISHED, Status
from touchbench.app.services.beside import Beside, besides, merged_results, row_runs
from touchbench.app.services.runs.ranking import check_metric, run_metric
from touchbench.app.services.runs.stopping import RACE_TEST, never_started
from touchbench.app.store.database import Store
from touchbench.app.store.drops import load_drops
from touchbench.app.store.runs import RunInfo, get_run, load_results, results_version
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.results import Drop, Origin, TaskResult

if TYPE_CHECKING:  # scipy.stats (significance) loads when a leaderboard is first built
    from touchbench.benchmark.evaluation.leaderboard import Leaderboard


T = TypeVar("T")

#: Why a run has no results yet, when it is under way (:data:`app.schemas.status.UNFINISHED`).
_UNDER_WAY = {
    Status.QUEUED: "it waits for a worker",
    Status.RUNNING: "it is still running",
    Status.CANCELLING: "it is being cancelled",
}


class NoResultsError(ConfigurationError):
    """A run without a stored result has no leaderboard yet.

    Attributes
    ----------
    under_way : bool
        The run is queued, running or being cancelled (resuming it would not help).
    """

    def __init__(self, run: RunInfo) -> None:
        hint = _UNDER_WAY.get(run.status, f"it is {run.status}; resuming it carries it out")
        super().__init__(f"run {run.id} has no results yet ({hint})")
        self.run = run
        self.under_way = run.status in UNFINISHED


@dataclass(frozen=True)
class RunLeaderboard:
    """A run, its stored results and their leaderboard.

    Attributes
    ----------
    run : RunInfo
    board : Leaderboard
        The run's classifiers ranked, with WEKA's marks against a baseline.
    results : list of TaskResult
        Every stored fold result of the run, read once.
    besides : tuple of Beside
        Runs ranked beside this one (an imported paper's results), with how each is
        compared; their results are in ``board`` but not in ``results``.
    drops : dict of str to Drop
        The classifiers that stopped before their last fold (raced or budgeted runs).
    rescored : {"window", "recording"} or None
        How ``results`` were scored again from the run's stored fold predictions, when not
        as the run scored them (:mod:`.rescore`); ``None``: as the run scored them.
    """

    run: RunInfo
    board: Leaderboard
    results: list[TaskResult]
    besides: tuple[Beside, ...]
    drops: dict[str, Drop]
    rescored: Aggregate | None = field(default=None, kw_only=True)

    @property
    def entries(self) -> list[str]:
        """The run's classifiers, then the helpers fitted only as members of its ensembles:
        every entry with rows and folds of its own."""
        return [*self.run.classifiers, *self.run.config.helpers]

    @property
    def aggregate(self) -> Aggregate:
        """What one prediction of the leaderboard's scores is: a window or a recording."""
        return self.rescored or self.run.config.aggregate

    @property
    def per_recording(self) -> bool:
        """Whether the scores count each recording's windows as one prediction."""
        return self.aggregate == "recording"

    def notes(self) -> list[str]:
        """What the leaderboard of a run scored per recording, raced, budgeted or stopped
        says under its table."""
        notes = [PER_RECORDING_NOTE] if self.per_recording else []
        if self.rescored is not None:
            notes.append(
                f"re-scored per {self.rescored} from the run's stored test-fold predictions, "
                f"nothing fitted again (the run scored per {self.run.config.aggregate}; the "
                "costs are as measured then)"
            )
        helpers = self.run.config.helpers
        if helpers:
            spent = sum(
                r.metrics.get("fit_time", 0.0) + r.metrics.get("predict_time", 0.0)
                for r in self.results
                if r.ok and r.key.classifier in helpers
            )
            notes.append(
                f"fitted only as members of ensembles: {', '.join(helpers)} "
                f"({spent:.1f} s of fitting and predicting in all)"
            )
        notes += [part.note for part in (self.race(), self.budget()) if part is not None]
        unstarted = [c for c, d in self.drops.items() if d.reason == "not started"]
        if unstarted:
            more = f" and {len(unstarted) - 10} more" if len(unstarted) > 10 else ""
            notes.append(
                f"{len(unstarted)} classifier(s) never started (the run is {self.run.status}): "
                f"{', '.join(unstarted[:10])}{more}"
            )
        return notes

    def race(self) -> RaceSchema | None:
        """How the run raced; ``None`` for a run that did not."""
        race = self.run.config.race
        if race is None:
            return None
        alpha = race.alpha
        dropped = sum(1 for d in self.drops.values() if d.reason == "race")
        return RaceSchema(
            alpha=alpha,
            test=RACE_TEST,
            dropped=dropped,
            note=f"raced at alpha {alpha:g} ({RACE_TEST}); {dropped} dropped",
        )

    def budget(self) -> BudgetSchema | None:
        """What the run's total budget cut; ``None`` for a run without one."""
        minutes = self.run.config.budget_total
        if minutes is None:
            return None
        cut = [c for c, d in self.drops.items() if d.reason == "budget"]
        raced_out = sum(
            self.run.config.tasks_per_entry(len(self.run.classifiers)) - d.after_fold
            for d in self.drops.values()
            if d.reason == "race"
        )
        missing = max(self.run.n_tasks - len(self.results) - raced_out, 0)
        cut_text = f"; cut: {', '.join(cut)}" if cut else ""
        return BudgetSchema(
            minutes=minutes,
            cut=cut,
            tasks_not_run=missing,
            minutes_spent=self.run.seconds_spent / 60.0,
            note=f"total budget {minutes:g} min: {missing} task(s) not run{cut_text}",
        )

    def report(self) -> LeaderboardSchema:
        """What ``leaderboard --json`` prints and the API serves: rows with their per-target
        scores, tuned twins against their defaults, the choices per fold."""
        from touchbench.benchmark.evaluation.tuned import compare_tuned, fold_choices

        run, board, results = self.run, self.board, self.results
        per_target = per_target_summary(results)
        data = board.to_json()
        origins = row_runs(self.besides)
        for row in data["leaderboard"]:
            row["run_id"] = origins.get(row["classifier"])
            targets = per_target.get(row["classifier"])
            if targets:
                row["metrics"]["per_target"] = {
                    target: {
                        name: {"mean": mean, "std": std} for name, (mean, std) in scores.items()
                    }
                    for target, scores in targets.items()
                }
        return LeaderboardSchema(
            run_id=run.id,
            dataset=run.dataset_name,
            kind=run.kind,
            targets=run.targets,
            status=run.status,
            folds=run.folds_text,
            metric=data["metric"],
            lower_is_better=data["lower_is_better"],
            baseline=data["baseline"],
            summary=MarkSummary(**data["summary"]),
            leaderboard=[LeaderboardRowSchema(**row) for row in data["leaderboard"]],
            tuning=[
                TunedComparisonSchema(**c.to_json())
                for c in compare_tuned(results, metric=board.metric, alpha=board.alpha)
            ],
            choices=[FoldChoiceSchema(**c.to_json()) for c in fold_choices(results)],
            beside=[b.schema() for b in self.besides],
            race=self.race(),
            budget=self.budget(),
            aggregate=self.aggregate,
            notes=self.notes(),
        )


def run_leaderboard(
    store: Store,
    run_id: int | str,
    *,
    metric: str | None = None,
    baseline: str | None = None,
    beside: Sequence[int | str] = (),
    aggregate: str | None = None,
    confusion: bool = True,
) -> RunLeaderboard:
    """A run's leaderboard from its stored results.

    Parameters
    ----------
    metric, baseline : str, optional
        Rank by this metric, mark against this classifier; default: what the run was
        asked to rank by, else its kind's metric and its best classifier.
    beside : sequence of run ids
        Runs of the same data set and target whose classifiers are ranked too (an
        imported paper's results): t-tested where their folds pair with the run's, by
        their means otherwise (:mod:`app.services.beside`).
    aggregate : {"window", "recording"}, optional
        Score each window, or each recording's windows pooled into one prediction; default:
        as each run scored.  The run and each run beside it that scored otherwise are
        scored again from their stored test-fold predictions, without fitting
        (:mod:`.rescore`).
    confusion : bool
        Read the results' confusion matrices; ``False``: without them (``None``), for a
        ranking that keeps its board and report only (:func:`ranked_run`): the ranking
        never reads them, and a run of thousands of classifiers reads less.

    Raises
    ------
    NoResultsError
        The run has no result yet.
    ConfigurationError
        A metric of the other kind of problem; an unknown metric or baseline.
    FieldError
        For ``aggregate``: another value, or a run it cannot re-score
        (:func:`~.rescore.rescored_results`).
    """
    from touchbench.app.services.runs.rescore import (
        as_asked,
        check_aggregate,
        check_rescorable,
        results_as_asked,
    )
    from touchbench.benchmark.evaluation.leaderboard import build_leaderboard

    asked = check_aggregate(aggregate)
    run = get_run(store, run_id)
    if asked is not None and asked != run.config.aggregate:
        check_rescorable(run, asked)  # before reading results it could not use
    results = load_results(store, run.id, confusion=confusion)
    if not results:
        raise NoResultsError(run)
    if metric is not None:
        check_metric(run.kind, metric, position=bool(run.config.position), run_id=run.id)
    metric = metric or run_metric(run)
    others = besides(run, [get_run(store, ref) for ref in dict.fromkeys(beside)])
    rescored = asked if asked is not None and asked != run.config.aggregate else None
    results = as_asked(store, run, results, asked)
    theirs = [(b, results_as_asked(store, b.run, asked, confusion=confusion)) for b in others]
    ranked, groups = merged_results(results, theirs)
    drops = {**never_started(run, results), **load_drops(store, run.id)}
    board = build_leaderboard(
        ranked,
        metric=metric,
        baseline=baseline or run.config.baseline,
        groups=groups if others else None,
        drops=drops,
        origins=run_origins(run),
    )
    return RunLeaderboard(run, board, results, tuple(others), drops, rescored=rescored)


def run_origins(run: RunInfo) -> dict[str, Origin]:
    """How the run came by the folds of its computed entries and helpers, as planned."""
    return {
        entry: Origin(origin.kind, tuple(origin.entries))
        for entry, origin in run.config.origins.items()
    }


@dataclass(frozen=True)
class RankedRun:
    """A run's leaderboard as the web page shows it: the ranking and its report, without
    the fold results they were computed from (:func:`ranked_run` keeps these).

    Attributes
    ----------
    run : RunInfo
        The run as it was when ranked.
    board : Leaderboard
    besides : tuple of Beside
    drops : dict of str to Drop
    report : LeaderboardSchema
        :meth:`RunLeaderboard.report` of the ranking.
    rescored : {"window", "recording"} or None
        As :attr:`RunLeaderboard.rescored`.
    aggregates : tuple of str
        What the run's leaderboard may be scored per (``("window", "recording")``), or
        ``()`` when only as the run scored it (:func:`~.rescore.rescorable`).
    """

    run: RunInfo
    board: Leaderboard
    besides: tuple[Beside, ...]
    drops: dict[str, Drop]
    report: LeaderboardSchema
    rescored: Aggregate | None = None
    aggregates: tuple[str, ...] = ()

    def notes(self) -> list[str]:
        """What the leaderboard's notes say (:meth:`RunLeaderboard.notes`)."""
        return list(self.report.notes)


class _Kept:
    """What was computed last of runs, by store, run version and what was asked; what is
    asked for again while it is computed waits for it rather than computing it twice."""

    def __init__(self) -> None:
        self._kept: OrderedDict[Hashable, Any] = OrderedDict()
        self._computing: dict[Hashable, threading.Lock] = {}
        self._lock = threading.Lock()

    def get(self, key: Hashable, compute: Callable[[], T], size: int) -> T:
        with self._lock:
            if key in self._kept:
                self._kept.move_to_end(key)
                return cast(T, self._kept[key])
            computing = self._computing.setdefault(key, threading.Lock())
        with computing:
            with self._lock:
                if key in self._kept:
                    return cast(T, self._kept[key])
            try:
                with _no_collection_pauses():
                    made = compute()
            finally:
                with self._lock:
                    self._computing.pop(key, None)
            with self._lock:
                self._kept[key] = made
                while len(self._kept) > size:
                    self._kept.popitem(last=False)
            return made


_KEPT = _Kept()
_PAUSED = [0]  # computations under way that paused the collector
_PAUSED_LOCK = threading.Lock()


@contextmanager
def _no_collection_pauses() -> Iterator[None]:
    """No full garbage collection while a run is ranked.

    A full collection holds every thread of the service (its predictions too) for as long
    as it takes to go through the heap, and ranking a run of thousands of classifiers
    allocates enough to start several.  So the collector waits while a ranking (or a plot)
    is computed; then the young generations alone are collected (the cycles it left).
    Nothing is frozen (:func:`gc.freeze`): that would take the whole process's objects out
    of the collector's reach, other requests' cycles in flight among them, which would then
    never be freed.
    """
    with _PAUSED_LOCK:
        _PAUSED[0] += 1
        gc.disable()
    try:
        yield
    finally:
        with _PAUSED_LOCK:
            _PAUSED[0] -= 1
            if not _PAUSED[0]:
                # the young generations only (what was made meanwhile, not the heap): the
                # cycles a computation left (a figure's)
                gc.collect(1)
                gc.enable()


def kept(store: Store, runs: Sequence[int | str], asked: Hashable, compute: Callable[[], T]) -> T:
    """What ``compute`` makes of ``runs`` (a run and the runs beside it) for ``asked``,
    computed once per version of their results (:func:`~app.store.runs.results_version`,
    one light query a run) and kept for the next pages: the setting ``ranking_cache``
    says how many a service process keeps.  Nothing is kept when ``compute`` raises.

    Raises
    ------
    NotFoundError
        No such run.
    """
    from touchbench.app.settings import get_settings

    key = (store.url, tuple(results_version(store, run) for run in runs), asked)
    return _KEPT.get(key, compute, get_settings().ranking_cache)


def ranked_run(
    store: Store,
    run_id: int | str,
    *,
    metric: str | None = None,
    baseline: str | None = None,
    beside: Sequence[int | str] = (),
    aggregate: str | None = None,
) -> RankedRun:
    """A run's leaderboard as :func:`run_leaderboard` makes it, computed once per version
    of the run's results and of the runs ``beside`` it (:func:`kept`): a page asking
    again costs a light query per run, not the run's configuration read again.

    Raises
    ------
    NoResultsError, ConfigurationError, FieldError
        As :func:`run_leaderboard`; nothing is kept then.
    """
    from touchbench.app.services.runs.rescore import AGGREGATES, rescorable

    others = list(dict.fromkeys(beside))

    def compute() -> RankedRun:
        ranked = run_leaderboard(
            store,
            run_id,
            metric=metric,
            baseline=baseline,
            beside=others,
            aggregate=aggregate,
            confusion=False,
        )
        return RankedRun(
            ranked.run,
            ranked.board,
            ranked.besides,
            ranked.drops,
            ranked.report(),
            rescored=ranked.rescored,
            aggregates=AGGREGATES if rescorable(store, ranked.run) else (),
        )

    return kept(store, [run_id, *others], ("ranking", metric, baseline, aggregate), compute)


PerTargetSummary = dict[str, dict[str, dict[str, tuple[float, float]]]]


def per_target_summary(results: Sequence[TaskResult]) -> PerTargetSummary:
    """Mean and standard deviation over folds of each target's scores, per classifier.

    Returns
    -------
    dict
        classifier -> target -> metric (accuracy, f1_weighted, ...) -> (mean, std).
    """
    collected: dict[str, dict[str, dict[str, list[float]]]] = {}
    for result in results:
        if result.status != "ok" or not result.per_target:
            continue
        by_target = collected.setdefault(result.key.classifier, {})
        for target, scores in result.per_target.items():
            for name, value in scores.items():
                by_target.setdefault(target, {}).setdefault(name, []).append(value)
    return {
        classifier: {
            target: {
                name: (
                    float(np.mean(values)),
                    float(np.std(values, ddof=1)) if len(values) > 1 else float("nan"),
                )
                for name, values in scores.items()
            }
            for target, scores in targets.items()
        }
        for classifier, targets in collected.items()
    }
