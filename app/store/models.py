"""Trained models in the store: the artifact's bytes with their sha256 and format, the schema
the model expects, the classifier and its parameters, the data set and run it came from,
and how that data set was extracted from recordings.

Artifacts live in a table of their own (``model_artifacts``), so listings and the version
check of every served prediction never read one; :func:`load_artifact` reads one, and
only a format that cannot run code when loaded (``skops``) is handed out.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import bindparam, delete, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from app.errors import AppError, ConflictError, FieldError
from app.schemas.listing import Page
from app.schemas.models import ModelSchema
from app.store.database import Store
from app.store.naming import find_row, free_name, is_decimal, is_row_id, may_be_name, shorten
from app.store.paging import count_rows, paged
from app.store.tables import DatasetRow, ModelArtifactRow, ModelRow

#: The only artifact format that is loaded (see :mod:`benchmark.artifacts`).
SAFE_FORMAT = "skops"


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
    """Store a model's artifact; its name defaults to ``DATASET-CLASSIFIER[-N]``.

    The data set's extraction recipe (if it was extracted from recordings) is copied to
    the model, so that live prediction extracts features as training did.
    """
    if name is not None:
        check_model_name(name)
    try:
        with store.session() as session:
            dataset = session.get(DatasetRow, dataset_id) if dataset_id is not None else None
            if name is None:
                base = f"{dataset.name if dataset else 'model'}-{classifier}"
                name = free_name(session, ModelRow, base)
            else:
                _refuse_taken(session, name)
            row = ModelRow(
                name=name,
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
            return _info(session, row)
    except IntegrityError:  # another process took the name between our check and insert
        raise ConflictError(_taken(str(name))) from None


def check_model_name(name: str) -> None:
    """Refuse names that cannot be told from ids or do not print.

    Raises
    ------
    FieldError
        For the request's ``name``, saying which rule the name breaks.
    """
    if not name.strip():
        raise FieldError("name", "a model name cannot be empty")
    if is_decimal(name):
        raise FieldError("name", f"a model name cannot be a number ('{name}' would read as an id)")
    if len(name) > 200:
        raise FieldError("name", f"a model name has at most 200 characters, got {len(name)}")
    if any(not character.isprintable() for character in name):
        raise FieldError("name", "a model name cannot contain control characters")


def check_name_free(store: Store, name: str) -> None:
    """Refuse a model name another model has.

    Raises
    ------
    ConflictError
        The name is taken.
    """
    with store.session() as session:
        _refuse_taken(session, name)


def _refuse_taken(session: Session, name: str) -> None:
    if session.scalars(select(ModelRow.id).where(ModelRow.name == name)).first() is not None:
        raise ConflictError(_taken(name))


def _taken(name: str) -> str:
    return f"a model named '{shorten(name)}' already exists; choose another name"


def list_models(store: Store, *, page: Page | None = None) -> list[ModelInfo]:
    """Every model (those of ``page``), oldest first, without reading any artifact."""
    with store.session() as session:
        rows = list(session.scalars(paged(select(ModelRow).order_by(ModelRow.id), page)))
        names = _dataset_names(session, rows)
        return [_info(session, row, names) for row in rows]


def count_models(store: Store) -> int:
    return count_rows(store, ModelRow)


def get_model(store: Store, ref: str | int) -> ModelInfo:
    """A model's description (its artifact is not read)."""
    with store.session() as session:
        return _info(session, _row(session, ref))


def model_version(store: Store, ref: str | int) -> tuple[int, str, str]:
    """A model's id, artifact sha256 and name: one indexed query on the driver's cursor.

    The service's model cache asks this on every prediction to know whether the model it
    holds is still the stored one.

    Raises
    ------
    NotFoundError
        As :func:`get_model` does.
    """
    text = str(ref)
    found = None
    if may_be_name(text):
        found = store.first_row(_VERSION_BY_NAME, ref=text)
    if found is None and is_row_id(text):
        found = store.first_row(_VERSION_BY_ID, ref=int(text))
    if found is None:
        get_model(store, ref)  # raises NotFoundError naming the known models
        raise AssertionError("get_model found a model the version query did not")
    return int(found[0]), str(found[1]), str(found[2])


_VERSION = select(ModelRow.id, ModelRow.sha256, ModelRow.name)
_VERSION_BY_NAME = _VERSION.where(ModelRow.name == bindparam("ref"))
_VERSION_BY_ID = _VERSION.where(ModelRow.id == bindparam("ref"))


def load_artifact(store: Store, ref: str | int) -> tuple[ModelInfo, bytes]:
    """A model's description and artifact bytes (check them with the sha256 before use).

    Raises
    ------
    AppError
        The artifact is in a format that could run code when loaded (models stored by
        touchbench before 0.2 were pickles).
    """
    with store.session() as session:
        row = _row(session, ref)
        info = _info(session, row)
        if row.format != SAFE_FORMAT:
            raise AppError(
                f"model '{row.name}' is stored as a {row.format}, a format that can run code "
                "when loaded; train it again under another name"
            )
        artifact = session.get_one(ModelArtifactRow, row.id).artifact
        return info, bytes(artifact)


def delete_model(store: Store, ref: str | int) -> ModelInfo:
    with store.session() as session:
        row = _row(session, ref)
        info = _info(session, row)
        session.execute(delete(ModelRow).where(ModelRow.id == row.id))
        return info


def rename_model(store: Store, ref: str | int, new_name: str) -> ModelInfo:
    check_model_name(new_name)
    try:
        with store.session() as session:
            row = _row(session, ref)
            session.execute(update(ModelRow).where(ModelRow.id == row.id).values(name=new_name))
    except IntegrityError:
        raise ConflictError(_taken(new_name)) from None
    return get_model(store, new_name)


def _row(session: Session, ref: str | int) -> ModelRow:
    return find_row(session, ModelRow, ref, kind="model", hint="none yet; training makes one")


def _dataset_names(session: Session, rows: Sequence[ModelRow]) -> dict[int, str]:
    ids = {row.dataset_id for row in rows if row.dataset_id is not None}
    if not ids:
        return {}
    return dict(
        session.execute(select(DatasetRow.id, DatasetRow.name).where(DatasetRow.id.in_(ids))).all()
    )


def _info(session: Session, row: ModelRow, names: dict[int, str] | None = None) -> ModelInfo:
    if names is None:
        names = _dataset_names(session, [row])
    return ModelInfo(
        id=row.id,
        name=row.name,
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
    )
