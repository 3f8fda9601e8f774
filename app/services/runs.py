"""Benchmark runs: created (checked, stored ``queued``), executed (by the CLI at once, or by a
service worker later), resumed, cancelled; their leaderboards read from the store.

:func:`create_run` validates everything that can be validated before any work is done (the
data set, its targets, the classifier ids, the folds) and stores the run; :func:`execute_run`
claims it, carries out the tasks that have no result yet while a heartbeat tells other
processes it is alive (and hears a cancel request), and writes the final status.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from app.errors import AppError
from app.schemas.runs import (
    FoldChoiceSchema,
    LeaderboardRowSchema,
    LeaderboardSchema,
    MarkSummary,
    RunStatus,
    TunedComparisonSchema,
)
from app.services.tuning import run_specs
from app.store.database import Store
from app.store.datasets import find_dataset, load_dataset, load_schema
from app.store.ownership import process_owner
from app.store.runs import (
    CANCEL_POLL,
    HEARTBEAT_INTERVAL,
    RunInfo,
    claim_run,
    finish_run,
    finished_keys,
    get_run,
    heartbeat,
    load_results,
    record_result,
    should_stop,
)
from app.store.runs import (
    create_run as store_run,
)
from benchmark.dataset import Dataset
from benchmark.errors import ConfigurationError
from benchmark.problem import Problem, problem_from_dataset, restrict_targets
from benchmark.results import TaskKey, TaskResult

if TYPE_CHECKING:  # scipy.stats (significance) loads when a leaderboard is first built
    from benchmark.catalogue import ClassifierSpec
    from benchmark.evaluation.leaderboard import Leaderboard
    from benchmark.run.folds import FoldPlan

#: Metric a leaderboard is ranked by unless asked otherwise, per kind of run.
DEFAULT_METRIC = {"multiclass": "f1_weighted", "multitarget": "hamming_score", "regression": "mae"}


@dataclass
class RunOptions:
    """How to cross-validate: the same options a resumed run gets back from the store.

    Attributes
    ----------
    folds, repeats, seed : int
        k of k-fold, repetitions of the whole partition, seed of folds and classifiers.
    timeout : float or None
        Seconds one task may take before its worker process is killed.
    max_memory_mb : float or None
        Megabytes one task may allocate beyond its worker's copy of the data.
    """

    folds: int = 10
    repeats: int = 1
    seed: int = 0
    timeout: float | None = 600.0
    max_memory_mb: float | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "folds": self.folds,
            "repeats": self.repeats,
            "seed": self.seed,
            "timeout": self.timeout,
            "max_memory_mb": self.max_memory_mb,
        }

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
        2 or 3 numeric targets that are a position's coordinates (``--position x,y,z``).
    """
    if dataset.n_instances == 0:
        raise ConfigurationError(f"dataset '{dataset.name}' has no instances")
    restricted = restrict_targets(dataset, targets)
    problem, warnings = problem_from_dataset(restricted, position=position)
    if problem.kind == "regression":
        for column, name in zip(problem.Y.T, problem.target_names, strict=True):
            if problem.n_instances and np.ptp(column) == 0:
                raise ConfigurationError(
                    f"numeric target '{name}' has a single value ({column[0]:g}): nothing to "
                    "predict"
                )
        return PreparedProblem(problem, list(problem.target_names), warnings)
    for column, target in zip(problem.Y.T, restricted.schema.targets, strict=True):
        present = np.unique(column)
        if present.size < 2:
            only = target.values[int(present[0])] if present.size else "none"
            raise ConfigurationError(
                f"target '{target.name}' has a single class ('{only}'): nothing to classify"
            )
    return PreparedProblem(problem, list(problem.target_names), warnings)


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
    from benchmark.estimators import reads_sequences

    if regression_size is not None:
        from benchmark.catalogue.regressors import regression_suite

        return regression_suite(suite_name, n_targets=n_targets, n_instances=regression_size)
    if n_targets > 1:
        from benchmark.multitarget.suites import multitarget_suite

        ids = multitarget_suite(suite_name)
    else:
        from benchmark.catalogue import suite

        ids = suite(suite_name)
    return [i for i in ids if sequences or not reads_sequences(i)]


