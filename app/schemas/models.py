"""Trained models and their predictions, as ``touchbench models/train/predict --json`` print
them and the API answers them."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path
from typing import Any, Literal

from pydantic import ConfigDict, Field, model_validator

from touchbench.app.errors import FieldError
from touchbench.app.schemas.base import Request, Schema
from touchbench.app.schemas.names import AliasName, ModelName
from touchbench.app.schemas.references import MAX_ROW_ID

#: The largest id or seed (the store's integer columns are 32-bit on PostgreSQL).
MAX_ID = MAX_ROW_ID


class TwinSchema(Schema):
    """A model's twin in ONNX, checked against the model when it was made."""

    format: str = "onnx"
    sha256: str = Field(description="Digest of the twin's bytes, checked before each load.")
    size_bytes: int
    problem: str | None = Field(
        default=None,
        description="Why the twin could not be loaded, once a prediction tried: predictions "
        "with engine auto then run the model itself, and engine onnx is refused.",
    )


class ModelSchema(Schema):
    """A trained model: what it classifies, what it was trained on, its artifact."""

    id: int
    name: str
    version: int = Field(description="1, 2, ...: training again under a name adds a version.")
    aliases: list[str] = Field(
        default_factory=list, description="Aliases pointing at this version (champion)."
    )
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
    onnx: TwinSchema | None = Field(
        default=None, description="Its ONNX twin (null: none yet; an export job makes one)."
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

    model: str = Field(description="NAME@VERSION: the version that answered.")
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
    missing: dict[str, int] = Field(
        default_factory=dict,
        description="JSON instances: per attribute the model needs, the instances that gave "
        'it no value (null, or left out under "missing": "allow"); attributes that '
        "every instance gave are not listed.",
    )


#: What a prediction does with an instance that leaves out attributes the model needs:
#: ``refuse`` it, as a file without the model's columns is refused, or ``allow`` it, the
#: attributes left out being missing values.
MissingPolicy = Literal["refuse", "allow"]


#: What runs a model's predictions: ``native`` its own estimator (scikit-learn, XGBoost...),
#: ``onnx`` its ONNX twin in ONNX Runtime (an export makes it), ``auto`` the twin where the
#: model has a usable one (measured faster: ``perf/serve.py``, ``perf/live_latency.py``),
#: else the estimator.
Engine = Literal["auto", "onnx", "native"]


class EngineChoice(Request):
    """The engine of a command that predicts (``predict``, ``live``, ``ros``)."""

    engine: Engine = Field(
        default="auto",
        description="auto: the model's ONNX twin where it has one, else the model itself; "
        "onnx: the twin (refused without one); native: the model itself.",
    )


#: Formats ``export-model`` writes.
ExportFormat = Literal["onnx"]


class ExportRequest(Request):
    """``POST /api/models/{id}/onnx`` (a job) and the CLI's ``export-model``: a model's twin
    in a format other programs run, checked against the model on its training instances."""

    model: str | int = Field(
        description="Model id, NAME (its newest version), NAME@VERSION or NAME@ALIAS."
    )
    format: ExportFormat = Field(default="onnx", description="onnx: one ONNX graph.")


class ExportSchema(Schema):
    """A model's stored twin."""

    model: str
    model_id: int
    format: str
    sha256: str = Field(description="Digest of the twin's bytes, checked before each load.")
    size_bytes: int
    checked_instances: int = Field(
        description="Training instances on which the twin's labels and probabilities were "
        "checked against the model's."
    )


class PredictFileRequest(EngineChoice):
    """The CLI's ``predict MODEL FILE`` and ``POST /api/models/{id}/predict/file``: every
    instance of an ARFF or CSV file (attributes matched by name; one the model needs and the
    file lacks is refused), or of a raw recording, whose instances are extracted with the
    model's own recipe."""

    model: str | int = Field(
        description="Model id, NAME (its newest version), NAME@VERSION or NAME@ALIAS."
    )
    file: Path = Field(description="The file to read.")
    source_name: str | None = Field(
        default=None,
        max_length=255,
        description="The name the user knows the file by (an upload's file name): what "
        "messages call the file.",
    )


class PredictRequest(EngineChoice):
    """``POST /api/models/{id}/predict``: instances as attribute -> value, matched by name.

    Every instance gives every attribute the model needs (``null`` for a value it does not
    know) unless ``missing`` is ``allow``: a misspelt attribute would otherwise become a
    missing value, and the prediction confident nonsense.
    """

    instances: list[dict[str, float | int | str | None]] = Field(min_length=1, max_length=10000)
    missing: MissingPolicy = Field(
        default="refuse",
        description="refuse: an instance that leaves out an attribute the model needs is "
        "refused; allow: it is a missing value (the answer counts them per attribute).",
    )


class TrainRequest(Request):
    """``POST /api/models`` and the CLI's ``train``: a classifier on a data set, or the best
    classifier of a finished run (``run``) on that run's data set and targets."""

    dataset: str | int | None = Field(default=None, description="Data set name or id.")
    classifier: str | None = Field(
        default=None, min_length=1, max_length=200, description="Classifier id."
    )
    target: str | None = Field(
        default=None, max_length=2000, description="Train for this one target only."
    )
    run: int | None = Field(
        default=None, ge=1, le=MAX_ID, description="Train the best classifier of this run."
    )
    name: ModelName | None = Field(
        default=None, description="Model name (default: DATASET-CLASSIFIER)."
    )
    seed: int = Field(default=0, ge=0, le=MAX_ID, description="Seed of the classifier.")
    onnx: bool = Field(
        default=False,
        description="Also make the model's ONNX twin, checked against the model on its "
        "training instances (predictions with engine auto then run it).",
    )

    @model_validator(mode="after")
    def _one_source(self) -> TrainRequest:
        """A data set and a classifier, or a run (whose data set, targets and seed are its
        own): what is missing or would be ignored is refused, naming the field."""
        if self.run is not None:
            given = {"dataset": self.dataset, "classifier": self.classifier, "target": self.target}
            for other, value in {**given, "seed": self.seed or None}.items():
                if value is not None:
                    raise FieldError(
                        other,
                        "is not taken with `run`: a run's best classifier is trained on the "
                        "run's own data set, targets and seed",
                    )
            return self
        if self.dataset is None:
            raise FieldError("dataset", "is required (or `run`, for a run's best classifier)")
        if self.classifier is None:
            raise FieldError("classifier", "is required with `dataset`")
        return self


class AliasRequest(Request):
    """``alias``, ``promote`` and ``rollback`` (``POST /api/models/{model}/aliases``,
    ``.../promote``, ``.../rollback``): point an alias of a model at one of its versions, or
    step it back to the version it pointed at before."""

    model: str = Field(
        min_length=1, max_length=400, description="MODEL@VERSION (any reference to a version)."
    )
    alias: AliasName = Field(default="champion", description="The alias (champion).")


class AliasBody(Request):
    """``POST /api/models/{model}/aliases`` (and ``.../rollback``): the alias to move."""

    alias: AliasName = Field(default="champion", description="The alias (champion).")


class AliasDeleted(Schema):
    """An alias removed (``DELETE /api/models/{model}/aliases/{alias}``): the version it
    pointed at."""

    alias: str
    model: str = Field(description="NAME@VERSION it pointed at.")
    version: int


class AliasMoved(Schema):
    """An alias set or stepped back: the version it points at now, and before."""

    alias: str
    model: str = Field(description="NAME@VERSION it points at now.")
    version: int
    previous: int | None = Field(description="The version it pointed at before (null: none).")
