"""Which sensor can go: a run's classifiers cross-validated again without each group of
features on the run's own folds (:mod:`benchmark.run.ablation`), each ablation against the
full set with the corrected resampled t-test ("channel 3 can go: -0.004, not
significant")."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from touchbench.app.errors import ConflictError, FieldError
from touchbench.app.schemas.ablation import (
    AblationEntry,
    AblationGroup,
    AblationRequest,
    AblationResult,
    Grouping,
)
from touchbench.app.schemas.runs import BenchRequest
from touchbench.app.schemas.status import Status
from touchbench.app.services.importance import feature_names, refittable_run
from touchbench.app.services.progress import throttled
from touchbench.app.services.report import run_view
from touchbench.app.services.runs import RunOptions, fold_plan, prepare_problem, task_memory
from touchbench.app.services.tuning import run_specs
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset, load_schema
from touchbench.app.store.runs import get_run
from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER
from touchbench.benchmark.evaluation.significance import corrected_resampled_ttest
from touchbench.benchmark.results import TaskResult

#: Level of the t-test that decides a verdict.
ALPHA = 0.05


def check_grouping(
    store: Store, grouping: Grouping, *, bench: BenchRequest | None, run: int | None
) -> None:
    """Refuse a grouping that the features of a run to come (``bench``) or of a run to
    resume (``run``) do not give, before the run.

    Raises
    ------
    FieldError
        For ``grouping``.
    """
    if bench is not None:
        info, _, _ = load_schema(store, bench.dataset)
        dataset_id, targets = info.id, [bench.target] if bench.target else None
    else:
        assert run is not None
        found = get_run(store, run)
        dataset_id, targets = found.dataset_id, found.config.targets_given
    dataset = load_dataset(store, dataset_id)
    _groups(dataset, targets, grouping, dataset.name or str(dataset_id))


def _groups(
    dataset: Dataset, targets: Sequence[str] | None, grouping: Grouping, name: str
) -> tuple[list[str], dict[str, list[int]]]:
    """The feature names of a run's problem and their groups of ``grouping``."""
    names = feature_names(dataset, targets)
    from touchbench.benchmark.run.importance import feature_groups  # start-up time: scikit-learn

    groups = feature_groups(names).get(grouping)
    if groups is None:
        raise FieldError(
            "grouping",
            f"the features of data set '{name}' fall into no {grouping} groups (channel: "
            "names ending _1, _2... or CHANNEL[T] windows; family: a statistic across several "
            "suffixed channels)",
        )
    return names, groups


def check_ablation(store: Store, request: AblationRequest) -> None:
    """Refuse what would fail at once, before a job exists (:func:`run_ablation`'s errors
    but the work's own)."""
    _plan(store, request)


def run_ablation(
    store: Store,
    request: AblationRequest,
    *,
    jobs: int = 1,
    on_progress: Callable[[AblationResult], None] = lambda partial: None,
) -> AblationResult:
    """Rerun ``request.classifiers`` of ``request.run`` once per group of
    ``request.grouping`` with the group's features removed.

    Parameters
    ----------
    jobs : int
        Local worker processes of the engine.
    on_progress : callable
        Hears the result so far (``complete`` false) after a finished task, at most every
        :data:`app.services.progress.PROGRESS_SECONDS`.

    Raises
    ------
    FieldError
        A classifier the run does not have; a grouping the data set's feature names do not
        give (no ``_1``/``_2`` suffixes, no ``CHANNEL[T]`` windows).
    ConflictError
        The run has not finished.
    ConfigurationError
        An imported run (nothing to refit).
    NotFoundError
        No such run.
    """
    plan = _plan(store, request)
    from touchbench.benchmark.run.ablation import ablate  # start-up time: the engine's imports

    results: dict[tuple[str, str], list[TaskResult]] = {}
    tell = throttled(on_progress, lambda: plan.summary(results))

    def heard(group: str, result: TaskResult) -> None:
        results.setdefault((group, result.key.classifier), []).append(result)
        tell()

    options = plan.options
    max_memory, _ = task_memory(
        options.max_memory_mb,
        jobs=jobs,
        scheduler=None,
        data_bytes=int(plan.problem.X.nbytes),
    )
    ablate(
        plan.problem,
        plan.classifiers,
        plan.folds,
        plan.columns,
        on_result=heard,
        jobs=jobs,
        timeout=options.timeout,
        random_state=options.seed,
        max_memory=max_memory,
        extra_specs=plan.specs,
    )
    return plan.summary(results)


