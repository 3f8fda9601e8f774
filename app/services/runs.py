"""Benchmark runs: created (checked, stored ``queued``), executed (by the CLI at once, or by a
service worker later), resumed, cancelled; their leaderboards read from the store.

:func:`create_run` validates everything that can be validated before any work is done (the
data set, its targets, the classifier ids, the folds) and stores the run; :func:`execute_run`
claims it, carries out the tasks that have no result yet while a heartbeat tells other
processes it is alive (and hears a cancel request), and writes the final status.
"""

from __future__ import annotations

# Imports inside functions: start-up time. The listing commands, the API's routes and the
# job process import this module; the catalogue, the engine and the statistics load
# scikit-learn and scipy, which only the functions that need them import.
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from touchbench.app.errors import AppError, FieldError
from touchbench.app.schemas.runs import (
    PER_RECORDING_NOTE,
    RACE_MIN_FOLDS,
    BenchRequest,
    BudgetSchema,
    FoldChoiceSchema,
    LeaderboardRowSchema,
    LeaderboardSchema,
    MarkSummary,
    RaceSchema,
    TunedComparisonSchema,
)
from touchbench.app.schemas.status import STOPPED_EARLY, UNFINISHED, Status
from touchbench.app.services.beside import Beside, besides, merged_results, row_runs
from touchbench.app.services.tuning import run_specs
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset, load_schema
from touchbench.app.store.drops import forget_budget_cuts, load_drops, record_drop
from touchbench.app.store.ownership import process_owner
from touchbench.app.store.runs import (
    RunInfo,
    add_spent,
    claim_run,
    finish_run,
    finished_keys,
    get_run,
    load_results,
    record_result,
    run_heartbeat,
    update_config,
)
from touchbench.app.store.runs import (
    create_run as store_run,
)
from touchbench.benchmark.dataset import Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.problem import (
    Problem,
    position_columns,
    problem_from_dataset,
    restrict_targets,
)
from touchbench.benchmark.results import Drop, TaskKey, TaskResult

if TYPE_CHECKING:  # scipy.stats (significance) loads when a leaderboard is first built
    from touchbench.benchmark.catalogue import ClassifierSpec
    from touchbench.benchmark.evaluation.leaderboard import Leaderboard
    from touchbench.benchmark.run.folds import FoldPlan
    from touchbench.benchmark.run.racing import RaceRule

#: The race's test, as the leaderboards name it.
RACE_TEST = "corrected resampled t-test against the leader"
#: Metric a leaderboard is ranked by unless asked otherwise, per kind of run.
DEFAULT_METRIC = {"multiclass": "f1_weighted", "multitarget": "hamming_score", "regression": "mae"}


@dataclass(frozen=True)
class RunOptions:
    """How a run cross-validates, as its stored config says: what a resumed run gets back.

    The defaults and bounds are the request's (:class:`app.schemas.runs.BenchRequest`).

    Attributes
    ----------
    folds, repeats, seed : int
        k of k-fold, repetitions of the whole partition, seed of folds and classifiers.
    timeout : float or None
        Seconds one task may take before its worker process is killed; ``None``: no limit.
    max_memory_mb : float or None
        Megabytes one task may allocate beyond its worker's copy of the data; 0: no limit;
        None: derived from the machine when the run starts (:func:`task_memory`).
    """

    folds: int
    repeats: int
    seed: int
    timeout: float | None
    max_memory_mb: float | None

    def to_json(self) -> dict[str, Any]:
        return {
            "folds": self.folds,
            "repeats": self.repeats,
            "seed": self.seed,
            "timeout": self.timeout,
            "max_memory_mb": self.max_memory_mb,
        }

    @classmethod
    def from_request(cls, request: BenchRequest) -> RunOptions:
        return cls(
            folds=request.folds,
            repeats=request.repeats,
            seed=request.seed,
            timeout=request.timeout,
            max_memory_mb=request.max_memory_mb,
        )

    @classmethod
    def from_config(cls, config: dict[str, Any]) -> RunOptions:
        return cls(
            folds=int(config.get("folds_requested", config["folds"])),
            repeats=int(config["repeats"]),
            seed=int(config["seed"]),
            timeout=config.get("timeout"),
            max_memory_mb=config.get("max_memory_mb"),
        )


