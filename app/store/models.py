"""Trained models in the store: the artifact's bytes with their sha256, the schema the
model expects, the classifier and its parameters, and the data set and run it came from."""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from app.errors import AppError
from app.store.database import Store
from app.store.naming import find_row, free_name
from app.store.tables import DatasetRow, ModelRow


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

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "name": self.name,
            "classifier": self.classifier,
            "targets": self.targets,
            "dataset": self.dataset_name,
            "dataset_id": self.dataset_id,
            "run_id": self.run_id,
            "sha256": self.sha256,
            "size_bytes": self.size_bytes,
            "created_at": self.created_at.isoformat(),
        }


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
    """Store a model's artifact; its name defaults to ``DATASET-CLASSIFIER[-N]``."""
    with store.session() as session:
        dataset_name = (
            session.scalar(select(DatasetRow.name).where(DatasetRow.id == dataset_id))
            if dataset_id is not None
            else None
        )
        if name is None:
            name = free_name(session, ModelRow, f"{dataset_name or 'model'}-{classifier}")
        elif session.scalars(select(ModelRow).where(ModelRow.name == name)).first() is not None:
            raise AppError(f"a model named '{name}' already exists; choose another --name")
        row = ModelRow(
            name=name,
            dataset_id=dataset_id,
            run_id=run_id,
            classifier=classifier,
            params=params,
            schema=schema,
            targets=list(targets),
            artifact=artifact,
            sha256=hashlib.sha256(artifact).hexdigest(),
            size_bytes=len(artifact),
        )
        session.add(row)
        session.flush()
        return _info(session, row)


def list_models(store: Store) -> list[ModelInfo]:
    with store.session() as session:
        rows = session.scalars(select(ModelRow).order_by(ModelRow.id))
        return [_info(session, row) for row in rows]


def load_artifact(store: Store, ref: str | int) -> tuple[ModelInfo, bytes]:
    """A model's description and artifact bytes (check them with the sha256 before use)."""
    with store.session() as session:
        row = _row(session, ref)
        return _info(session, row), bytes(row.artifact)


def _row(session: Session, ref: str | int) -> ModelRow:
    return find_row(
        session, ModelRow, ref, kind="model", hint="none yet; `touchbench train` makes one"
    )


def _info(session: Session, row: ModelRow) -> ModelInfo:
    dataset_name = (
        session.scalar(select(DatasetRow.name).where(DatasetRow.id == row.dataset_id))
        if row.dataset_id is not None
        else None
    )
    return ModelInfo(
        id=row.id,
        name=row.name,
        classifier=row.classifier,
        params=dict(row.params),
        targets=list(row.targets),
        dataset_id=row.dataset_id,
        dataset_name=dataset_name,
        run_id=row.run_id,
        sha256=row.sha256,
        size_bytes=row.size_bytes,
        created_at=row.created_at,
        schema=dict(row.schema),
    )
