"""A run's per-fold scores and its classifiers ranked over its folds, in one answer
(:class:`~app.schemas.folds.FoldScoresSchema`): the numbers behind the plots of a run's
folds and its critical-difference diagram, for clients that draw them themselves."""

from __future__ import annotations

from touchbench.app.schemas.base import finite
from touchbench.app.schemas.folds import FoldScoresSchema
from touchbench.app.services.compare import compare_folds, comparison_schema
from touchbench.app.services.report import run_view
from touchbench.app.store.database import Store
from touchbench.benchmark.errors import BenchmarkError
from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER


def run_fold_scores(
    store: Store,
    run_ref: int | str,
    *,
    metric: str | None = None,
    alpha: float = 0.05,
    aggregate: str | None = None,
) -> FoldScoresSchema:
    """Per-fold scores of a run's classifiers on ``metric`` (default: its leaderboard's),
    and their ranks over the folds at ``alpha`` where they can be ranked; scored per
    ``aggregate`` as the run's leaderboard (:func:`~app.services.runs.run_leaderboard`).

    Raises
    ------
    NotFoundError
        No such run.
    ConfigurationError
        An unknown metric, or a run without results.
    FieldError
        For ``aggregate``: another value, or a run it cannot re-score.
    """
    view = run_view(store, run_ref, metric=metric, aggregate=aggregate)
    table = view.fold_scores()
    ranks, note = None, None
    try:
        # the view's results: scored as asked once, not read and re-scored again
        ranks = comparison_schema(
            compare_folds(view.run, view.results, metric=view.metric, alpha=alpha)
        )
    except BenchmarkError as error:  # the scores stand without ranks; the answer says why
        note = str(error)
    return FoldScoresSchema(
        run_id=view.run.id,
        dataset=view.run.dataset_name,
        targets=view.run.targets,
        metric=view.metric,
        lower_is_better=view.metric in LOWER_IS_BETTER,
        folds=list(table.blocks),
        scores={name: [finite(float(v)) for v in table.column(name)] for name in table.classifiers},
        ranks=ranks,
        ranks_note=note,
        aggregate=view.aggregate,
    )
