"""Which sensor can go: a run's classifiers cross-validated again without each group of
features, the request and the answer (``bench --ablate-groups --json``, the API's job)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from touchbench.app.schemas.base import Request, Schema

#: How features are grouped (:func:`benchmark.run.importance.feature_groups`).
Grouping = Literal["channel", "family"]


class AblationRequest(Request):
    """Which run's classifiers to rerun, and without which groups."""

    run: int = Field(ge=1, description="The run whose folds and full-set scores are used.")
    grouping: Grouping = Field(
        default="channel",
        description="channel: per microphone/channel (the _1, _2, _3 suffixes, the "
        "CHANNEL[T] columns of windows); family: per statistic across channels.",
    )
    classifiers: list[str] | None = Field(
        default=None,
        min_length=1,
        max_length=50,
        description="These classifiers of the run; default every one with a successful fold.",
    )


class AblationGroup(Schema):
    """A group of features that an ablation removes."""

    name: str
    n_features: int
    features: list[str]


class AblationEntry(Schema):
    """One classifier without one group, against the full set on the same folds."""

    classifier: str
    group: str
    n_folds: int = Field(description="Folds where both the full set and the ablation scored.")
    full: float | None = Field(default=None, description="Mean score with every feature.")
    without: float | None = Field(default=None, description="Mean score without the group.")
    change: float | None = Field(default=None, description="without - full (mean over folds).")
    t: float | None = Field(default=None, description="Corrected resampled t (without vs full).")
    p: float | None = None
    significant: bool = Field(default=False, description="p <= 0.05 (two-sided).")
    verdict: str = Field(
        description="'can go' (no significant change), 'needed' (significantly worse "
        "without), 'better without', or 'failed' (no fold to compare)."
    )
    errors: int = Field(default=0, description="Folds of the ablation that failed.")


class AblationResult(Schema):
    """The ablations of a run, classifier-major, groups in the order of the features."""

    run_id: int
    dataset: str
    targets: list[str]
    metric: str
    lower_is_better: bool
    grouping: Grouping
    test: str = "corrected resampled t-test (Nadeau and Bengio), alpha 0.05"
    n_folds: int
    groups: list[AblationGroup]
    entries: list[AblationEntry]
    done: int = Field(description="Tasks (classifier x group x fold) finished.")
    total: int
    complete: bool
