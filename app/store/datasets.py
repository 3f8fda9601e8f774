"""Data sets in the store: add (one transaction, deduplicated by content), look up by name
or id, load into a :class:`benchmark.dataset.Dataset`, list and delete."""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass
from datetime import datetime
from typing import Any

import numpy as np
from sqlalchemy import delete, insert, select
from sqlalchemy.orm import Session

from app.errors import AppError
from app.store.database import Store
from app.store.naming import find_row, free_name
from app.store.tables import DatasetRow, InstanceRow
from benchmark.dataset import Dataset, Schema

_LITTLE_F8 = np.dtype("<f8")
_INSERT_BATCH = 5000


@dataclass(frozen=True)
class DatasetInfo:
    """What a listing shows of a stored data set."""

    id: int
    name: str
    relation: str
    n_instances: int
    n_features: int
    targets: list[str]
    source_name: str | None
    sha256: str
    created_at: datetime

    @classmethod
    def of(cls, row: DatasetRow) -> DatasetInfo:
        return cls(
            id=row.id,
            name=row.name,
            relation=row.relation,
            n_instances=row.n_instances,
            n_features=row.n_attributes - len(row.target_names),
            targets=list(row.target_names),
            source_name=row.source_name,
            sha256=row.sha256,
            created_at=row.created_at,
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "name": self.name,
            "relation": self.relation,
            "n_instances": self.n_instances,
            "n_features": self.n_features,
            "targets": self.targets,
            "source": self.source_name,
            "sha256": self.sha256,
            "created_at": self.created_at.isoformat(),
        }


def content_digest(content: bytes) -> str:
    """sha256 of a file's bytes, the key that recognises a file imported before."""
    return hashlib.sha256(content).hexdigest()


def dataset_digest(dataset: Dataset) -> str:
    """sha256 of a data set made in memory (schema and values), for data without a file."""
    digest = hashlib.sha256(json.dumps(dataset.schema.to_json(), sort_keys=True).encode())
    digest.update(np.ascontiguousarray(dataset.values, dtype=_LITTLE_F8).tobytes())
    return digest.hexdigest()


def add_dataset(
    store: Store,
    dataset: Dataset,
    *,
    sha256: str,
    name: str | None = None,
    source_name: str | None = None,
    extraction: dict[str, Any] | None = None,
) -> tuple[DatasetInfo, bool]:
    """Store a data set in one transaction, unless the same content is stored already.

    Parameters
    ----------
    store : Store
    dataset : Dataset
    sha256 : str
        Digest of the content (:func:`content_digest` of the file's bytes).
    name : str, optional
        Unique name; by default the relation name (made unique with a numeric suffix).
    source_name : str, optional
        File name the data came from.
    extraction : dict, optional
        How the data set was extracted from recordings (JSON), kept so that models trained
        on it can extract live features the same way.

    Returns
    -------
    info : DatasetInfo
    created : bool
        ``False`` when the content was already stored and ``info`` is that data set.
    """
    with store.session() as session:
        existing = session.scalars(
            select(DatasetRow).where(DatasetRow.sha256 == sha256).order_by(DatasetRow.id)
        ).first()
        if existing is not None:
            return DatasetInfo.of(existing), False
        if name is not None:
            _check_name(session, name)
        else:
            name = free_name(session, DatasetRow, default_name(dataset.schema.relation))
        row = DatasetRow(
            name=name,
            relation=dataset.schema.relation,
            schema=dataset.schema.to_json(),
            target_names=list(dataset.schema.target_names),
            n_instances=dataset.n_instances,
            n_attributes=dataset.schema.n_attributes,
            sparse=dataset.sparse,
            source_name=source_name,
            sha256=sha256,
            extraction=extraction,
        )
        session.add(row)
        session.flush()
        _insert_instances(session, row.id, dataset)
        return DatasetInfo.of(row), True


def default_name(relation: str) -> str:
    """A data set name from a relation: MEKA's options dropped, unsafe characters folded."""
    base = relation.split(":", 1)[0].strip() or "dataset"
    return re.sub(r"[^\w.-]+", "_", base).strip("_") or "dataset"


def find_dataset(store: Store, ref: str | int) -> DatasetInfo:
    """The data set called ``ref``, or with id ``ref``."""
    with store.session() as session:
        return DatasetInfo.of(_row(session, ref))


def list_datasets(store: Store) -> list[DatasetInfo]:
    with store.session() as session:
        rows = session.scalars(select(DatasetRow).order_by(DatasetRow.id))
        return [DatasetInfo.of(row) for row in rows]


