"""Jobs in the store: queued by the service, claimed by exactly one worker process, finished
with a result or an error.  Claiming is one conditional UPDATE, so that two dispatchers (two
service processes on one store) never carry out the same job twice."""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import select, update

from touchbench.app.errors import NotFoundError
from touchbench.app.schemas.jobs import JobSchema
from touchbench.app.schemas.listing import Page
from touchbench.app.schemas.status import ACTIVE, Status
from touchbench.app.store import queue
from touchbench.app.store.database import Store
from touchbench.app.store.naming import is_row_id
from touchbench.app.store.ownership import mark_lost, owner_alive, process_owner
from touchbench.app.store.paging import count_rows, paged
from touchbench.app.store.states import LOST_AS
from touchbench.app.store.tables import JobRow, utcnow

#: The error a job left by a dead process is recorded with.
_LOST_ERROR = "the worker process stopped before the job ended"


@dataclass(frozen=True)
class _JobState:
    """What the state rules (:mod:`app.store.states`) read of a job."""

    id: int
    status: Status
    owner: str | None
    heartbeat_at: datetime | None

    def owner_alive(self) -> bool:
        return owner_alive(self.owner, self.heartbeat_at)


def create_job(store: Store, kind: str, params: dict[str, Any]) -> JobSchema:
    with store.session() as session:
        row = JobRow(kind=kind, status=Status.QUEUED, params=params)
        session.add(row)
        session.flush()
        return _schema(row)


def start_job(store: Store, kind: str, params: dict[str, Any], *, owner: str) -> JobSchema:
    """A job carried out at once by ``owner`` (the command line's own process): created
    ``running``, so that no dispatcher takes it."""
    now = utcnow()
    with store.session() as session:
        row = JobRow(
            kind=kind,
            status=Status.RUNNING,
            params=params,
            owner=owner,
            started_at=now,
            heartbeat_at=now,
        )
        session.add(row)
        session.flush()
        return _schema(row)


def record_job_progress(store: Store, job_id: int, result: dict[str, Any]) -> None:
    """Keep what a running job has finished so far as its ``result`` (shown while it runs;
    the final result replaces it)."""
    with store.session() as session:
        session.execute(
            update(JobRow)
            .where(JobRow.id == job_id, JobRow.status.in_(ACTIVE))
            .values(result=result)
            .execution_options(synchronize_session=False)
        )


def done_jobs_of_run(store: Store, kind: str, run_id: int) -> list[JobSchema]:
    """The finished (``done``) jobs of ``kind`` whose request names run ``run_id``, newest
    first."""
    return done_jobs_naming(store, kind, "run", (run_id,))


def done_jobs_naming(
    store: Store, kind: str, field: str, values: Collection[object]
) -> list[JobSchema]:
    """The finished (``done``) jobs of ``kind`` whose request's ``field`` is one of
    ``values`` (a data set's name and id, say), newest first."""
    with store.session() as session:
        rows = session.scalars(
            select(JobRow)
            .where(JobRow.kind == kind, JobRow.status == Status.DONE)
            .order_by(JobRow.id.desc())
        )
        return [_schema(row) for row in rows if row.params.get(field) in values]


def get_job(store: Store, job_id: int | str) -> JobSchema:
    with store.session() as session:
        return _schema(_row(session, job_id))


def list_jobs(store: Store, *, page: Page | None = None) -> list[JobSchema]:
    """The jobs, oldest first (those of ``page``, when given)."""
    with store.session() as session:
        rows = session.scalars(paged(select(JobRow).order_by(JobRow.id), page))
        return [_schema(row) for row in rows]


def count_jobs(store: Store) -> int:
    return count_rows(store, JobRow)


def queued_jobs(store: Store) -> list[JobSchema]:
    with store.session() as session:
        rows = session.scalars(
            select(JobRow).where(JobRow.status == Status.QUEUED).order_by(JobRow.id)
        )
        return [_schema(row) for row in rows]


def claim_job(store: Store, job_id: int, *, owner: str | None = None) -> bool:
    """Take a queued job for this process; ``False`` if another process took it first."""
    now = utcnow()
    with store.session() as session:
        claimed = session.execute(
            update(JobRow)
            .where(JobRow.id == job_id, JobRow.status == Status.QUEUED)
            .values(
                status=Status.RUNNING,
                owner=owner or process_owner(),
                started_at=now,
                heartbeat_at=now,
                cancel_requested=False,
            )
            .execution_options(synchronize_session=False)
        ).rowcount  # type: ignore[attr-defined]  # an UPDATE gives a CursorResult
    return bool(claimed)


def finish_job(
    store: Store,
    job_id: int,
    status: Status,
    *,
    result: dict[str, Any] | None = None,
    error: str | None = None,
) -> None:
    with store.session() as session:
        session.execute(
            update(JobRow)
            .where(JobRow.id == job_id)
            .values(
                status=status,
                result=result,
                error=error,
                finished_at=utcnow(),
                owner=None,
                heartbeat_at=None,
            )
            .execution_options(synchronize_session=False)
        )


def request_job_cancel(store: Store, job_id: int | str) -> JobSchema:
    """Cancel a job: at once while it is queued, else by asking its process to stop (status
    ``cancelling`` until it has).

    Raises
    ------
    ConflictError
        The job is over (done, failed, cancelled or interrupted).
    """
    with store.session() as session:
        row = _row(session, job_id)
        state = _JobState(row.id, Status(row.status), row.owner, row.heartbeat_at)
    outcome = queue.request_cancel(store, JobRow, state, "job")
    if outcome == "changed":  # the job changed meanwhile: judge it again
        return request_job_cancel(store, state.id)
    job = get_job(store, state.id)
    if outcome == Status.CANCELLING:  # what this request did, whatever the job's process does
        return job.model_copy(update={"status": Status.CANCELLING})
    return job


def job_heartbeat(
    store: Store, job_id: int, owner: str, on_stop: Callable[[], None]
) -> queue.Heartbeat:
    """The thread that keeps the job's heartbeat for ``owner`` and calls ``on_stop`` once
    when the job should stop (a cancel)."""
    return queue.Heartbeat(store, JobRow, job_id, owner, on_stop)


def mark_lost_jobs(store: Store) -> list[int]:
    """Jobs left active by a process that died become ``interrupted`` (``cancelled`` when
    they were being cancelled); their ids."""
    lost: list[int] = []
    with store.session() as session:
        for status, becomes in LOST_AS.items():
            error = _LOST_ERROR if status == Status.RUNNING else None
            lost += mark_lost(
                session,
                JobRow,
                of=status,
                status=becomes,
                error=error,
                finished_at=utcnow(),
                owner=None,
                heartbeat_at=None,
            )
    return sorted(lost)


def _row(session: Any, job_id: int | str) -> JobRow:
    text = str(job_id)
    row = session.get(JobRow, int(text)) if is_row_id(text) else None
    if row is None:
        raise NotFoundError(f"no job '{text[:40]}'")
    return row


def _schema(row: JobRow) -> JobSchema:
    return JobSchema(
        id=row.id,
        kind=row.kind,  # type: ignore[arg-type]  # a JobKind literal in the column
        status=Status(row.status),
        params=dict(row.params),
        result=row.result,
        error=row.error,
        created_at=row.created_at,
        started_at=row.started_at,
        finished_at=row.finished_at,
    )