def check_classifiers(
    problem: Problem,
    classifiers: Sequence[str],
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
) -> None:
    """Refuse, before a run exists, ids that are unknown or do not fit the problem."""
    from benchmark.estimators import check_classifier

    if not classifiers:
        raise ConfigurationError("no classifiers to run")
    for classifier in classifiers:
        check_classifier(classifier, problem, extra_specs)


def weka_specs(commands: Sequence[str] | Mapping[str, str | None]) -> dict[str, ClassifierSpec]:
    """The catalogue configurations of WEKA command lines, by id (a run's ``--weka``)."""
    from benchmark.catalogue import parse_weka_command

    texts = commands.values() if isinstance(commands, Mapping) else commands
    specs = [parse_weka_command(text) for text in texts if text]
    return {spec.id: spec for spec in specs}


def create_run(
    store: Store,
    dataset_ref: str,
    classifiers: Sequence[str] | None = None,
    *,
    suite: str | None = None,
    targets: Sequence[str] | None = None,
    options: RunOptions | None = None,
    on_warning: Callable[[str], None] | None = None,
    weka: Sequence[str] = (),
    position: Sequence[str] = (),
    metric: str | None = None,
    tune: bool = False,
    budget: float | None = None,
    stack: int | None = None,
) -> RunInfo:
    """Check a benchmark request and store it as a ``queued`` run.

    Parameters
    ----------
    store : Store
    dataset_ref : str
        Data set name or id.
    classifiers : sequence of str, optional
        Classifier ids; default: the suite's (``default`` unless ``suite`` says).
    suite : str, optional
        ``fast``, ``default`` or ``all``; not together with ``classifiers``.
    targets : sequence of str, optional
        Targets to classify (one: the multi-class catalogue); default the data set's own.
    options : RunOptions, optional
    on_warning : callable, optional
        Hears adjustments made (fewer folds than asked, unstratified folds, ...).
    weka : sequence of str
        WEKA command lines (``"weka.classifiers.trees.J48 -C 0.1"``) to run as well, each
        as the catalogue configuration that computes what WEKA computes.
    position : sequence of str
        2 or 3 numeric targets that are a position's coordinates: the run also scores the
        mean Euclidean error.
    metric : str, optional
        The metric its leaderboard will be ranked by, checked against the kind of run.

    Raises
    ------
    ConfigurationError, AppError
        Anything that would make the run fail at once: unknown data set, target or
        classifier, a target with one class, impossible folds, a position that is not
        numeric targets, a metric of the other kind of problem.
    """
    if classifiers and suite:
        raise ConfigurationError("give classifiers or a suite, not both")
    options = options or RunOptions()
    _check_options(options)
    commands = weka_specs(weka)
    info = find_dataset(store, dataset_ref)
    prepared = prepare_problem(load_dataset(store, info.id), targets, position)
    problem = prepared.problem
    if metric is not None:
        check_metric(problem.kind, metric, position=bool(position))
    if commands and problem.kind == "regression":
        raise ConfigurationError("--weka runs WEKA classifiers; the targets here are numeric")
    ids = list(dict.fromkeys(classifiers or ()))
    if not ids and not commands:
        ids = default_classifiers(
            len(prepared.target_names),
            suite or "default",
            sequences=problem.sequence is not None,
            regression_size=problem.n_instances if problem.kind == "regression" else None,
        )
    ids = list(dict.fromkeys([*ids, *commands]))
    if budget is not None and not tune:
        raise ConfigurationError("--budget bounds the tuning: give --tune as well")
    if (tune or stack is not None) and problem.kind == "regression":
        raise ConfigurationError(
            "--tune and --stack work on classification runs; the targets here are numeric"
        )
    if tune:
        from app.services.tuning import with_tuned_twins

        ids = with_tuned_twins(ids, commands, budget)
    if stack is not None:
        from app.services.tuning import add_stack

        ids = add_stack(ids, stack, multitarget=problem.kind == "multitarget")
    extra = run_specs(_tuning_config(commands, tune, budget, stack), ids)
    check_classifiers(problem, ids, extra)
    plan = _folds(prepared, options)
    folds, fold_notes = plan.folds, plan.notes
    effective = max(f.fold for f in folds) + 1
    config = {
        **options.to_json(),
        "folds": effective,
        "folds_requested": options.folds,
        "targets_given": list(targets) if targets else None,
        "suite": None if classifiers or weka else (suite or "default"),
        **_tuning_config(commands, tune, budget, stack),
        "n_tasks": len(ids) * len(folds),
        "n_instances": int(prepared.problem.X.shape[0]),
        "grouped": prepared.problem.groups is not None,
        "fold_scheme": plan.scheme,
        "position": list(position) or None,
    }
    run = store_run(
        store,
        dataset_id=info.id,
        kind=prepared.problem.kind,
        targets=prepared.target_names,
        classifiers=ids,
        config=config,
    )
    if on_warning is not None:
        for message in prepared.warnings + fold_notes:
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
    if run.status == "done" and run.n_results >= run.n_tasks:
        return run
    owner = process_owner()
    run = claim_run(store, run.id, owner=owner)
    stop = threading.Event()
    beat = _Heartbeat(store, run.id, owner, stop)
    try:
        options = RunOptions.from_config(run.config)
        prepared = prepare_problem(
            load_dataset(store, run.dataset_id),
            run.config.get("targets_given"),
            run.config.get("position") or (),
        )
        folds = _folds(prepared, options).folds
        done = finished_keys(store, run.id)
        callbacks.on_plan(len(run.classifiers) * len(folds), len(done))

        def persist(result: TaskResult) -> None:
            record_result(store, run.id, result)
            callbacks.on_result(result)

        from benchmark.run.engine import RunStopped, run_tasks

        beat.start()
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
                max_memory=_bytes(options.max_memory_mb),
                stop=stop.is_set,
                extra_specs=run_specs(run.config, run.classifiers),
            )
        except RunStopped:
            finish_run(store, run.id, "cancelled")
            raise RunCancelled(get_run(store, run.id)) from None
    except (KeyboardInterrupt, SystemExit):
        finish_run(store, run.id, "interrupted")
        raise
    except RunCancelled:
        raise
    except (ConfigurationError, AppError) as error:
        finish_run(store, run.id, "failed", error=str(error))
        raise
    except BaseException as error:
        finish_run(store, run.id, "interrupted", error=f"{type(error).__name__}: {error}")
        raise
    finally:
        beat.stop()
    status, error_text = _outcome(load_results(store, run.id))
    finish_run(store, run.id, status, error=error_text)
    return get_run(store, run.id)


