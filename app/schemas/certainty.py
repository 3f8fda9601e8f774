"""How sure a run's classifiers are and where they go wrong: per-class scores, confusion
matrices and calibration, as ``touchbench classes --json`` prints them and
``GET /api/runs/{id}/classes`` answers."""

from __future__ import annotations

from pydantic import Field

from touchbench.app.schemas.base import Schema
from touchbench.app.schemas.runs import Aggregate


class ClassScores(Schema):
    """One class of one target: precision, recall and F1 over the summed folds."""

    label: str
    precision: float | None
    recall: float | None
    f1: float | None
    support: int = Field(description="Test instances of the class, over every fold.")


class ReliabilityBin(Schema):
    """One bin of the top-label confidence."""

    lower: float
    upper: float
    count: int
    confidence: float | None = Field(description="Mean confidence of the bin's instances.")
    accuracy: float | None = Field(description="Share of them whose top label is right.")


class Calibration(Schema):
    """Out-of-fold calibration of the top-label confidence (every fold's test instances)."""

    ece: float | None = Field(description="Expected calibration error (0 is perfect).")
    n_instances: int
    n_folds: int
    bins: list[ReliabilityBin]


class TargetClasses(Schema):
    """A classifier on one target: the confusion matrix summed over its successful folds
    (rows true, columns predicted) and the scores of each class."""

    target: str
    labels: list[str]
    confusion: list[list[int]]
    classes: list[ClassScores]
    calibration: Calibration | None = Field(
        default=None,
        description="Multi-target runs: this target's calibration (multi-class runs: the "
        "classifier's).",
    )


class ClassifierCertainty(Schema):
    """One classifier: its per-class scores per target and its calibration."""

    classifier: str
    n_folds: int = Field(description="Successful folds summed.")
    targets: list[TargetClasses]
    calibration: Calibration | None
    calibration_note: str | None = Field(
        default=None, description="Why there is no calibration, when there is none."
    )


class RunCertainty(Schema):
    """A run's classifiers (best first, or those asked for)."""

    run_id: int
    dataset: str
    kind: str
    targets: list[str]
    metric: str = Field(description="The leaderboard metric that orders the classifiers.")
    classifiers: list[ClassifierCertainty]
    aggregate: Aggregate = Field(
        default="window",
        description="What the confusion matrices and the calibration count: windows, or "
        "recordings (each one's windows pooled into one prediction), as the run scored or "
        "as asked.",
    )
