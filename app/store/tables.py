"""ORM models of the store: data sets and their instances, benchmark runs and their
per-fold results, the registry of trained models.

Instances keep WEKA's encoding (see :mod:`benchmark.dataset`) in blocks of consecutive
instances: each row of ``instance_blocks`` holds a block's values as little-endian float64
bytes, row by row in attribute order, so that a block loads into numpy with one
``frombuffer``, nothing is lost to text formatting, and a data set of 235 000 instances is
a few hundred rows to write, not 235 000.  The few instances that carry a group or
metadata (extracted data sets) have a row of ``instances`` for it.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from sqlalchemy import (
    JSON,
    DateTime,
    Float,
    ForeignKey,
    ForeignKeyConstraint,
    Index,
    Integer,
    LargeBinary,
    String,
    Text,
    UniqueConstraint,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship

from touchbench.app.schemas.status import Status


def utcnow() -> datetime:
    return datetime.now(UTC)


class Base(DeclarativeBase):
    pass


class DatasetRow(Base):
    """One data set: its schema and provenance."""

    __tablename__ = "datasets"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), unique=True)
    relation: Mapped[str] = mapped_column(Text)
    schema: Mapped[dict[str, Any]] = mapped_column(JSON)
    target_names: Mapped[list[str]] = mapped_column(JSON)
    n_instances: Mapped[int] = mapped_column(Integer)
    n_attributes: Mapped[int] = mapped_column(Integer)
    sparse: Mapped[bool] = mapped_column(default=False)
    source_name: Mapped[str | None] = mapped_column(Text)
    sha256: Mapped[str] = mapped_column(String(64), index=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
    #: How the data set was extracted from recordings (extractor, options, event detector),
    #: so that models trained on it extract live features the same way; None if imported.
    extraction: Mapped[dict[str, Any] | None] = mapped_column(JSON(none_as_null=True))

    instances: Mapped[list[InstanceRow]] = relationship(
        back_populates="dataset", cascade="all, delete-orphan", passive_deletes=True
    )


class InstanceBlockRow(Base):
    """Consecutive instances of a data set: their values and weights."""

    __tablename__ = "instance_blocks"

    dataset_id: Mapped[int] = mapped_column(
        ForeignKey("datasets.id", ondelete="CASCADE"), primary_key=True
    )
    #: The position (0-based, in file order) of the block's first instance.
    start: Mapped[int] = mapped_column(Integer, primary_key=True)
    n_rows: Mapped[int] = mapped_column(Integer)
    #: ``n_rows x n_attributes`` little-endian float64, row by row.
    data: Mapped[bytes] = mapped_column(LargeBinary)
    #: ``n_rows`` little-endian float64; ``None`` when every weight is 1.
    weights: Mapped[bytes | None] = mapped_column(LargeBinary)


class InstanceRow(Base):
    """The group and metadata of one instance that has either (extracted data sets)."""

    __tablename__ = "instances"

    dataset_id: Mapped[int] = mapped_column(
        ForeignKey("datasets.id", ondelete="CASCADE"), primary_key=True
    )
    position: Mapped[int] = mapped_column(Integer, primary_key=True)
    group_id: Mapped[str | None] = mapped_column(Text)
    meta: Mapped[dict[str, Any] | None] = mapped_column(JSON(none_as_null=True))

    dataset: Mapped[DatasetRow] = relationship(back_populates="instances")


class RunRow(Base):
    """One benchmark run: a data set, its targets, classifiers and protocol."""

    __tablename__ = "runs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    dataset_id: Mapped[int] = mapped_column(ForeignKey("datasets.id", ondelete="CASCADE"))
    kind: Mapped[str] = mapped_column(String(20))
    targets: Mapped[list[str]] = mapped_column(JSON)
    classifiers: Mapped[list[str]] = mapped_column(JSON)
    config: Mapped[dict[str, Any]] = mapped_column(JSON)
    status: Mapped[str] = mapped_column(String(20), default=Status.QUEUED)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
    started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    #: ``host:pid`` of the process executing the run, and when it last said it was alive.
    owner: Mapped[str | None] = mapped_column(String(200))
    heartbeat_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    error: Mapped[str | None] = mapped_column(Text)
    cancel_requested: Mapped[bool] = mapped_column(default=False)
    #: Wall seconds the engine ran for this run, summed over its executions (a resumed run
    #: with a total budget gets the rest).
    seconds_spent: Mapped[float] = mapped_column(Float, default=0.0, server_default="0")


class FoldResultRow(Base):
    """The outcome of one classifier on one fold of one repetition of a run."""

    __tablename__ = "fold_results"
    __table_args__ = (
        UniqueConstraint("run_id", "classifier", "repeat", "fold"),
        # the progress a page polls counts a run's results and failures from this index
        Index("ix_fold_results_run_status", "run_id", "status"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    run_id: Mapped[int] = mapped_column(ForeignKey("runs.id", ondelete="CASCADE"), index=True)
    classifier: Mapped[str] = mapped_column(String(100))
    repeat: Mapped[int] = mapped_column(Integer)
    fold: Mapped[int] = mapped_column(Integer)
    status: Mapped[str] = mapped_column(String(20))
    error: Mapped[str | None] = mapped_column(Text)
    metrics: Mapped[dict[str, Any]] = mapped_column(JSON)
    confusion: Mapped[Any | None] = mapped_column(JSON)
    n_train: Mapped[int] = mapped_column(Integer)
    n_test: Mapped[int] = mapped_column(Integer)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)


class EntryDropRow(Base):
    """A classifier of a run that stopped before its last fold: dropped by the run's race
    (``reason`` ``race``: its p-value against the leader then, and its mean so far) or cut
    by the run's total budget (``budget``)."""

    __tablename__ = "entry_drops"

    run_id: Mapped[int] = mapped_column(ForeignKey("runs.id", ondelete="CASCADE"), primary_key=True)
    classifier: Mapped[str] = mapped_column(String(100), primary_key=True)
    reason: Mapped[str] = mapped_column(String(20))
    #: Folds the classifier ran (the round after which the race dropped it).
    after_fold: Mapped[int] = mapped_column(Integer)
    p_value: Mapped[float | None] = mapped_column(Float)
    leader: Mapped[str | None] = mapped_column(String(100))
    mean: Mapped[float | None] = mapped_column(Float)


