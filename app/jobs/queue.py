"""The one queue a dispatcher reads: queued runs and queued jobs, oldest first.

Runs and jobs wait in two tables; a dispatcher takes them in the order they were queued,
whichever table holds them.  Upload folders are on the disk of the host that received the
upload, so a job that names a host waits for that host's dispatcher.
"""

from __future__ import annotations

import socket
from collections.abc import Collection
from dataclasses import dataclass
from typing import Literal

from touchbench.app.schemas.status import Status
from touchbench.app.store.database import Store
from touchbench.app.store.jobs import queued_jobs
from touchbench.app.store.runs import list_runs

Kind = Literal["run", "job"]


@dataclass(frozen=True)
class Item:
    """A queued run or job, as a worker process is told to carry it out."""

    kind: Kind
    id: int


def waiting(store: Store, *, host: str | None = None) -> list[Item]:
    """The queued runs and jobs that ``host`` (default: this one) may take, oldest first.

    Items queued at the same moment come in id order, runs before jobs.
    """
    host = host or socket.gethostname()
    runs = [(run.created_at, Item("run", run.id)) for run in list_runs(store, status=Status.QUEUED)]
    jobs = [
        (job.created_at, Item("job", job.id))
        for job in queued_jobs(store)
        if job.params.get("host", host) == host
    ]
    ordered = sorted(runs + jobs, key=lambda entry: (entry[0].timestamp(), entry[1].id))
    return [item for _, item in ordered]


def next_item(
    store: Store, *, taken: Collection[Item] = (), host: str | None = None
) -> Item | None:
    """The oldest item in :func:`waiting` that is not in ``taken``, or None."""
    return next((item for item in waiting(store, host=host) if item not in taken), None)
