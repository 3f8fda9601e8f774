"""Trained models in the store, as a registry: a registered model per name
(``registered_models``), its versions (``models``: the artifact's sha256 and format, the
schema the model expects, the classifier and its parameters, the data set and run it came
from, and how that data set was extracted from recordings).

Artifacts live in a table of their own (``model_artifacts``), so listings and the version
check of every served prediction never read one; :func:`load_artifact` reads one, and
only a format that cannot run code when loaded (``skops``) is handed out.

Models stored under one name are its versions 1, 2, ... (training again under a name adds
one).  A number is taken from the registered model's counter, which only grows, and ids
are never given twice either: ``NAME@VERSION`` and an id name one model for good, even
after it is deleted.  A reference to a model is read by
:func:`app.schemas.references.parse_model_ref` (an id, ``NAME``: the newest version,
``NAME@VERSION``, ``NAME@latest``, ``NAME@ALIAS``) and resolved by
:mod:`app.store.model_refs`; aliases are :mod:`app.store.aliases`' business.
"""

from __future__ import annotations

import hashlib
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import delete, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from touchbench.app.errors import AppError, ConflictError, FieldError
from touchbench.app.schemas.listing import Page
from touchbench.app.schemas.models import ModelSchema, TwinSchema
from touchbench.app.schemas.names import check_name
from touchbench.app.schemas.references import SEPARATOR, version_label
from touchbench.app.store.database import Store
from touchbench.app.store.model_refs import TWIN_FORMAT, version_row
from touchbench.app.store.naming import shorten
from touchbench.app.store.paging import count_rows, paged
from touchbench.app.store.tables import (
    DatasetRow,
    ModelAliasRow,
    ModelArtifactRow,
    ModelExportRow,
    ModelRow,
    RegisteredModelRow,
)

#: The only artifact format that is loaded (see :mod:`benchmark.artifacts`).
SAFE_FORMAT = "skops"
#: Attempts at storing the first version of a name that other processes store at once.
VERSION_ATTEMPTS = 20


@dataclass(frozen=True)
class TwinInfo:
    """A model's twin in another format (ONNX), as the store describes it (its bytes are
    not read); ``problem`` says why it could not be loaded, once a prediction tried."""

    format: str
    sha256: str
    size_bytes: int
    problem: str | None = None


@dataclass(frozen=True)
class ModelInfo:
    id: int
    name: str
    classifier: str
    params: dict[str, Any]
    targets: list[str]
    dataset_id: int | None
    dataset_name: str | None
    run_id: int | None
    sha256: str
    size_bytes: int
    created_at: datetime
    schema: dict[str, Any]
    format: str = SAFE_FORMAT
    extraction: dict[str, Any] | None = None
    version: int = 1
    aliases: tuple[str, ...] = ()
    twin: TwinInfo | None = None

    @property
    def label(self) -> str:
        """``NAME@VERSION``: the one version this is, as answers name it."""
        return version_label(self.name, self.version)

    @property
    def feature_names(self) -> list[str]:
        targets = set(self.schema.get("target_indices", ()))
        return [
            attribute["name"]
            for i, attribute in enumerate(self.schema.get("attributes", ()))
            if i not in targets
        ]

    def to_schema(self) -> ModelSchema:
        return ModelSchema(
            id=self.id,
            name=self.name,
            version=self.version,
            aliases=list(self.aliases),
            classifier=self.classifier,
            targets=self.targets,
            dataset=self.dataset_name,
            dataset_id=self.dataset_id,
            run_id=self.run_id,
            sha256=self.sha256,
            size_bytes=self.size_bytes,
            format=self.format,
            created_at=self.created_at,
            features=self.feature_names,
            extraction=self.extraction,
            onnx=None
            if self.twin is None
            else TwinSchema(
                sha256=self.twin.sha256,
                size_bytes=self.twin.size_bytes,
                problem=self.twin.problem,
            ),
        )

    def to_json(self) -> dict[str, Any]:
        return self.to_schema().to_json()