def start_run(
    store: Store,
    dataset_ref: str,
    classifiers: Sequence[str] | None = None,
    *,
    suite: str | None = None,
    targets: Sequence[str] | None = None,
    options: RunOptions | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
    weka: Sequence[str] = (),
    position: Sequence[str] = (),
) -> tuple[RunInfo, list[TaskResult]]:
    """Create a run and carry it out at once (the CLI's ``bench``)."""
    callbacks = callbacks or Callbacks()
    run = create_run(
        store,
        dataset_ref,
        classifiers,
        suite=suite,
        targets=targets,
        options=options,
        on_warning=callbacks.on_note,
        weka=weka,
        position=position,
    )
    run = execute_run(store, run.id, jobs=jobs, scheduler=scheduler, callbacks=callbacks)
    return run, load_results(store, run.id)


def resume_run(
    store: Store,
    run_id: int | str,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> tuple[RunInfo, list[TaskResult]]:
    """Finish a run that was interrupted: only the tasks without a result are carried out."""
    run = execute_run(store, run_id, jobs=jobs, scheduler=scheduler, callbacks=callbacks)
    return run, load_results(store, run.id)


def run_leaderboard(
    store: Store, run_id: int | str, *, metric: str | None = None, baseline: str | None = None
) -> tuple[RunInfo, Leaderboard]:
    """A run's leaderboard from its stored results.

    Raises
    ------
    ConfigurationError
        The run has no result yet; an unknown metric or baseline.
    """
    run, _, board = run_results(store, run_id, metric=metric, baseline=baseline)
    return run, board


def run_results(
    store: Store, run_id: int | str, *, metric: str | None = None, baseline: str | None = None
) -> tuple[RunInfo, list[TaskResult], Leaderboard]:
    """A run, its stored results (read once) and its leaderboard, for callers that need
    the results too; raises as :func:`run_leaderboard` does."""
    from benchmark.evaluation.leaderboard import build_leaderboard

    run = get_run(store, run_id)
    results = load_results(store, run.id)
    if not results:
        hint = (
            "it is still running"
            if run.status == "running"
            else f"it is {run.status}; `touchbench bench --resume {run.id}` carries it out"
        )
        raise ConfigurationError(f"run {run.id} has no results yet ({hint})")
    if metric is not None:
        check_metric(run.kind, metric, position=bool(run.config.get("position")), run_id=run.id)
    board = build_leaderboard(
        results, metric=metric or DEFAULT_METRIC.get(run.kind, "f1_weighted"), baseline=baseline
    )
    return run, results, board


def check_metric(kind: str, metric: str, *, position: bool, run_id: int | None = None) -> None:
    """Refuse a regression metric for a classification and a classification metric for a
    regression (costs such as ``fit_time`` rank either), and the Euclidean error without a
    position.

    Raises
    ------
    ConfigurationError
        One line naming the metric, the kind of run and the metrics it has.
    """
    from benchmark.evaluation.metrics import COST_METRICS, REGRESSION_METRICS

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
            f"'euclidean_error' needs coordinates: {run} was not given --position X,Y[,Z]"
        )


