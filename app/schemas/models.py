"""Trained models and their predictions, as ``touchbench models/train/predict --json`` print
them and the API answers them."""

from __future__ import annotations

from datetime import datetime
from typing import Any

from pydantic import ConfigDict, Field

from app.schemas.base import Schema


class ModelSchema(Schema):
    """A trained model: what it classifies, what it was trained on, its artifact."""

    id: int
    name: str
    classifier: str
    targets: list[str]
    dataset: str | None = Field(description="Name of the training data set (null if deleted).")
    dataset_id: int | None
    run_id: int | None = Field(description="The run whose best classifier it is, if any.")
    sha256: str = Field(description="Digest of the artifact, checked before loading.")
    size_bytes: int
    format: str = Field(description="skops: an artifact that cannot run code when loaded.")
    created_at: datetime
    features: list[str] = Field(default_factory=list, description="Attributes it needs, by name.")
    extraction: dict[str, Any] | None = Field(
        default=None,
        description="How its training data was extracted from recordings (null: imported).",
    )


class ModelList(Schema):
    models: list[ModelSchema]


class PredictionRow(Schema):
    """One instance: ``instance`` (1-based), one key per target with the predicted label (a
    number for a regression model), and ``probabilities`` (target -> label -> probability)
    when the classifier gives them."""

    model_config = ConfigDict(extra="allow", ser_json_inf_nan="null")

    instance: int
    probabilities: dict[str, dict[str, float]] | None = None


class PredictionReport(Schema):
    """Predictions of a model for a file or a list of instances."""

    model: str
    targets: list[str]
    predictions: list[PredictionRow]
    accuracy: dict[str, float] = Field(
        default_factory=dict, description="Per target, where the input carries the true labels."
    )
    mae: dict[str, float] = Field(
        default_factory=dict,
        description="A regression model's mean absolute error per target, where the input "
        "carries the true values.",
    )
    warnings: list[str] = Field(
        default_factory=list, description="What was changed or counted, and where."
    )


class PredictRequest(Schema):
    """``POST /api/models/{id}/predict``: instances as attribute -> value, matched by name."""

    instances: list[dict[str, float | int | str | None]] = Field(min_length=1, max_length=10000)


class TrainRequest(Schema):
    """``POST /api/models``: a classifier on a data set, or the best of a run."""

    dataset: str | int | None = None
    classifier: str | None = None
    target: str | None = None
    run: int | None = None
    name: str | None = Field(default=None, max_length=200)
    seed: int = Field(default=0, ge=0, le=2**31 - 1)