def save_model(
    store: Store,
    *,
    classifier: str,
    params: dict[str, Any],
    schema: dict[str, Any],
    targets: Sequence[str],
    artifact: bytes,
    dataset_id: int | None = None,
    run_id: int | None = None,
    name: str | None = None,
) -> ModelInfo:
    """Store a model's artifact as the next version of ``name`` (default
    ``DATASET-CLASSIFIER``: training the same classifier on the same data set again is a
    new version of that model, not another model).

    The data set's extraction recipe (if it was extracted from recordings) is copied to
    the model, so that live prediction extracts features as training did.  The version's
    number is taken from the registered model's counter in the same statement that raises
    it, so processes storing versions of one name at once each get their own; two that
    register a new name at once are told apart by its unique key, and the second tries
    again.
    """
    if name is not None:
        check_model_name(name)
    for _attempt in range(VERSION_ATTEMPTS):
        try:
            with store.session() as session:
                dataset = session.get(DatasetRow, dataset_id) if dataset_id is not None else None
                chosen = name if name is not None else default_model_name(dataset, classifier)
                row = ModelRow(
                    registered_model_id=(parent := _register(session, chosen)),
                    version=take_version(session, parent),
                    dataset_id=dataset_id,
                    run_id=run_id,
                    classifier=classifier,
                    params=params,
                    schema=schema,
                    targets=list(targets),
                    sha256=hashlib.sha256(artifact).hexdigest(),
                    size_bytes=len(artifact),
                    format=SAFE_FORMAT,
                    extraction=dataset.extraction if dataset is not None else None,
                )
                session.add(row)
                session.flush()
                session.add(ModelArtifactRow(model_id=row.id, artifact=artifact))
                return version_info(session, row)
        except IntegrityError as error:
            if "registered_models" not in str(error.orig):
                raise
            # another process registered the name meanwhile: its row is there now
    raise ConflictError(
        f"could not register model '{shorten(str(name))}' after {VERSION_ATTEMPTS} attempts "
        "(busy store); try again"
    )


def _register(session: Session, name: str) -> int:
    """The id of the registered model ``name``, registered now if it is new."""
    found = session.scalar(select(RegisteredModelRow.id).where(RegisteredModelRow.name == name))
    if found is not None:
        return int(found)
    parent = RegisteredModelRow(name=name, last_version=0)
    session.add(parent)
    session.flush()  # a concurrent registration of the name fails here
    return parent.id


def take_version(session: Session, parent: int) -> int:
    """Raise the registered model's counter and return it: the number of its next version
    (one UPDATE: another process raising it meanwhile waits for this transaction's end,
    then raises what this one left)."""
    raised = session.execute(
        update(RegisteredModelRow)
        .where(RegisteredModelRow.id == parent)
        .values(last_version=RegisteredModelRow.last_version + 1)
        .returning(RegisteredModelRow.last_version)
        .execution_options(synchronize_session=False)
    ).scalar_one()
    return int(raised)


def lock_registered(session: Session, parent: int) -> None:
    """Hold the registered model ``parent`` until the transaction ends (its row lock on
    PostgreSQL, the write lock on SQLite), as :func:`take_version` does, without changing
    it: every change to a model's versions and aliases takes it first, so that they happen
    one at a time, each on what the one before it left."""
    session.execute(
        update(RegisteredModelRow)
        .where(RegisteredModelRow.id == parent)
        .values(last_version=RegisteredModelRow.last_version)
        .execution_options(synchronize_session=False)
    )


def held_version(session: Session, ref: str | int) -> ModelRow:
    """The version ``ref`` names, read once its registered model is held
    (:func:`lock_registered`): what the changes before this one left.

    Raises
    ------
    NotFoundError
        ``ref`` names nothing now (another change deleted it meanwhile).
    ConflictError
        ``ref`` names another model now (renamed meanwhile).
    """
    row = version_row(session, ref)
    parent = row.registered_model_id
    lock_registered(session, parent)
    session.expire_all()  # rows read before the lock may have changed since
    row = version_row(session, ref)
    if row.registered_model_id != parent:
        raise ConflictError(
            f"'{shorten(str(ref))}' names another model than it did a moment ago (renamed "
            "meanwhile); try again"
        )
    return row


def default_model_name(dataset: DatasetRow | None, classifier: str) -> str:
    """``DATASET-CLASSIFIER`` (``@`` folded to ``_``: it would read as a version)."""
    base = f"{dataset.name if dataset else 'model'}-{classifier}".replace(SEPARATOR, "_")
    return base[:200]


def check_model_name(name: str) -> None:
    """Refuse names that cannot be told from ids or versions, or do not print
    (:func:`app.schemas.names.check_name`).

    Raises
    ------
    FieldError
        For the request's ``name``, saying which rule the name breaks.
    """
    try:
        check_name(name, kind="model")
    except AppError as error:
        raise FieldError("name", str(error)) from None


def list_models(store: Store, *, page: Page | None = None) -> list[ModelInfo]:
    """Every model version (those of ``page``), oldest first, with their aliases, without
    reading any artifact."""
    with store.session() as session:
        rows = list(session.scalars(paged(select(ModelRow).order_by(ModelRow.id), page)))
        names = _dataset_names(session, rows)
        aliases = _aliases(session, {row.registered_model_id for row in rows})
        twins = _twins(session, [row.id for row in rows])
        return [version_info(session, row, names, aliases, twins) for row in rows]


def count_models(store: Store) -> int:
    """How many model versions the store holds."""
    return count_rows(store, ModelRow)


def get_model(store: Store, ref: str | int) -> ModelInfo:
    """A model's description (its artifact is not read)."""
    with store.session() as session:
        return version_info(session, version_row(session, ref))