def load_schema(store: Store, ref: str | int) -> Schema:
    """The stored data set's schema alone (attributes, labels, targets), without its rows."""
    with store.session() as session:
        return Schema.from_json(_row(session, ref).schema)


def load_dataset(store: Store, ref: str | int) -> Dataset:
    """The stored data set, values as WEKA encodes them (see :mod:`benchmark.dataset`)."""
    with store.session() as session:
        row = _row(session, ref)
        schema = Schema.from_json(row.schema)
        blobs = _instance_blobs(session, row.id)
        values = np.frombuffer(b"".join(blobs), dtype=_LITTLE_F8).reshape(
            len(blobs), schema.n_attributes
        )
        weights, groups, meta = _instance_extras(session, row.id, len(blobs))
        return Dataset(
            schema=schema,
            values=values.copy(),
            weights=weights,
            groups=groups,
            meta=meta,
            sparse=row.sparse,
            name=row.name,
        )


def delete_dataset(store: Store, ref: str | int) -> DatasetInfo:
    """Remove a data set with its instances (and, by cascade, its runs)."""
    with store.session() as session:
        row = _row(session, ref)
        info = DatasetInfo.of(row)
        session.execute(delete(InstanceRow).where(InstanceRow.dataset_id == row.id))
        session.delete(row)
        return info


def _insert_instances(session: Session, dataset_id: int, dataset: Dataset) -> None:
    values = np.ascontiguousarray(dataset.values, dtype=_LITTLE_F8)
    n = dataset.n_instances
    weights = dataset.weights
    groups = dataset.groups
    metas = dataset.meta
    for start in range(0, n, _INSERT_BATCH):
        stop = min(start + _INSERT_BATCH, n)
        session.execute(
            insert(InstanceRow),
            [
                {
                    "dataset_id": dataset_id,
                    "position": i,
                    "data": values[i].tobytes(),
                    "weight": None if weights is None else float(weights[i]),
                    "group_id": None if groups is None else str(groups[i]),
                    "meta": None if metas is None else metas[i],
                }
                for i in range(start, stop)
            ],
        )


def _instance_blobs(session: Session, dataset_id: int) -> list[bytes]:
    """Every instance's bytes in order, through the driver's own cursor: SQLAlchemy's
    per-row processing and psycopg's text-format ``bytea`` would triple the load time."""
    connection = session.connection()
    dbapi = connection.connection.dbapi_connection
    assert dbapi is not None
    style = connection.dialect.paramstyle
    marker = {"qmark": "?", "numeric": ":1", "named": ":id"}.get(style, "%s")
    cursor = (
        dbapi.cursor(binary=True) if connection.dialect.driver == "psycopg" else (dbapi.cursor())
    )
    try:
        cursor.execute(
            f"SELECT data FROM instances WHERE dataset_id = {marker} ORDER BY position",
            {"id": dataset_id} if style == "named" else (dataset_id,),
        )
        return [bytes(blob) for (blob,) in cursor.fetchall()]
    finally:
        cursor.close()


def _instance_extras(
    session: Session, dataset_id: int, n: int
) -> tuple[np.ndarray | None, np.ndarray | None, list[dict[str, Any]] | None]:
    """Weights, group ids and metadata, read only from the instances that have any."""
    rows = session.execute(
        select(InstanceRow.position, InstanceRow.weight, InstanceRow.group_id, InstanceRow.meta)
        .where(InstanceRow.dataset_id == dataset_id)
        .where(
            InstanceRow.weight.is_not(None)
            | InstanceRow.group_id.is_not(None)
            | InstanceRow.meta.is_not(None)
        )
    ).all()
    weights: np.ndarray | None = None
    groups: np.ndarray | None = None
    meta: list[dict[str, Any]] | None = None
    for position, weight, group, extra in rows:
        if weight is not None:
            if weights is None:
                weights = np.ones(n)
            weights[position] = weight
        if group is not None:
            if groups is None:
                groups = np.full(n, None, dtype=object)
            groups[position] = group
        if extra is not None:
            if meta is None:
                meta = [{} for _ in range(n)]
            meta[position] = extra
    return weights, groups, meta


def _check_name(session: Session, name: str) -> None:
    if not name.strip():
        raise AppError("a dataset name cannot be empty")
    if name.isdigit():
        raise AppError(f"a dataset name cannot be a number ('{name}' would read as an id)")
    clash = session.scalars(select(DatasetRow).where(DatasetRow.name == name)).first()
    if clash is not None:
        raise AppError(
            f"a dataset named '{name}' already exists (id {clash.id}); choose another --name"
        )


def _row(session: Session, ref: str | int) -> DatasetRow:
    return find_row(
        session, DatasetRow, ref, kind="dataset", hint="the store has none; import one first"
    )