def leaderboard_schema(
    store: Store, run_id: int | str, *, metric: str | None = None, baseline: str | None = None
) -> tuple[RunInfo, Leaderboard, LeaderboardSchema]:
    """A run's leaderboard, and the report ``leaderboard --json`` prints and the API serves
    (multi-target rows carry ``metrics.per_target``)."""
    run, results, board = run_results(store, run_id, metric=metric, baseline=baseline)
    return run, board, leaderboard_report(run, board, results)


def leaderboard_report(
    run: RunInfo, board: Leaderboard, results: Sequence[TaskResult]
) -> LeaderboardSchema:
    """The report of a run's leaderboard ``board`` built from its ``results``: rows with
    their per-target scores, tuned twins against their defaults, the choices per fold."""
    from benchmark.evaluation.tuned import compare_tuned, fold_choices

    per_target = per_target_summary(results)
    data = board.to_json()
    for row in data["leaderboard"]:
        targets = per_target.get(row["classifier"])
        if targets:
            row["metrics"]["per_target"] = {
                target: {name: {"mean": mean, "std": std} for name, (mean, std) in scores.items()}
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
    dataset_ref: str,
    classifiers: Sequence[str] | None = None,
    *,
    suite: str | None = None,
    options: RunOptions | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> IndependentResult:
    """A multi-class run per target of a multi-target data set, and the product of the
    best scores (the comparison the UC3M paper makes with its multi-target results)."""
    info, schema, _ = load_schema(store, dataset_ref)
    numeric = [t.name for t in schema.targets if t.kind == "numeric"]
    if numeric:
        raise ConfigurationError(
            f"--independent compares targets classified separately, but "
            f"{', '.join(numeric)} of '{info.name}' are numeric: a regression benchmarks its "
            "targets together (drop --independent; br:ID fits one model per target)"
        )
    if len(info.targets) < 2:
        raise ConfigurationError(
            f"--independent compares targets classified separately, but '{info.name}' has one "
            f"target ({', '.join(info.targets)})"
        )
    runs: dict[str, tuple[RunInfo, Leaderboard]] = {}
    for target in info.targets:
        run, _ = start_run(
            store,
            str(info.id),
            classifiers,
            suite=suite,
            targets=[target],
            options=options,
            jobs=jobs,
            scheduler=scheduler,
            callbacks=callbacks,
        )
        runs[target] = run_leaderboard(store, run.id)
    product = {}
    for name in ("accuracy", "f1_weighted"):
        value = 1.0
        for _, board in runs.values():
            value *= board.rows[0].metrics[name][0]
        product[name] = value
    return IndependentResult(runs, product)


class _Heartbeat:
    """A thread that keeps a run's heartbeat and sets ``stop`` when the run should stop.

    It looks for a cancel request every :data:`~app.store.runs.CANCEL_POLL` seconds (one
    read of the run's row) and writes the heartbeat every
    :data:`~app.store.runs.HEARTBEAT_INTERVAL` seconds, so that a cancel is heard within a
    fraction of a second while the store takes a write only every few seconds.
    """

    def __init__(self, store: Store, run_id: int, owner: str, stop: threading.Event) -> None:
        self._store = store
        self._run_id = run_id
        self._owner = owner
        self._stop = stop
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._beat, daemon=True, name="run-heartbeat")

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._done.set()
        if self._thread.is_alive():
            self._thread.join(timeout=HEARTBEAT_INTERVAL * 2)

    def _beat(self) -> None:
        next_beat = time.monotonic() + HEARTBEAT_INTERVAL
        while not self._done.wait(CANCEL_POLL):
            try:
                if time.monotonic() >= next_beat:
                    next_beat = time.monotonic() + HEARTBEAT_INTERVAL
                    told = heartbeat(self._store, self._run_id, self._owner)
                else:
                    told = should_stop(self._store, self._run_id, self._owner)
            except Exception:  # a busy store: try again at the next look
                continue
            if told:
                self._stop.set()