def load_artifact(store: Store, ref: str | int) -> tuple[ModelInfo, bytes]:
    """A model's description and artifact bytes (check them with the sha256 before use).

    Raises
    ------
    AppError
        The artifact is in a format that could run code when loaded (models stored by
        touchbench before 0.2 were pickles).
    """
    with store.session() as session:
        row = version_row(session, ref)
        info = version_info(session, row)
        if row.format != SAFE_FORMAT:
            raise AppError(
                f"model '{row.name}' is stored as a {row.format}, a format that can run code "
                "when loaded; train it again under another name"
            )
        artifact = session.get_one(ModelArtifactRow, row.id).artifact
        return info, bytes(artifact)


def delete_model(store: Store, ref: str | int) -> ModelInfo:
    """Delete the version ``ref`` names (``NAME``: the newest): one DELETE, its artifact,
    twins and the aliases that pointed at it going with it by cascade (their history
    stays, and ``rollback`` skips versions that are gone).  Its number and id are not given
    again."""
    with store.session() as session:
        row = held_version(session, ref)
        info = version_info(session, row)
        session.execute(delete(ModelRow).where(ModelRow.id == row.id))
        return info


def rename_model(store: Store, ref: str | int, new_name: str) -> ModelInfo:
    """Give the model ``ref`` names (every version, its aliases and their history) another
    name: one UPDATE of its registered model; returns the version ``ref`` named.

    Raises
    ------
    ConflictError
        Another model has the name, or had it (its numbers are not given again).
    """
    check_model_name(new_name)
    try:
        with store.session() as session:
            row = version_row(session, ref)
            version = row.version
            if new_name != row.name:
                session.execute(
                    update(RegisteredModelRow)
                    .where(RegisteredModelRow.id == row.registered_model_id)
                    .values(name=new_name)
                    .execution_options(synchronize_session=False)
                )
    except IntegrityError:
        raise ConflictError(
            f"a model named '{shorten(new_name)}' exists or existed (a name keeps its version "
            "numbers, which are not given again); choose another name"
        ) from None
    return get_model(store, version_label(new_name, version))


def _dataset_names(session: Session, rows: Sequence[ModelRow]) -> dict[int, str]:
    ids = {row.dataset_id for row in rows if row.dataset_id is not None}
    if not ids:
        return {}
    return dict(
        session.execute(select(DatasetRow.id, DatasetRow.name).where(DatasetRow.id.in_(ids))).all()
    )


def _aliases(session: Session, parents: Collection[int]) -> dict[tuple[int, int], tuple[str, ...]]:
    """(registered model id, version) -> the aliases that point at it, sorted."""
    if not parents:
        return {}
    found: dict[tuple[int, int], list[str]] = {}
    rows = session.execute(
        select(ModelAliasRow.registered_model_id, ModelAliasRow.version, ModelAliasRow.alias)
        .where(ModelAliasRow.registered_model_id.in_(parents))
        .order_by(ModelAliasRow.alias)
    )
    for parent, version, alias in rows:
        found.setdefault((parent, version), []).append(alias)
    return {key: tuple(aliases) for key, aliases in found.items()}


def _twins(session: Session, ids: Collection[int]) -> dict[int, TwinInfo]:
    """Model id -> its ONNX twin's description (the bytes are not read)."""
    if not ids:
        return {}
    rows = session.execute(
        select(ModelExportRow.model_id, ModelExportRow.sha256, ModelExportRow.size_bytes).where(
            ModelExportRow.model_id.in_(ids), ModelExportRow.format == TWIN_FORMAT
        )
    )
    return {model_id: TwinInfo(TWIN_FORMAT, sha256, size) for model_id, sha256, size in rows}


def version_info(
    session: Session,
    row: ModelRow,
    names: dict[int, str] | None = None,
    aliases: dict[tuple[int, int], tuple[str, ...]] | None = None,
    twins: dict[int, TwinInfo] | None = None,
) -> ModelInfo:
    """The description of the version ``row`` (``names``: data set names by id,
    ``aliases`` and ``twins``, when a listing read them for many rows at once)."""
    if names is None:
        names = _dataset_names(session, [row])
    if aliases is None:
        aliases = _aliases(session, {row.registered_model_id})
    if twins is None:
        twins = _twins(session, [row.id])
    return ModelInfo(
        id=row.id,
        name=row.name,
        version=row.version,
        aliases=aliases.get((row.registered_model_id, row.version), ()),
        classifier=row.classifier,
        params=dict(row.params),
        targets=list(row.targets),
        dataset_id=row.dataset_id,
        dataset_name=names.get(row.dataset_id) if row.dataset_id is not None else None,
        run_id=row.run_id,
        sha256=row.sha256,
        size_bytes=row.size_bytes,
        created_at=row.created_at,
        schema=dict(row.schema),
        format=row.format,
        extraction=row.extraction,
        twin=twins.get(row.id),
    )
