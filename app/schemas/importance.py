"""Permutation importance of a run's classifier: the request and the answer, as
``touchbench importance --json`` prints it."""

from __future__ import annotations

from pydantic import Field

from touchbench.app.schemas.base import Request, Schema


class ImportanceRequest(Request):
    """Which run's classifier to explain, and how many shuffles per feature and fold."""

    run: int = Field(ge=1, description="The run whose folds and classifier are used.")
    classifier: str = Field(min_length=1, max_length=200, description="One of the run's ids.")
    repeats: int = Field(
        default=3, ge=1, le=20, description="Shuffles per feature and fold (their mean counts)."
    )


class FeatureImportance(Schema):
    """The drop in weighted F1 when a feature (or group) is shuffled on the test folds."""

    name: str
    n_features: int = 1
    mean: float = Field(description="Mean drop over the folds (larger: it matters more).")
    std: float
    t: float | None = Field(default=None, description="Corrected resampled t of drop > 0.")
    p: float | None = None
    significant: bool = Field(default=False, description="p <= 0.05 (two-sided).")


class ImportanceResult(Schema):
    """Features and groups, most important first."""

    run_id: int
    classifier: str
    target: str
    metric: str
    n_folds: int
    repeats: int
    baseline: float = Field(description="Mean weighted F1 with nothing shuffled.")
    features: list[FeatureImportance]
    groups: dict[str, list[FeatureImportance]] = Field(
        description="Per grouping (channel, family): each group shuffled together."
    )
    done: int = Field(default=0, description="Folds finished (n_folds of them so far).")
    total: int = Field(default=0, description="Folds in all.")
    complete: bool = True