@dataclass
class Callbacks:
    """What the caller hears while a run goes on (progress bars, logs)."""

    on_plan: Callable[[int, int], None] = lambda total, done: None
    on_start: Callable[[TaskKey], None] = lambda key: None
    on_result: Callable[[TaskResult], None] = lambda result: None
    on_warning: Callable[[str], None] = lambda message: None
    on_note: Callable[[str], None] = lambda message: None


@dataclass
class PreparedProblem:
    problem: Problem
    target_names: list[str]
    warnings: list[str] = field(default_factory=list)


class OneValueError(ConfigurationError):
    """A numeric target with a single value: a regression has nothing to predict."""

    def __init__(self, target: str, value: float) -> None:
        super().__init__(
            f"numeric target '{target}' has a single value ({value:g}): nothing to predict"
        )
        self.target = target
        self.value = value


class RunCancelled(Exception):  # noqa: N818 (an outcome, not an error)
    """The run was cancelled while it executed; its finished tasks are kept."""

    def __init__(self, run: RunInfo) -> None:
        super().__init__(f"run {run.id} was cancelled")
        self.run = run


def prepare_problem(
    dataset: Dataset, targets: Sequence[str] | None = None, position: Sequence[str] = ()
) -> PreparedProblem:
    """The engine's view of a data set: numeric X, integer target codes (or target values
    of a regression), nominal columns.

    Parameters
    ----------
    dataset : Dataset
    targets : sequence of str, optional
        Target attributes to predict; the data set's own targets by default (the others
        are left out, never used as features).
    position : sequence of str
        2 or 3 numeric targets that are a position's coordinates.
    """
    if dataset.n_instances == 0:
        raise ConfigurationError(f"dataset '{dataset.name}' has no instances")
    restricted = restrict_targets(dataset, targets)
    problem, warnings = problem_from_dataset(restricted, position=position)
    if problem.kind == "regression":
        for column, name in zip(problem.Y.T, problem.target_names, strict=True):
            if problem.n_instances and np.ptp(column) == 0:
                raise OneValueError(name, float(column[0]))
        return PreparedProblem(problem, list(problem.target_names), warnings)
    for column, target in zip(problem.Y.T, restricted.schema.targets, strict=True):
        present = np.unique(column)
        if present.size < 2:
            only = target.values[int(present[0])] if present.size else "none"
            raise ConfigurationError(
                f"target '{target.name}' has a single class ('{only}'): nothing to classify"
            )
    return PreparedProblem(problem, list(problem.target_names), warnings)


def _check_position(schema: Schema, position: Sequence[str]) -> None:
    """Refuse a position the run's targets (``schema``'s) cannot have, naming the field.

    Raises
    ------
    FieldError
        Not 2 or 3 distinct numeric targets, or targets that are not all numeric (a
        position's run is a regression).
    """
    try:
        position_columns(schema, position)
    except ConfigurationError as error:
        raise FieldError("position", str(error)) from None
    nominal = [t.name for t in schema.targets if t.kind != "numeric"]
    if nominal:
        raise FieldError(
            "position",
            f"coordinates make the run a regression, and the targets include nominal ones "
            f"({', '.join(nominal)}): a position's run takes numeric targets only",
        )


