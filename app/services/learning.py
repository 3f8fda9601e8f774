"""How many touches: a learning curve of classifiers on a data set, training fractions
inside each fold (:mod:`benchmark.run.learning`), and the fraction at which each classifier
comes within a point of its full score: the answer to "do I need to record more?"."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from touchbench.app.errors import FieldError
from touchbench.app.schemas.learning import (
    ClassifierCurve,
    CurvePoint,
    LearningCurveRequest,
    LearningCurveResult,
)
from touchbench.app.services.progress import throttled
from touchbench.app.services.runs import (
    DEFAULT_METRIC,
    RunOptions,
    check_classifiers,
    check_metric,
    fold_plan,
    prepare_problem,
)
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset, load_schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER
from touchbench.benchmark.results import TaskResult


def check_learning_curve(store: Store, request: LearningCurveRequest) -> None:
    """Refuse what would fail at once (before a job exists): :func:`learning_curve`'s
    errors but the work's own."""
    _Plan(store, request)


def learning_curve(
    store: Store,
    request: LearningCurveRequest,
    *,
    jobs: int = 1,
    on_progress: Callable[[LearningCurveResult], None] = lambda partial: None,
) -> LearningCurveResult:
    """Cross-validate ``request.classifiers`` at each training fraction, smallest first.

    Parameters
    ----------
    jobs : int
        Local worker processes of the engine.
    on_progress : callable
        Hears the curve so far (``complete`` false) after a finished task, at most every
        :data:`app.services.progress.PROGRESS_SECONDS`.

    Raises
    ------
    FieldError
        An unknown data set's target, a classifier or metric the data set refuses.
    NotFoundError
        No such data set.
    """
    plan = _Plan(store, request)
    # start-up time: the engine's imports (scikit-learn) load with the first curve
    from touchbench.benchmark.run.engine import run_tasks
    from touchbench.benchmark.run.folds import Fold

    # one call to the engine for every fraction (its workers start once): a fraction's
    # folds are told apart by their ``repeat``, the fraction's place in the list
    fractions = list(plan.folds)
    folds = [
        Fold(place, fold.fold, fold.train, fold.test)
        for place, fraction in enumerate(fractions)
        for fold in plan.folds[fraction]
    ]
    results: dict[float, list[TaskResult]] = {}
    tell = throttled(on_progress, lambda: plan.summary(results))

    def heard(result: TaskResult) -> None:
        results.setdefault(fractions[result.key.repeat], []).append(result)
        tell()

    run_tasks(
        plan.problem,
        request.classifiers,
        folds,
        jobs=jobs,
        timeout=request.timeout,
        random_state=request.seed,
        on_result=heard,
    )
    return plan.summary(results)


class _Plan:
    """A learning curve's problem, folds per fraction and metric, checked."""

    def __init__(self, store: Store, request: LearningCurveRequest) -> None:
        info, schema, _ = load_schema(store, request.dataset)
        targets = [request.target] if request.target else None
        if request.target is not None:
            try:
                schema.index(request.target)
            except ConfigurationError as error:
                raise FieldError("target", str(error)) from None
        prepared = prepare_problem(load_dataset(store, info.id), targets)
        problem = prepared.problem
        ids = list(dict.fromkeys(request.classifiers))
        check_classifiers(problem, ids, asked=ids)
        metric = request.metric or DEFAULT_METRIC.get(problem.kind, "f1_weighted")
        try:
            check_metric(problem.kind, metric, position=False)
        except ConfigurationError as error:
            raise FieldError("metric", str(error)) from None
        options = RunOptions(request.folds, 1, request.seed, request.timeout, None)
        plan = fold_plan(prepared, options)
        from touchbench.benchmark.run.learning import learning_folds  # start-up time, as above

        self.request = request
        self.dataset = info.name
        self.targets = prepared.target_names
        self.problem = problem
        self.metric = metric
        self.scheme = plan.scheme
        self.n_folds = len(plan.folds)
        self.folds = learning_folds(
            plan.folds,
            request.fractions,
            strata=_strata(problem.Y) if problem.kind != "regression" else None,
            groups=problem.groups,
            seed=request.seed,
        )

    def summary(self, results: dict[float, list[TaskResult]]) -> LearningCurveResult:
        """The curves from the results so far."""
        from touchbench.benchmark.run.learning import enough_fraction  # start-up time, as above

        lower = self.metric in LOWER_IS_BETTER
        curves = []
        for classifier in dict.fromkeys(self.request.classifiers):
            points = [
                self._point(fraction, folds, results.get(fraction, []), classifier)
                for fraction, folds in self.folds.items()
            ]
            full = points[-1]
            enough = None
            if full.n_folds == self.n_folds:
                means = {
                    p.fraction: np.nan if p.mean is None else p.mean for p in points if p.n_folds
                }
                enough = enough_fraction(
                    means, tolerance=self.request.tolerance, lower_is_better=lower
                )
            curves.append(ClassifierCurve(classifier=classifier, points=points, enough=enough))
        done = sum(len(found) for found in results.values())
        total = len(self.folds) * self.n_folds * len(curves)
        return LearningCurveResult(
            dataset=self.dataset,
            targets=self.targets,
            metric=self.metric,
            lower_is_better=lower,
            tolerance=self.request.tolerance,
            n_folds=self.n_folds,
            fold_scheme=self.scheme,
            fractions=list(self.folds),
            curves=curves,
            done=done,
            total=total,
            complete=done >= total,
        )

    def _point(
        self, fraction: float, folds: Sequence, found: Sequence[TaskResult], classifier: str
    ) -> CurvePoint:
        scores = np.array(
            [
                r.metrics.get(self.metric, np.nan)
                for r in found
                if r.key.classifier == classifier and r.ok
            ],
            dtype=np.float64,
        )
        scores = scores[~np.isnan(scores)]
        return CurvePoint(
            fraction=fraction,
            n_train=float(np.mean([f.train.size for f in folds])),
            mean=float(scores.mean()) if scores.size else None,
            std=float(scores.std(ddof=1)) if scores.size > 1 else None,
            n_folds=int(scores.size),
        )


def _strata(Y: np.ndarray) -> np.ndarray:
    """One label per instance to stratify on: the target, or the targets' combination."""
    if Y.shape[1] == 1:
        return Y[:, 0]
    return np.unique(Y, axis=0, return_inverse=True)[1].reshape(-1)