class _Plan:
    """What an ablation needs of its run, read once."""

    def __init__(self, store: Store, request: AblationRequest) -> None:
        view = run_view(store, request.run)
        run = refittable_run(view.run)
        if run.status != Status.DONE:
            raise ConflictError(
                f"run {run.id} is {run.status}: an ablation compares against a finished run"
            )
        ok = [
            row.classifier
            for row in view.board.rows
            if row.n_ok and row.classifier in run.classifiers
        ]
        chosen = list(dict.fromkeys(request.classifiers or ok))
        for name in chosen:
            if name not in run.classifiers:
                raise FieldError(
                    "classifiers",
                    f"'{name}' is not a classifier of run {run.id} "
                    f"(classifiers: {', '.join(run.classifiers)})",
                )
        if not chosen:
            raise FieldError(
                "classifiers", f"run {run.id} has no classifier with a successful fold"
            )
        dataset = load_dataset(store, run.dataset_id)
        targets = run.config.targets_given
        names, groups = _groups(dataset, targets, request.grouping, run.dataset_name)
        self.request = request
        self.run = run
        self.classifiers = chosen
        self.options = RunOptions.from_config(run.config)
        prepared = prepare_problem(dataset, targets, run.config.position or ())
        self.problem = prepared.problem
        self.folds = fold_plan(prepared, self.options).folds
        self.specs = run_specs(run.config, run.classifiers)
        self.columns = groups
        self.groups = [
            AblationGroup(name=name, n_features=len(cols), features=[names[c] for c in cols])
            for name, cols in groups.items()
        ]
        self.metric = view.metric
        self.lower_is_better = view.metric in LOWER_IS_BETTER
        self.full = _by_fold(view.results, self.metric)
        self.ratio = float(np.mean([f.test.size / f.train.size for f in self.folds]))

    def summary(self, results: dict[tuple[str, str], list[TaskResult]]) -> AblationResult:
        """The answer from the results so far."""
        entries = [
            self._entry(name, group.name, results.get((group.name, name), []))
            for name in self.classifiers
            for group in self.groups
        ]
        total = len(self.classifiers) * len(self.groups) * len(self.folds)
        done = sum(len(found) for found in results.values())
        return AblationResult(
            run_id=self.run.id,
            dataset=self.run.dataset_name,
            targets=self.run.targets,
            metric=self.metric,
            lower_is_better=self.lower_is_better,
            grouping=self.request.grouping,
            n_folds=len(self.folds),
            groups=self.groups,
            entries=entries,
            done=done,
            total=total,
            complete=done >= total,
        )

    def _entry(self, classifier: str, group: str, found: Sequence[TaskResult]) -> AblationEntry:
        keys = [(f.repeat, f.fold) for f in self.folds]
        mine = self.full.get(classifier, {})
        ablated = _by_fold(found, self.metric).get(classifier, {})
        full = np.array([mine.get(key, np.nan) for key in keys])
        without = np.array([ablated.get(key, np.nan) for key in keys])
        errors = sum(not r.ok for r in found)
        both = ~np.isnan(full) & ~np.isnan(without)
        if not both.any():
            return AblationEntry(
                classifier=classifier, group=group, n_folds=0, verdict="failed", errors=errors
            )
        a, b = without[both], full[both]
        t, p, sign = corrected_resampled_ttest(a, b, test_train_ratio=self.ratio, alpha=ALPHA)
        gain = -sign if self.lower_is_better else sign  # +1: significantly better without
        verdict = "can go" if sign == 0 else ("better without" if gain > 0 else "needed")
        return AblationEntry(
            classifier=classifier,
            group=group,
            n_folds=int(both.sum()),
            full=float(b.mean()),
            without=float(a.mean()),
            change=float((a - b).mean()),
            t=None if np.isnan(t) else float(t),
            p=None if np.isnan(p) else float(p),
            significant=sign != 0,
            verdict=verdict,
            errors=errors,
        )


def _by_fold(results: Sequence[TaskResult], metric: str) -> dict[str, dict[tuple[int, int], float]]:
    """classifier -> (repeat, fold) -> score of the successful results."""
    out: dict[str, dict[tuple[int, int], float]] = {}
    for r in results:
        if r.ok:
            score = r.metrics.get(metric, np.nan)
            out.setdefault(r.key.classifier, {})[(r.key.repeat, r.key.fold)] = score
    return out


def _plan(store: Store, request: AblationRequest) -> _Plan:
    return _Plan(store, request)