def default_classifiers(
    n_targets: int,
    suite_name: str = "default",
    *,
    sequences: bool = False,
    regression_size: int | None = None,
) -> list[str]:
    """The classifiers a suite means for a data set with ``n_targets`` targets.

    Sequence classifiers are among them only for a sequence data set (``sequences``).
    A regression (``regression_size``: its number of instances) gets the suite's
    regressors (:func:`benchmark.catalogue.regressors.regression_suite`).
    """
    from touchbench.benchmark.estimators import reads_sequences

    if regression_size is not None:
        from touchbench.benchmark.catalogue.regressors import regression_suite

        return regression_suite(
            suite_name, n_targets=n_targets, n_instances=regression_size, sequences=sequences
        )
    if n_targets > 1:
        from touchbench.benchmark.multitarget.suites import multitarget_suite

        ids = multitarget_suite(suite_name)
    else:
        from touchbench.benchmark.catalogue import suite

        ids = suite(suite_name)
    return [i for i in ids if sequences or not reads_sequences(i)]


def check_classifiers(
    problem: Problem,
    classifiers: Sequence[str],
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
    *,
    asked: Sequence[str] = (),
) -> None:
    """Refuse, before a run exists, ids that are unknown or do not fit the problem.

    Raises
    ------
    FieldError
        For ``classifiers``: one of the ids the user asked for (``asked``) is refused.
    ConfigurationError
        No classifiers; an id the run added (a suite's, a twin) does not fit.
    """
    from touchbench.benchmark.estimators import check_classifier

    if not classifiers:
        raise ConfigurationError("no classifiers to run")
    for classifier in classifiers:
        try:
            check_classifier(classifier, problem, extra_specs)
        except ConfigurationError as error:
            if classifier in asked:
                raise FieldError("classifiers", str(error)) from None
            raise


def weka_specs(commands: Sequence[str] | Mapping[str, str | None]) -> dict[str, ClassifierSpec]:
    """The catalogue configurations of WEKA command lines, by id (a run's ``weka``).

    Raises
    ------
    FieldError
        For ``weka``: a command line the catalogue cannot compute.
    """
    from touchbench.benchmark.catalogue import parse_weka_command

    texts = commands.values() if isinstance(commands, Mapping) else commands
    try:
        specs = [parse_weka_command(text) for text in texts if text]
    except ConfigurationError as error:
        raise FieldError("weka", str(error)) from None
    return {spec.id: spec for spec in specs}


@dataclass(frozen=True)
class _Plan:
    """A checked run, ready to be stored: what :func:`create_run` stores."""

    dataset_id: int
    kind: str
    targets: list[str]
    classifiers: list[str]
    config: dict[str, Any]
    notes: list[str]


def create_run(
    store: Store, request: BenchRequest, *, on_warning: Callable[[str], None] | None = None
) -> RunInfo:
    """Check a benchmark request against its data set and store it as a ``queued`` run.

    The command line carries the run out at once (:func:`execute_run`), the service's
    workers later; a benchmark of each target on its own is :func:`independent_runs`.

    Parameters
    ----------
    store : Store
    request : BenchRequest
        The run's data set, classifiers and protocol, checked on their own already.
    on_warning : callable, optional
        Hears adjustments made (fewer folds than asked, unstratified folds, ...).

    Raises
    ------
    FieldError
        A field the data set refuses: a target it lacks, a metric of the other kind of
        problem, ``tune``,
        ``stack`` or ``weka`` on numeric targets, a stack on several targets, a baseline
        that is not one of the run's classifiers, impossible folds, ``independent``.
    NotFoundError
        An unknown data set.
    ConfigurationError
        Anything else that would make the run fail at once: a target with one class.
    """
    if request.independent:
        raise FieldError(
            "independent",
            "asks for one run per target, carried out at once rather than queued: "
            "queue a run per `target` instead",
        )
    return _store_plan(store, _plan_run(store, request), on_warning)


