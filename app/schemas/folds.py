"""A run's scores fold by fold, and its classifiers ranked over its folds: what the plots of
per-fold scores and the critical-difference diagram draw, as ``GET /api/runs/{id}/folds``
answers them (``touchbench plot --kind folds`` and ``--kind cd`` draw the same)."""

from __future__ import annotations

from pydantic import Field

from touchbench.app.schemas.base import Schema
from touchbench.app.schemas.compare import ComparisonOut
from touchbench.app.schemas.runs import Aggregate


class FoldScoresSchema(Schema):
    """Every fold's score of every classifier of a run, on one metric."""

    run_id: int
    dataset: str
    targets: list[str]
    metric: str
    lower_is_better: bool
    folds: list[str] = Field(description="The folds' labels (repeat and fold), in order.")
    scores: dict[str, list[float | None]] = Field(
        description="Classifier (best first) -> its score on each fold (null: failed or not run)."
    )
    ranks: ComparisonOut | None = Field(
        description="The classifiers ranked over the run's folds (Friedman, Nemenyi's "
        "critical difference): what `compare RUN --json` prints; null when they cannot be "
        "ranked (see `ranks_note`)."
    )
    ranks_note: str | None = Field(default=None, description="Why there are no ranks.")
    aggregate: Aggregate = Field(
        default="window",
        description="What one prediction of the scores is: a window, or a recording's "
        "windows pooled (`recording`), as the run scored or as asked.",
    )