class FoldPredictionsRow(Base):
    """What a task's model predicted (:mod:`benchmark.predictions`): its test fold's rows
    (``part`` ``test``), or its training fold's out of fold (``inner``), as one encoded
    blob; never pickled."""

    __tablename__ = "fold_predictions"

    run_id: Mapped[int] = mapped_column(ForeignKey("runs.id", ondelete="CASCADE"), primary_key=True)
    classifier: Mapped[str] = mapped_column(String(100), primary_key=True)
    repeat: Mapped[int] = mapped_column(Integer, primary_key=True)
    fold: Mapped[int] = mapped_column(Integer, primary_key=True)
    part: Mapped[str] = mapped_column(String(10), primary_key=True)
    data: Mapped[bytes] = mapped_column(LargeBinary)


# The model registry, as MLflow's (``mlflow/store/model_registry/dbmodels/models.py``): a
# parent row per registered name; its versions, their aliases and the aliases' history tied
# to it by foreign keys, so that renaming a model is one UPDATE of its parent and deleting a
# version one DELETE (its artifact, twins and aliases go by cascade).  Ids come from
# AUTOINCREMENT on SQLite (a sequence on PostgreSQL), so that an id is never given twice.
#: The constraint that keeps two versions of one model from taking the same number.
MODEL_VERSION_KEY = "uq_models_registered_model_version"


class RegisteredModelRow(Base):
    """A model's name, the parent of its versions: ``last_version`` is the number its newest
    version ever took, and only grows (a version deleted is never given again, so that
    ``NAME@VERSION`` names one model for good).  The row stays when its versions are
    deleted, keeping the count."""

    __tablename__ = "registered_models"
    __table_args__ = ({"sqlite_autoincrement": True},)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), unique=True)
    last_version: Mapped[int] = mapped_column(Integer, default=0)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)


