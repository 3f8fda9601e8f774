"""Runs and their leaderboards, as ``touchbench runs/bench/leaderboard --json`` print them
and the API answers them."""

from __future__ import annotations

from datetime import datetime
from typing import Any, Literal

from pydantic import Field

from app.schemas.base import Schema

#: Where a run is in its life (the rules: :mod:`app.store.run_states`): ``queued`` (created,
#: waiting for a worker), ``running``, ``cancelling`` (its process was asked to stop),
#: ``done`` (every task has a result), ``failed`` (every task failed, or the run could not
#: be carried out), ``cancelled`` (on request), ``interrupted`` (its process stopped: Ctrl-C,
#: kill -9, a crash; ``--resume`` finishes it).
RunStatus = Literal["queued", "running", "cancelling", "done", "failed", "cancelled", "interrupted"]
RUN_STATUSES: tuple[RunStatus, ...] = (
    "queued",
    "running",
    "cancelling",
    "done",
    "failed",
    "cancelled",
    "interrupted",
)
#: Statuses after which nothing more happens unless the run is resumed.
FINAL_STATUSES: frozenset[str] = frozenset({"done", "failed", "cancelled", "interrupted"})


class RunSchema(Schema):
    """A benchmark run: its data set, classifiers, protocol and progress."""

    id: int
    dataset: str = Field(description="Name of the data set.")
    dataset_id: int
    kind: str = Field(description="multiclass, multitarget or regression (numeric targets).")
    targets: list[str]
    classifiers: list[str]
    config: dict[str, Any] = Field(description="Folds, repeats, seed, timeout, ...")
    status: RunStatus
    created_at: datetime
    started_at: datetime | None = None
    finished_at: datetime | None = None
    tasks_done: int = Field(description="Tasks with a result (failed ones included).")
    tasks: int = Field(description="Tasks in all: classifiers x folds x repeats.")
    tasks_failed: int = 0
    error: str | None = Field(default=None, description="Why the run failed, if it did.")
    owner: str | None = Field(default=None, description="host:pid of the executing process.")


class RunList(Schema):
    runs: list[RunSchema]


class RunCreated(Schema):
    """What ``POST /api/runs`` answers at once: the run waits for a worker."""

    id: int
    status: RunStatus


class MetricValue(Schema):
    """Mean and sample standard deviation over the successful folds (``null``: none)."""

    mean: float | None
    std: float | None


PerTargetScores = dict[str, dict[str, MetricValue]]


class LeaderboardRowSchema(Schema):
    """One classifier's line; ``metrics.per_target`` holds a multi-target row's scores per
    target (target -> metric -> mean/std)."""

    rank: int
    classifier: str
    mark: Literal["v", "*", ""] = Field(description="v: better than the baseline; *: worse.")
    metrics: dict[str, MetricValue | PerTargetScores]
    n_ok: int
    n_failed: int
    errors: list[str]


class MarkSummary(Schema):
    better: int
    same: int
    worse: int


class FoldChoiceSchema(Schema):
    """What a tuned twin or a stack chose on one outer training fold."""

    classifier: str
    repeat: int
    fold: int
    params: dict[str, Any]


class TunedComparisonSchema(Schema):
    """A tuned twin beside its default: means over the folds both completed, and the
    corrected resampled t-test of tuned against default."""

    tuned: str
    default: str
    metric: str
    tuned_mean: float | None
    default_mean: float | None
    n_folds: int
    t: float | None
    p: float | None
    mark: Literal["v", "*", ""] = Field(description="v: tuned significantly better; *: worse.")
    choices: list[FoldChoiceSchema]


class LeaderboardSchema(Schema):
    """A run's ranked classifiers with WEKA's significance marks."""

    run_id: int
    dataset: str
    kind: str
    targets: list[str]
    status: RunStatus
    folds: str = Field(
        default="",
        description="How the folds were made: stratified k-fold, k-fold (shuffled), or their "
        "group k-fold variants (recordings/sessions never straddle training and test).",
    )
    metric: str
    lower_is_better: bool = Field(
        default=False, description="Whether the ranking metric is better when smaller (mae)."
    )
    baseline: str | None = Field(description="The classifier the marks compare against.")
    summary: MarkSummary
    leaderboard: list[LeaderboardRowSchema]
    tuning: list[TunedComparisonSchema] = Field(
        default_factory=list, description="Tuned twins against their defaults (bench --tune)."
    )
    choices: list[FoldChoiceSchema] = Field(
        default_factory=list,
        description="What each tuned twin and stack chose per fold (bench --tune/--stack).",
    )
