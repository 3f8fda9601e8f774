"""How many touches: a learning curve, the request and the answer (``touchbench
learning-curve --json``, the API's job)."""

from __future__ import annotations

from pydantic import Field, field_validator

from touchbench.app.schemas.base import Request, Schema
from touchbench.app.schemas.runs import DEFAULT_TIMEOUT, MAX_TIMEOUT, id_as_text, zero_is_no_limit

#: Fractions of each training fold when none are given (benchmark.run.learning's).
DEFAULT_FRACTIONS = [0.1, 0.2, 0.3, 0.5, 0.7, 1.0]


class LearningCurveRequest(Request):
    """Which data set, classifiers and training fractions."""

    dataset: str = Field(min_length=1, description="Data set name or id.")
    target: str | None = Field(
        default=None, min_length=1, description="This one target; default the data set's own."
    )
    classifiers: list[str] = Field(
        min_length=1, max_length=20, description="Classifier ids (one curve each)."
    )
    fractions: list[float] = Field(
        default_factory=lambda: list(DEFAULT_FRACTIONS),
        min_length=1,
        max_length=20,
        description="Shares of each training fold, in (0, 1]; 1 is always added.",
    )
    folds: int = Field(default=5, ge=2, le=100, description="k of k-fold cross-validation.")
    seed: int = Field(default=0, ge=0, le=2**31 - 1, description="Seed of folds and cuts.")
    timeout: float | None = Field(
        default=DEFAULT_TIMEOUT,
        ge=0,
        le=MAX_TIMEOUT,
        description="Seconds one task may take; 0 or null: no limit.",
    )
    metric: str | None = Field(
        default=None, min_length=1, max_length=100, description="Default as a run's."
    )
    tolerance: float = Field(
        default=0.01, gt=0, le=1, description="'Within 1 point': the gap to the full score."
    )

    _id_as_text = field_validator("dataset", mode="before")(id_as_text)
    _zero_is_no_limit = field_validator("timeout", mode="after")(zero_is_no_limit)

    @field_validator("fractions", mode="after")
    @classmethod
    def _fractions(cls, value: list[float]) -> list[float]:
        for fraction in value:
            if not 0 < fraction <= 1:
                raise ValueError(f"each fraction lies in (0, 1], got {fraction:g}")
        return sorted({*value, 1.0})


class CurvePoint(Schema):
    """A classifier's score at one training fraction."""

    fraction: float
    n_train: float = Field(description="Mean training instances per fold.")
    mean: float | None
    std: float | None
    n_folds: int = Field(description="Folds that scored.")


class ClassifierCurve(Schema):
    classifier: str
    points: list[CurvePoint]
    enough: float | None = Field(
        default=None,
        description="The smallest fraction within `tolerance` of the full score (null until "
        "the full fraction is scored).",
    )


class LearningCurveResult(Schema):
    dataset: str
    targets: list[str]
    metric: str
    lower_is_better: bool
    tolerance: float
    n_folds: int
    fold_scheme: str
    fractions: list[float]
    curves: list[ClassifierCurve]
    done: int = Field(description="Tasks (classifier x fraction x fold) finished.")
    total: int
    complete: bool
