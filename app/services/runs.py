"""Benchmark runs end to end: a stored data set -> a problem -> folds -> the engine, each
finished task written to the store as it arrives; resume; leaderboards from the store."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.store.database import Store
from app.store.datasets import find_dataset, load_dataset
from app.store.runs import (
    RunInfo,
    create_run,
    finished_keys,
    get_run,
    load_results,
    record_result,
    set_status,
)
from benchmark.dataset import Dataset
from benchmark.errors import ConfigurationError
from benchmark.evaluation.leaderboard import Leaderboard, build_leaderboard
from benchmark.problem import problem_from_dataset, restrict_targets
from benchmark.run.engine import Problem, TaskKey, TaskResult, run_tasks
from benchmark.run.folds import Fold, make_folds


@dataclass
class RunOptions:
    """How to cross-validate: the same options a resumed run gets back from the store."""

    folds: int = 10
    repeats: int = 1
    seed: int = 0
    timeout: float | None = 600.0

    def to_json(self) -> dict[str, Any]:
        return {
            "folds": self.folds,
            "repeats": self.repeats,
            "seed": self.seed,
            "timeout": self.timeout,
        }


@dataclass
class Callbacks:
    """What the caller hears while a run goes on (progress bars, logs)."""

    on_plan: Callable[[int, int], None] = lambda total, done: None
    on_start: Callable[[TaskKey], None] = lambda key: None
    on_result: Callable[[TaskResult], None] = lambda result: None
    on_warning: Callable[[str], None] = lambda message: None


@dataclass
class PreparedProblem:
    problem: Problem
    target_names: list[str]
    warnings: list[str] = field(default_factory=list)


def prepare_problem(dataset: Dataset, targets: Sequence[str] | None = None) -> PreparedProblem:
    """The engine's view of a data set: numeric X, integer target codes, nominal columns.

    Parameters
    ----------
    dataset : Dataset
    targets : sequence of str, optional
        Target attributes to classify; the data set's own targets by default (the others
        are left out, never used as features).
    """
    if dataset.n_instances == 0:
        raise ConfigurationError(f"dataset '{dataset.name}' has no instances")
    restricted = restrict_targets(dataset, targets)
    problem, warnings = problem_from_dataset(restricted)
    for column, target in zip(problem.Y.T, restricted.schema.targets, strict=True):
        present = np.unique(column)
        if present.size < 2:
            only = target.values[int(present[0])] if present.size else "none"
            raise ConfigurationError(
                f"target '{target.name}' has a single class ('{only}'): nothing to classify"
            )
    return PreparedProblem(problem, list(problem.target_names), warnings)


def default_classifiers(n_targets: int, suite_name: str = "default") -> list[str]:
    """The classifiers a suite means for a data set with ``n_targets`` targets."""
    if n_targets > 1:
        from benchmark.multitarget.suites import multitarget_suite

        return multitarget_suite(suite_name)
    from benchmark.catalogue import suite

    return suite(suite_name)


def check_classifiers(problem: Problem, classifiers: Sequence[str]) -> None:
    """Refuse, before a run exists, ids that are unknown or do not fit the problem."""
    from benchmark.catalogue import get_spec
    from benchmark.multitarget import META_METHODS, check_targets

    if not classifiers:
        raise ConfigurationError("no classifiers to run")
    names = ", ".join(problem.target_names)
    for classifier in classifiers:
        is_meta = ":" in classifier or classifier.lower() in META_METHODS
        if problem.kind == "multitarget" and not is_meta:
            get_spec(classifier)
            raise ConfigurationError(
                f"'{classifier}' is a multi-class classifier and the data set has "
                f"{len(problem.target_names)} targets ({names}): use --target NAME for one "
                f"target, or a multi-target configuration such as bcc:{classifier}"
            )
        if is_meta:
            check_targets(classifier, problem.n_classes, problem.target_names)
        else:
            get_spec(classifier)


def start_run(
    store: Store,
    dataset_ref: str,
    classifiers: Sequence[str],
    *,
    targets: Sequence[str] | None = None,
    options: RunOptions | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> tuple[RunInfo, list[TaskResult]]:
    """Create a run in the store and carry it out."""
    options = options or RunOptions()
    callbacks = callbacks or Callbacks()
    info = find_dataset(store, dataset_ref)
    prepared = prepare_problem(load_dataset(store, info.id), targets)
    check_classifiers(prepared.problem, classifiers)
    folds, fold_warnings = _folds(prepared, options)
    effective = max(f.fold for f in folds) + 1
    config = {
        **options.to_json(),
        "folds": effective,
        "folds_requested": options.folds,
        "targets_given": list(targets) if targets else None,
        "n_tasks": len(classifiers) * len(folds),
        "n_instances": int(prepared.problem.X.shape[0]),
    }
    run = create_run(
        store,
        dataset_id=info.id,
        kind=prepared.problem.kind,
        targets=prepared.target_names,
        classifiers=list(classifiers),
        config=config,
    )
    for message in prepared.warnings + fold_warnings:
        callbacks.on_warning(message)
    results = _execute(store, run, prepared, folds, options, jobs, scheduler, callbacks)
    return get_run(store, run.id), results


def resume_run(
    store: Store,
    run_id: int | str,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> tuple[RunInfo, list[TaskResult]]:
    """Finish a run that was interrupted: only the tasks without a result are carried out."""
    callbacks = callbacks or Callbacks()
    run = get_run(store, run_id)
    config = run.config
    options = RunOptions(
        folds=config["folds"],
        repeats=config["repeats"],
        seed=config["seed"],
        timeout=config["timeout"],
    )
    prepared = prepare_problem(load_dataset(store, run.dataset_id), config.get("targets_given"))
    folds, _ = _folds(prepared, options)
    results = _execute(store, run, prepared, folds, options, jobs, scheduler, callbacks)
    return get_run(store, run.id), results


def run_leaderboard(
    store: Store, run_id: int | str, *, metric: str | None = None, baseline: str | None = None
) -> tuple[RunInfo, Leaderboard]:
    run = get_run(store, run_id)
    results = load_results(store, run.id)
    if not results:
        raise ConfigurationError(f"run {run.id} has no results yet (resume it with --resume)")
    default_metric = "f1_weighted" if run.kind == "multiclass" else "hamming_score"
    return run, build_leaderboard(results, metric=metric or default_metric, baseline=baseline)


PerTargetSummary = dict[str, dict[str, dict[str, tuple[float, float]]]]


def per_target_summary(store: Store, run_id: int) -> PerTargetSummary:
    """Mean and standard deviation over folds of each target's scores, per classifier.

    Returns
    -------
    dict
        classifier -> target -> metric (accuracy, f1_weighted, ...) -> (mean, std).
    """
    collected: dict[str, dict[str, dict[str, list[float]]]] = {}
    for result in load_results(store, run_id):
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
    classifiers: Sequence[str],
    *,
    options: RunOptions | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> IndependentResult:
    """A multi-class run per target of a multi-target data set, and the product of the
    best scores (the comparison the UC3M paper makes with its multi-target results)."""
    info = find_dataset(store, dataset_ref)
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


def _folds(prepared: PreparedProblem, options: RunOptions) -> tuple[list[Fold], list[str]]:
    return make_folds(
        prepared.problem.Y,
        n_folds=options.folds,
        n_repeats=options.repeats,
        seed=options.seed,
        groups=prepared.problem.groups,
        target_names=prepared.target_names,
    )


def _execute(
    store: Store,
    run: RunInfo,
    prepared: PreparedProblem,
    folds: list[Fold],
    options: RunOptions,
    jobs: int,
    scheduler: str | None,
    callbacks: Callbacks,
) -> list[TaskResult]:
    done = finished_keys(store, run.id)
    callbacks.on_plan(len(run.classifiers) * len(folds), len(done))

    def persist(result: TaskResult) -> None:
        record_result(store, run.id, result)
        callbacks.on_result(result)

    set_status(store, run.id, "running")
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
        )
    except BaseException:
        set_status(store, run.id, "interrupted")
        raise
    set_status(store, run.id, "done")
    return load_results(store, run.id)
