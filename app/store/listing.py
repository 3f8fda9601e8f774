"""The data sets' listing, read through the database driver alone.

``touchbench datasets`` and the pages that list data sets need one row per data set and
nothing of its instances.  The listing is one SQL statement run on a DB-API connection
(:mod:`app.store.reading`): the CLI reads a SQLite store without importing SQLAlchemy, the
service through its :class:`~app.store.database.Store`'s pool, alike.  :data:`COLUMNS`
names the columns it reads; a test keeps them those of the ``datasets`` table of
:mod:`app.store.tables`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from datetime import UTC, datetime
from types import SimpleNamespace
from typing import Any

from touchbench.app.schemas.listing import Page
from touchbench.app.store.reading import Readable, fetch_all

#: The columns of ``datasets`` the listing reads, in the order of its rows.
COLUMNS = (
    "id",
    "name",
    "relation",
    "target_names",
    "n_instances",
    "n_attributes",
    "source_name",
    "sha256",
    "created_at",
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


def list_datasets(store: Readable, *, page: Page | None = None) -> list[DatasetInfo]:
    """The data sets, oldest first (those of ``page`` only, when given)."""
    statement = f"SELECT {', '.join(COLUMNS)} FROM datasets ORDER BY id"
    if page is not None:  # whole numbers (a Page's bounds): written into the statement
        statement += f" LIMIT {int(page.limit)} OFFSET {int(page.offset)}"
    return [_info(values) for values in fetch_all(store, statement)]


def _info(values: tuple[Any, ...]) -> DatasetInfo:
    """A row as its driver gives it: SQLite's JSON and times as text, PostgreSQL's parsed."""
    row = dict(zip(COLUMNS, values, strict=True))
    if isinstance(row["target_names"], str):
        row["target_names"] = json.loads(row["target_names"])
    if isinstance(row["created_at"], str):
        row["created_at"] = datetime.fromisoformat(row["created_at"])
    return DatasetInfo.of(SimpleNamespace(**row))


def count_datasets(store: Readable) -> int:
    """How many data sets the store holds."""
    ((count,),) = fetch_all(store, "SELECT count(*) FROM datasets")
    return int(count)
