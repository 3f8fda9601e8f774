"""The data sets' listing as the CLI, the API and the web page show it.

Kept apart from :mod:`app.services.datasets`, which reads and writes data files, so that
listing the store loads neither NumPy nor the file readers.
"""

from __future__ import annotations

from touchbench.app.schemas.datasets import DatasetSummary
from touchbench.app.schemas.listing import Page
from touchbench.app.store import listing as stored
from touchbench.app.store.listing import DatasetInfo
from touchbench.app.store.reading import Readable


def summary(info: DatasetInfo) -> DatasetSummary:
    """The listing of a stored data set as the CLI and the API show it."""
    return DatasetSummary(
        id=info.id,
        name=info.name,
        relation=info.relation,
        n_instances=info.n_instances,
        n_features=info.n_features,
        targets=info.targets,
        source=info.source_name,
        sha256=info.sha256,
        created_at=info.created_at,
    )


def list_datasets(store: Readable, *, page: Page | None = None) -> list[DatasetSummary]:
    """Every stored data set (those of ``page``), oldest first."""
    return [summary(info) for info in stored.list_datasets(store, page=page)]


def count_datasets(store: Readable) -> int:
    """How many data sets the store holds."""
    return stored.count_datasets(store)