def _plan_run(store: Store, request: BenchRequest) -> _Plan:
    """Everything :func:`create_run` checks, and the run it would store."""
    options = RunOptions.from_request(request)
    commands = weka_specs(request.weka or ())
    targets = [request.target] if request.target else None
    position = list(request.position or ())
    info, schema, _ = load_schema(store, request.dataset)
    if request.target is not None:
        try:
            schema.index(request.target)
        except ConfigurationError as error:
            raise FieldError("target", str(error)) from None
    if position:
        run_schema = schema if targets is None else schema.with_targets([schema.index(targets[0])])
        _check_position(run_schema, position)
    try:
        prepared = prepare_problem(load_dataset(store, info.id), targets, position)
    except OneValueError as error:
        if error.target not in position:
            raise
        raise FieldError(
            "position", f"'{error.target}' has a single value ({error.value:g}): nothing to predict"
        ) from None
    problem = prepared.problem
    if request.metric is not None:
        try:
            check_metric(problem.kind, request.metric, position=bool(position))
        except ConfigurationError as error:
            raise FieldError("metric", str(error)) from None
    numeric = problem.kind == "regression"
    for name in ("weka", "tune", "stack"):
        if numeric and getattr(request, name):
            raise FieldError(name, "works on classification runs; the targets here are numeric")
    ids = list(dict.fromkeys(request.classifiers or ()))
    if not ids and not commands:
        ids = default_classifiers(
            len(prepared.target_names),
            request.suite or "default",
            sequences=problem.sequence is not None,
            regression_size=problem.n_instances if numeric else None,
        )
    ids = list(dict.fromkeys([*ids, *commands]))
    tuning = _tuning_config(commands, request.tune, request.budget, request.stack)
    if request.tune:
        from touchbench.app.services.tuning import with_tuned_twins

        ids = with_tuned_twins(ids, commands, request.budget)
    if request.stack is not None:
        from touchbench.app.services.tuning import add_stack

        ids = add_stack(ids, request.stack, multitarget=problem.kind == "multitarget")
    check_classifiers(problem, ids, run_specs(tuning, ids), asked=request.classifiers or ())
    if request.baseline is not None and request.baseline not in ids:
        raise FieldError(
            "baseline",
            f"'{request.baseline}' is not a classifier of this run (classifiers: {', '.join(ids)})",
        )
    if request.aggregate == "recording":
        from touchbench.benchmark.evaluation.recordings import check_one_label

        try:
            check_one_label(problem.Y, problem.groups, prepared.target_names, info.name)
        except ConfigurationError as error:
            raise FieldError("aggregate", str(error)) from None
    plan = fold_plan(prepared, options)
    if request.race and len(plan.folds) < RACE_MIN_FOLDS:
        raise FieldError(
            "race",
            f"needs at least {RACE_MIN_FOLDS} folds in all, and the data allow "
            f"{len(plan.folds)} ({'; '.join(plan.notes)})",
        )
    config = {
        **options.to_json(),
        "folds": max(f.fold for f in plan.folds) + 1,
        "folds_requested": options.folds,
        "targets_given": targets,
        "suite": None if request.classifiers or request.weka else (request.suite or "default"),
        **tuning,
        "n_tasks": len(ids) * len(plan.folds),
        "n_instances": int(problem.X.shape[0]),
        "grouped": problem.groups is not None,
        "fold_scheme": plan.scheme,
        "position": position or None,
        "metric": request.metric,
        "baseline": request.baseline,
        "race": {"alpha": request.race_alpha} if request.race else None,
        "budget_total": request.budget_total,
        "aggregate": request.aggregate,
    }
    return _Plan(
        info.id, problem.kind, prepared.target_names, ids, config, prepared.warnings + plan.notes
    )


def _store_plan(
    store: Store, plan: _Plan, on_warning: Callable[[str], None] | None = None
) -> RunInfo:
    run = store_run(
        store,
        dataset_id=plan.dataset_id,
        kind=plan.kind,
        targets=plan.targets,
        classifiers=plan.classifiers,
        config=plan.config,
    )
    if on_warning is not None:
        for message in plan.notes:
            on_warning(message)
    return run


