"""Which sensor and which features: permutation importance of a run's classifier on the
run's own outer test folds (:mod:`benchmark.run.importance`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from touchbench.app.errors import FieldError
from touchbench.app.schemas.importance import FeatureImportance, ImportanceRequest, ImportanceResult
from touchbench.app.services.imported import is_imported
from touchbench.app.services.runs import RunOptions, fold_plan, prepare_problem
from touchbench.app.services.tuning import run_specs
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.app.store.runs import RunInfo, get_run
from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.significance import corrected_resampled_ttest
from touchbench.benchmark.problem import restrict_targets, usable_feature_columns


def refittable_run(run: RunInfo) -> RunInfo:
    """``run``, unless it was imported (a WEKA results file: nothing to refit).

    Raises
    ------
    ConfigurationError
        An imported run.
    """
    if is_imported(run):
        raise ConfigurationError(f"run {run.id} was imported: there is no classifier to refit")
    return run


def feature_names(dataset: Dataset, targets: Sequence[str] | None) -> list[str]:
    """The names of the feature columns a run of ``targets`` on ``dataset`` uses (those of
    its problem's ``X``, in order)."""
    schema = restrict_targets(dataset, targets).schema
    return [schema.features[c].name for c in usable_feature_columns(schema)]


def run_importance(
    store: Store,
    request: ImportanceRequest,
    *,
    on_progress: Callable[[ImportanceResult], None] = lambda partial: None,
) -> ImportanceResult:
    """Permutation importance of ``request.classifier`` on every fold of ``request.run``.

    Each group's drop is tested against no drop with the corrected resampled t-test over
    the folds (``significant`` at alpha 0.05): "microphone 3 can go" is a group whose drop
    is small and not significant.  ``on_progress`` hears the answer over the folds done
    (``complete`` false) after each fold.

    Raises
    ------
    FieldError
        A classifier the run does not have.
    ConfigurationError
        An imported run (nothing to refit), a run that is not multi-class.
    NotFoundError
        No such run.
    """
    run = check_importance(store, request)
    dataset = load_dataset(store, run.dataset_id)
    targets = run.config.targets_given  # as the run prepared its problem
    prepared = prepare_problem(dataset, targets)
    names = feature_names(dataset, targets)
    options = RunOptions.from_config(run.config)
    folds = fold_plan(prepared, options).folds
    # the engine's fitting code (scikit-learn): imported here so the module starts fast
    from touchbench.benchmark.run.importance import (
        Importance,
        feature_groups,
        permutation_importance,
    )

    ratio = float(np.mean([f.test.size / f.train.size for f in folds]))

    def described(name: str, drops: np.ndarray, size: int = 1) -> FeatureImportance:
        t, p, _ = corrected_resampled_ttest(drops, np.zeros_like(drops), test_train_ratio=ratio)
        return FeatureImportance(
            name=name,
            n_features=size,
            mean=float(drops.mean()),
            std=float(drops.std(ddof=1)) if drops.size > 1 else 0.0,
            t=None if np.isnan(t) else float(t),
            p=None if np.isnan(p) else float(p),
            significant=bool(p <= 0.05),
        )

    def ranked(items: list[FeatureImportance]) -> list[FeatureImportance]:
        return sorted(items, key=lambda item: -item.mean)

    sizes = {g: {n: len(c) for n, c in m.items()} for g, m in feature_groups(names).items()}

    def answer(found: Importance) -> ImportanceResult:
        done = int(found.baseline.size)
        return ImportanceResult(
            run_id=run.id,
            classifier=request.classifier,
            target=prepared.target_names[0],
            metric="f1_weighted",
            n_folds=done,
            repeats=request.repeats,
            baseline=float(found.baseline.mean()),
            features=ranked([described(n, d) for n, d in found.features.items()]),
            groups={
                grouping: ranked([described(n, d, sizes[grouping][n]) for n, d in members.items()])
                for grouping, members in found.groups.items()
            },
            done=done,
            total=len(folds),
            complete=done >= len(folds),
        )

    found = permutation_importance(
        prepared.problem,
        request.classifier,
        folds,
        names,
        n_repeats=request.repeats,
        random_state=options.seed,
        extra_specs=run_specs(run.config, run.classifiers),
        on_fold=lambda done, total, so_far: on_progress(answer(so_far)),
    )
    return answer(found)


def check_importance(store: Store, request: ImportanceRequest) -> RunInfo:
    """The run of ``request``, once nothing in it is refused (before a job exists).

    Raises
    ------
    FieldError
        A classifier the run does not have.
    ConfigurationError
        An imported run (nothing to refit), a run that is not multi-class.
    NotFoundError
        No such run.
    """
    run = refittable_run(get_run(store, request.run))
    if run.kind != "multiclass":
        raise ConfigurationError(
            f"run {run.id} is {run.kind}: permutation importance scores one nominal target"
        )
    if request.classifier not in run.classifiers:
        raise FieldError(
            "classifier",
            f"'{request.classifier}' is not a classifier of run {run.id} "
            f"(classifiers: {', '.join(run.classifiers)})",
        )
    return run