def _outcome(results: Sequence[TaskResult]) -> tuple[RunStatus, str | None]:
    """``done``, or ``failed`` with a one-line reason when no task succeeded."""
    if any(result.ok for result in results):
        return "done", None
    if not results:
        return "failed", "no task was carried out"
    reasons: dict[str, int] = {}
    for result in results:
        reason = (result.error or result.status).split(" (at ", 1)[0]
        reasons[reason] = reasons.get(reason, 0) + 1
    common = max(reasons, key=lambda reason: reasons[reason])
    return "failed", (f"all {len(results)} tasks failed; most often ({reasons[common]}x): {common}")


def _tuning_config(
    commands: Mapping[str, ClassifierSpec], tune: bool, budget: float | None, stack: int | None
) -> dict[str, Any]:
    """The parts of a run's config that say how to build its extra specs again."""
    return {
        "weka": {spec_id: spec.weka_command for spec_id, spec in commands.items()},
        "tune": {"budget_minutes": budget} if tune else None,
        "stack": stack,
    }


def _check_options(options: RunOptions) -> None:
    if options.folds < 2:
        raise ConfigurationError(f"folds must be at least 2, got {options.folds}")
    if options.repeats < 1:
        raise ConfigurationError(f"repeats must be at least 1, got {options.repeats}")
    if options.timeout is not None and not options.timeout > 0:
        raise ConfigurationError(
            f"timeout must be a positive number of seconds, got {options.timeout}"
        )
    if options.max_memory_mb is not None and not options.max_memory_mb > 0:
        raise ConfigurationError(
            f"max_memory must be a positive number of megabytes, got {options.max_memory_mb}"
        )


def _bytes(megabytes: float | None) -> int | None:
    return None if megabytes is None else int(megabytes * 2**20)


def _folds(prepared: PreparedProblem, options: RunOptions) -> FoldPlan:
    from benchmark.run.folds import make_fold_plan

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
        raise ConfigurationError(f"cannot make {options.folds} folds: {error}") from None