def execute_run(
    store: Store,
    run_id: int | str,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> RunInfo:
    """Carry out every task of a run that has no result yet, then record how it ended.

    The run is claimed first (another live process executing it is refused); a heartbeat
    thread tells other processes this one is alive and stops the engine when a cancel is
    requested.

    Returns
    -------
    RunInfo
        Status ``done``, or ``failed`` when every task failed.

    Raises
    ------
    RunCancelled
        A cancel request stopped the run (status ``cancelled``).
    KeyboardInterrupt
        Passed on after the run is marked ``interrupted``.
    AppError
        Another process executes the run.
    """
    callbacks = callbacks or Callbacks()
    run = get_run(store, run_id)
    if run.status == Status.DONE and run.n_results >= run.n_tasks:
        return run
    owner = process_owner()
    run = claim_run(store, run.id, owner=owner)
    stop = threading.Event()
    beat = run_heartbeat(store, run.id, owner, stop.set)
    try:
        options = RunOptions.from_config(run.config)
        prepared = prepare_problem(
            load_dataset(store, run.dataset_id),
            run.config.get("targets_given"),
            run.config.get("position") or (),
        )
        folds = fold_plan(prepared, options).folds
        race = race_rule(run)
        # a race replays its decisions from the stored scores; a plain run needs their keys
        previous = load_results(store, run.id) if race is not None else []
        done = {r.key for r in previous} if race is not None else finished_keys(store, run.id)
        # tasks in all and done, for the caller's progress: a drop takes its entry's later
        # folds off the total
        counts = [len(run.classifiers) * len(folds), len(done)]
        callbacks.on_plan(*counts)
        forget_budget_cuts(store, run.id)
        budget = _budget_left(run)
        max_memory, memory_from = task_memory(
            options.max_memory_mb,
            jobs=jobs,
            scheduler=scheduler,
            data_bytes=int(prepared.problem.X.nbytes),
        )
        update_config(
            store,
            run.id,
            {
                "task_memory_mb": None if max_memory is None else round(max_memory / 2**20),
                "task_memory_from": memory_from,
            },
        )

        def persist(result: TaskResult) -> None:
            record_result(store, run.id, result)
            counts[1] += 1
            callbacks.on_result(result)

        def dropped(drop: Drop) -> None:
            record_drop(store, run.id, drop)
            counts[0] -= len(folds) - drop.after_fold
            callbacks.on_plan(*counts)
            callbacks.on_note(f"{drop.classifier}: {drop.describe()}")

        from touchbench.benchmark.run.engine import RunStopped, run_tasks

        beat.start()
        began = time.monotonic()
        try:
            run_tasks(
                prepared.problem,
                run.classifiers,
                folds,
                jobs=jobs,
                scheduler=scheduler,
                timeout=options.timeout,
                random_state=options.seed,
                skip=done,
                on_start=callbacks.on_start,
                on_result=persist,
                max_memory=max_memory,
                stop=stop.is_set,
                extra_specs=run_specs(run.config, run.classifiers),
                race=race,
                budget=budget,
                previous=previous,
                on_drop=dropped,
                by_recording=run.config.get("aggregate") == "recording",
            )
        except RunStopped:
            finish_run(store, run.id, Status.CANCELLED)
            raise RunCancelled(get_run(store, run.id)) from None
        finally:
            add_spent(store, run.id, time.monotonic() - began)
    except (KeyboardInterrupt, SystemExit):
        finish_run(store, run.id, Status.INTERRUPTED)
        raise
    except RunCancelled:
        raise
    except (ConfigurationError, AppError) as error:
        finish_run(store, run.id, Status.FAILED, error=str(error))
        raise
    except BaseException as error:
        finish_run(store, run.id, Status.INTERRUPTED, error=f"{type(error).__name__}: {error}")
        raise
    finally:
        beat.stop()
    status, error_text = _outcome(load_results(store, run.id))
    finish_run(store, run.id, status, error=error_text)
    return get_run(store, run.id)


#: Seconds a resumed run whose total budget is spent gets: positive for the engine, too
#: short for any task to fit, so that every entry left is cut and the leaderboard says so.
NO_BUDGET_LEFT = 1e-6


def _budget_left(run: RunInfo) -> float | None:
    """Seconds of the run's total budget its earlier executions left; ``None`` without one."""
    minutes = run.config.get("budget_total")
    if minutes is None:
        return None
    return max(float(minutes) * 60.0 - run.seconds_spent, NO_BUDGET_LEFT)


def race_rule(run: RunInfo) -> RaceRule | None:
    """How a run races, from its config: its ranking metric, level and baseline; ``None``
    for a run that is not raced."""
    race = run.config.get("race")
    if not race:
        return None
    from touchbench.benchmark.run.racing import RaceRule

    baseline = run.config.get("baseline")
    return RaceRule(
        metric=run.config.get("metric") or DEFAULT_METRIC.get(run.kind, "f1_weighted"),
        alpha=float(race["alpha"]),
        protected=frozenset({baseline} if baseline else ()),
    )


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
    """

    run: RunInfo
    board: Leaderboard
    results: list[TaskResult]
    besides: tuple[Beside, ...]
    drops: dict[str, Drop]

    @property
    def per_recording(self) -> bool:
        """Whether the run scored each recording's windows as one prediction."""
        return self.run.config.get("aggregate") == "recording"

    def notes(self) -> list[str]:
        """What the leaderboard of a run scored per recording, raced, budgeted or stopped
        says under its table."""
        notes = [PER_RECORDING_NOTE] if self.per_recording else []
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
        race = self.run.config.get("race")
        if not race:
            return None
        alpha = float(race["alpha"])
        dropped = sum(1 for d in self.drops.values() if d.reason == "race")
        return RaceSchema(
            alpha=alpha,
            test=RACE_TEST,
            dropped=dropped,
            note=f"raced at alpha {alpha:g} ({RACE_TEST}); {dropped} dropped",
        )

    def budget(self) -> BudgetSchema | None:
        """What the run's total budget cut; ``None`` for a run without one."""
        minutes = self.run.config.get("budget_total")
        if minutes is None:
            return None
        cut = [c for c, d in self.drops.items() if d.reason == "budget"]
        raced_out = sum(
            self.run.n_tasks // max(len(self.run.classifiers), 1) - d.after_fold
            for d in self.drops.values()
            if d.reason == "race"
        )
        missing = max(self.run.n_tasks - len(self.results) - raced_out, 0)
        cut_text = f"; cut: {', '.join(cut)}" if cut else ""
        return BudgetSchema(
            minutes=float(minutes),
            cut=cut,
            tasks_not_run=missing,
            minutes_spent=self.run.seconds_spent / 60.0,
            note=f"total budget {float(minutes):g} min: {missing} task(s) not run{cut_text}",
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
            folds=run.fold_scheme,
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
            aggregate="recording" if self.per_recording else "window",
            notes=self.notes(),
        )


def run_leaderboard(
    store: Store,
    run_id: int | str,
    *,
    metric: str | None = None,
    baseline: str | None = None,
    beside: Sequence[int | str] = (),
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

    Raises
    ------
    NoResultsError
        The run has no result yet.
    ConfigurationError
        A metric of the other kind of problem; an unknown metric or baseline.
    """
    from touchbench.benchmark.evaluation.leaderboard import build_leaderboard

    run = get_run(store, run_id)
    results = load_results(store, run.id)
    if not results:
        raise NoResultsError(run)
    if metric is not None:
        check_metric(run.kind, metric, position=bool(run.config.get("position")), run_id=run.id)
    metric = metric or run.config.get("metric") or DEFAULT_METRIC.get(run.kind, "f1_weighted")
    others = besides(run, [get_run(store, ref) for ref in dict.fromkeys(beside)])
    ranked, groups = merged_results(results, [(b, load_results(store, b.run.id)) for b in others])
    drops = {**never_started(run, results), **load_drops(store, run.id)}
    board = build_leaderboard(
        ranked,
        metric=metric,
        baseline=baseline or run.config.get("baseline"),
        groups=groups if others else None,
        drops=drops,
    )
    return RunLeaderboard(run, board, results, tuple(others), drops)


def never_started(run: RunInfo, results: Sequence[TaskResult]) -> dict[str, Drop]:
    """The entries of a run stopped early (cancelled, interrupted) that have no result, by
    id: a leaderboard lists them (marked ``never started``) rather than leave them out."""
    if run.status not in STOPPED_EARLY:
        return {}
    started = {result.key.classifier for result in results}
    return {c: Drop(c, "not started", 0) for c in run.classifiers if c not in started}


def check_metric(kind: str, metric: str, *, position: bool, run_id: int | None = None) -> None:
    """Refuse a regression metric for a classification and a classification metric for a
    regression (costs such as ``fit_time`` rank either), and the Euclidean error without a
    position.

    Raises
    ------
    ConfigurationError
        One line naming the metric, the kind of run and the metrics it has.
    """
    from touchbench.benchmark.evaluation.metrics import COST_METRICS, REGRESSION_METRICS

    run = f"run {run_id}" if run_id is not None else "this run"
    if metric in COST_METRICS:
        return
    if kind == "regression" and metric not in REGRESSION_METRICS:
        raise ConfigurationError(
            f"'{metric}' is not a regression metric and {run} is a regression (numeric "
            f"targets): rank by {', '.join(REGRESSION_METRICS[:3])} or a cost"
        )
    if kind != "regression" and metric in REGRESSION_METRICS:
        raise ConfigurationError(
            f"'{metric}' is a regression metric and {run} classifies nominal targets "
            f"({kind}): rank by {DEFAULT_METRIC.get(kind, 'f1_weighted')} or another "
            "classification metric"
        )
    if metric == "euclidean_error" and not position:
        raise ConfigurationError(
            f"'euclidean_error' needs coordinates: {run} has no position (2 or 3 numeric "
            "targets that are coordinates)"
        )


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


@dataclass
class IndependentResult:
    """The paper's other approach: each target's best multi-class classifier, separately.

    Attributes
    ----------
    runs : dict of str to (RunInfo, Leaderboard)
        One multi-class run per target.
    product : dict of str to float
        Product over targets of the best classifiers' mean accuracy and weighted F1: what
        independent classifiers score on all targets at once if their errors are independent.
    """

    runs: dict[str, tuple[RunInfo, Leaderboard]]
    product: dict[str, float]

    def to_json(self) -> dict[str, Any]:
        best = {}
        for target, (run, board) in self.runs.items():
            row = board.rows[0]
            best[target] = {
                "run_id": run.id,
                "classifier": row.classifier,
                "metrics": {
                    name: {"mean": row.metrics[name][0], "std": row.metrics[name][1]}
                    for name in ("accuracy", "f1_weighted")
                    if name in row.metrics
                },
            }
        return {"independent": True, "best": best, "product": self.product}


def independent_runs(
    store: Store,
    request: BenchRequest,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> IndependentResult:
    """A multi-class run per target of a multi-target data set, carried out at once, and
    the product of the best scores (the comparison the UC3M paper makes with its
    multi-target results).

    Every target's run is checked before the first one is stored.

    Raises
    ------
    FieldError
        For ``independent``: the data set has one target, or numeric ones.
    """
    callbacks = callbacks or Callbacks()
    info, schema, _ = load_schema(store, request.dataset)
    numeric = [t.name for t in schema.targets if t.kind == "numeric"]
    if numeric:
        raise FieldError(
            "independent",
            f"compares targets classified separately, but {', '.join(numeric)} of "
            f"'{info.name}' are numeric: a regression benchmarks its targets together "
            "(br:ID fits one model per target)",
        )
    if len(info.targets) < 2:
        raise FieldError(
            "independent",
            f"compares targets classified separately, but '{info.name}' has one target "
            f"({', '.join(info.targets)})",
        )
    fields = request.model_dump(exclude={"independent", "target"}, exclude_defaults=True)
    plans = {
        target: _plan_run(store, BenchRequest(**fields, target=target)) for target in info.targets
    }
    runs: dict[str, tuple[RunInfo, Leaderboard]] = {}
    for target, plan in plans.items():
        run = _store_plan(store, plan, callbacks.on_note)
        execute_run(store, run.id, jobs=jobs, scheduler=scheduler, callbacks=callbacks)
        ranked = run_leaderboard(store, run.id)
        runs[target] = (ranked.run, ranked.board)
    product = {}
    for name in ("accuracy", "f1_weighted"):
        value = 1.0
        for _, board in runs.values():
            value *= board.rows[0].metrics[name][0]
        product[name] = value
    return IndependentResult(runs, product)


def _outcome(results: Sequence[TaskResult]) -> tuple[Status, str | None]:
    """``done``, or ``failed`` with a one-line reason when no task succeeded."""
    if any(result.ok for result in results):
        return Status.DONE, None
    if not results:
        return Status.FAILED, "no task was carried out"
    reasons: dict[str, int] = {}
    for result in results:
        reason = (result.error or result.status).split(" (at ", 1)[0]
        reasons[reason] = reasons.get(reason, 0) + 1
    common = max(reasons, key=lambda reason: reasons[reason])
    return Status.FAILED, (
        f"all {len(results)} tasks failed; most often ({reasons[common]}x): {common}"
    )


def _tuning_config(
    commands: Mapping[str, ClassifierSpec], tune: bool, budget: float | None, stack: int | None
) -> dict[str, Any]:
    """The parts of a run's config that say how to build its extra specs again."""
    return {
        "weka": {spec_id: spec.weka_command for spec_id, spec in commands.items()},
        "tune": {"budget_minutes": budget} if tune else None,
        "stack": stack,
    }


def task_memory(
    max_memory_mb: float | None, *, jobs: int, scheduler: str | None, data_bytes: int
) -> tuple[int | None, str]:
    """The bytes one task of a run may allocate, and where that cap comes from.

    Parameters
    ----------
    max_memory_mb : float or None
        The run's own cap in megabytes; 0: no limit; None: derived from what this machine
        has available, shared by ``jobs`` workers
        (:func:`benchmark.run.memory.default_task_memory`).  A run on a Dask cluster
        derives none: its workers' own memory limits apply.
    jobs : int
        Local worker processes (-1: one per core).
    scheduler : str or None
        The Dask scheduler the run uses, if any.
    data_bytes : int
        Bytes of the run's features.

    Returns
    -------
    tuple of (int or None, str)
        The cap (None: no limit) and a few words on its origin, stored with the run.
    """
    if max_memory_mb == 0:
        return None, "no limit asked"
    if max_memory_mb is not None:
        return int(max_memory_mb * 2**20), "asked"
    if scheduler is not None:
        return None, "the Dask workers' own memory limits"
    from touchbench.benchmark.run.engine import available_cores
    from touchbench.benchmark.run.memory import default_task_memory

    cap = default_task_memory(available_cores() if jobs == -1 else jobs, data_bytes=data_bytes)
    if cap is None:
        return None, "no limit: this machine's memory cannot be read"
    # whole megabytes: the figure the run's config and its failures' messages show
    return cap.bytes // 2**20 * 2**20, f"default: {cap.describe()}"


def fold_plan(prepared: PreparedProblem, options: RunOptions) -> FoldPlan:
    """The folds a run with these options makes on this problem (the same on resume)."""
    from touchbench.benchmark.run.folds import make_fold_plan

    try:
        return make_fold_plan(
            prepared.problem.Y,
            n_folds=options.folds,
            n_repeats=options.repeats,
            seed=options.seed,
            groups=prepared.problem.groups,
            target_names=prepared.target_names,
            regression=prepared.problem.kind == "regression",
        )
    except ValueError as error:  # scikit-learn's splitters on data too small to split
        raise FieldError("folds", f"cannot make {options.folds} folds: {error}") from None