class ModelRow(Base):
    """A trained model, one version of a registered model: the estimator's artifact
    (``format`` says how it is serialised; only formats that cannot run code are loaded),
    its schema, and how its features were extracted.

    ``id`` is the version's own number, unique across names and never given twice.
    """

    __tablename__ = "models"
    __table_args__ = (
        UniqueConstraint("registered_model_id", "version", name=MODEL_VERSION_KEY),
        {"sqlite_autoincrement": True},
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    registered_model_id: Mapped[int] = mapped_column(
        ForeignKey("registered_models.id", ondelete="CASCADE")
    )
    version: Mapped[int] = mapped_column(Integer)
    dataset_id: Mapped[int | None] = mapped_column(ForeignKey("datasets.id", ondelete="SET NULL"))
    run_id: Mapped[int | None] = mapped_column(ForeignKey("runs.id", ondelete="SET NULL"))
    classifier: Mapped[str] = mapped_column(String(100))
    params: Mapped[dict[str, Any]] = mapped_column(JSON)
    schema: Mapped[dict[str, Any]] = mapped_column(JSON)
    targets: Mapped[list[str]] = mapped_column(JSON)
    sha256: Mapped[str] = mapped_column(String(64))
    size_bytes: Mapped[int] = mapped_column(Integer)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
    format: Mapped[str] = mapped_column(String(20), default="skops")
    extraction: Mapped[dict[str, Any] | None] = mapped_column(JSON(none_as_null=True))

    registered: Mapped[RegisteredModelRow] = relationship(lazy="joined", innerjoin=True)

    @property
    def name(self) -> str:
        return self.registered.name


class ModelAliasRow(Base):
    """A name for one version of a model (``champion``), moved by ``alias``, ``promote``
    and ``rollback``: ``NAME@ALIAS`` is that version.  It goes with the version it points
    at (the foreign key on ``(registered_model_id, version)``)."""

    __tablename__ = "model_aliases"
    __table_args__ = (
        ForeignKeyConstraint(
            ["registered_model_id", "version"],
            ["models.registered_model_id", "models.version"],
            ondelete="CASCADE",
            name="fk_model_aliases_version",
        ),
    )

    registered_model_id: Mapped[int] = mapped_column(
        ForeignKey("registered_models.id", ondelete="CASCADE"), primary_key=True
    )
    alias: Mapped[str] = mapped_column(String(100), primary_key=True)
    version: Mapped[int] = mapped_column(Integer)
    set_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)


class ModelAliasEventRow(Base):
    """Each version an alias was set to, in order: ``rollback`` steps back through them
    (a step undone is marked, so that a second rollback goes one further back; a version
    deleted since is skipped, and never comes back under its number)."""

    __tablename__ = "model_alias_history"
    __table_args__ = (
        Index("ix_model_alias_history_alias", "registered_model_id", "alias", "id"),
        {"sqlite_autoincrement": True},
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    registered_model_id: Mapped[int] = mapped_column(
        ForeignKey("registered_models.id", ondelete="CASCADE")
    )
    alias: Mapped[str] = mapped_column(String(100))
    version: Mapped[int] = mapped_column(Integer)
    set_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
    undone: Mapped[bool] = mapped_column(default=False)


class ModelArtifactRow(Base):
    """A model's artifact bytes, apart from :class:`ModelRow`: SQLite reaches a column
    stored after a large value only through that value's pages, and the small columns of a
    model are read on every served prediction and every listing."""

    __tablename__ = "model_artifacts"

    model_id: Mapped[int] = mapped_column(
        ForeignKey("models.id", ondelete="CASCADE"), primary_key=True
    )
    artifact: Mapped[bytes] = mapped_column(LargeBinary)


class ModelExportRow(Base):
    """A model's twin in another format (``onnx``), written after it was checked against
    the model; its bytes are verified against ``sha256`` before each load."""

    __tablename__ = "model_exports"

    model_id: Mapped[int] = mapped_column(
        ForeignKey("models.id", ondelete="CASCADE"), primary_key=True
    )
    format: Mapped[str] = mapped_column(String(20), primary_key=True)
    sha256: Mapped[str] = mapped_column(String(64))
    size_bytes: Mapped[int] = mapped_column(Integer)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
    data: Mapped[bytes] = mapped_column(LargeBinary)


class JobRow(Base):
    """Long work other than runs (extraction, training), queued for worker processes."""

    __tablename__ = "jobs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    kind: Mapped[str] = mapped_column(String(20))
    status: Mapped[str] = mapped_column(String(20), index=True, default=Status.QUEUED)
    params: Mapped[dict[str, Any]] = mapped_column(JSON)
    result: Mapped[dict[str, Any] | None] = mapped_column(JSON(none_as_null=True))
    error: Mapped[str | None] = mapped_column(Text)
    owner: Mapped[str | None] = mapped_column(String(200))
    heartbeat_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    cancel_requested: Mapped[bool] = mapped_column(default=False)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
    started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
