"""The data sets' listing, read without the ORM.

``touchbench datasets`` and the pages that list data sets need one row per data set and
nothing of its instances; reading them through SQLAlchemy Core keeps the ORM (and NumPy)
out of the command's start-up.  :data:`DATASETS` names the columns the listing reads, with
the types that turn them back into Python values; a test keeps it equal to the ``datasets``
table of :mod:`app.store.tables`.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import JSON, DateTime, Integer, String, Text, column, func, select, table

from app.schemas.listing import Page
from app.store.database import Store
from app.store.paging import paged

DATASETS = table(
    "datasets",
    column("id", Integer),
    column("name", String),
    column("relation", Text),
    column("target_names", JSON),
    column("n_instances", Integer),
    column("n_attributes", Integer),
    column("source_name", Text),
    column("sha256", String),
    column("created_at", DateTime(timezone=True)),
)


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
    def of(cls, row: Any) -> DatasetInfo:
        """The listing of a ``datasets`` row: an ORM object or a Core row alike."""
        return cls(
            id=row.id,
            name=row.name,
            relation=row.relation,
            n_instances=row.n_instances,
            n_features=row.n_attributes - len(row.target_names),
            targets=list(row.target_names),
            source_name=row.source_name,
            sha256=row.sha256,
            # SQLite gives back naive times; they were written in UTC.
            created_at=row.created_at
            if row.created_at.tzinfo is not None
            else row.created_at.replace(tzinfo=UTC),
        )


def list_datasets(store: Store, *, page: Page | None = None) -> list[DatasetInfo]:
    """The data sets, oldest first (those of ``page`` only, when given)."""
    with store.engine.connect() as connection:
        rows = connection.execute(paged(select(DATASETS).order_by(DATASETS.c.id), page))
        return [DatasetInfo.of(row) for row in rows]


def count_datasets(store: Store) -> int:
    """How many data sets the store holds."""
    with store.engine.connect() as connection:
        return int(connection.scalar(select(func.count()).select_from(DATASETS)) or 0)
