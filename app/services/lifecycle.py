"""Stored runs and jobs as requests see them: listed, read, cancelled, a run queued again.

The rules of which status may become which are :mod:`app.store.states`'; this module is
what the adapters call for them.  It reads the store only, so that listing runs or
cancelling one loads neither the engine nor the statistics (start-up time of the CLI's
commands); carrying work out is :mod:`app.services.runs` and :mod:`app.services.jobs`.
"""

from __future__ import annotations

from touchbench.app.schemas.jobs import JobSchema
from touchbench.app.schemas.listing import Page
from touchbench.app.store import jobs as stored_jobs
from touchbench.app.store import run_progress as stored_progress
from touchbench.app.store import runs as stored_runs
from touchbench.app.store.database import Store
from touchbench.app.store.run_progress import RunProgress
from touchbench.app.store.runs import RunInfo


def list_runs(
    store: Store, *, dataset_id: int | None = None, page: Page | None = None
) -> list[RunInfo]:
    """The runs (on ``dataset_id``), oldest first (those of ``page``, when given)."""
    return stored_runs.list_runs(store, dataset_id=dataset_id, page=page)


def count_runs(store: Store, *, dataset_id: int | None = None) -> int:
    """How many runs there are (on ``dataset_id``)."""
    return stored_runs.count_runs(store, dataset_id=dataset_id)


def get_run(store: Store, run_id: int | str) -> RunInfo:
    """A run with its status and progress.

    Raises
    ------
    NotFoundError
    """
    return stored_runs.get_run(store, run_id)


def run_progress(store: Store, run_id: int | str) -> RunProgress:
    """A run's status and its tasks counted by state, read light for a page that polls it:
    what it reads does not grow with the run's classifiers or results.

    Raises
    ------
    NotFoundError
    """
    return stored_progress.run_progress(store, run_id)


def cancel_run(store: Store, run_id: int | str) -> RunInfo:
    """Cancel a run: a queued one at once, a running one by asking its process to stop
    (status ``cancelling`` until it has); its finished tasks stay.

    Raises
    ------
    NotFoundError
    ConflictError
        The run is already over.
    """
    return stored_runs.request_cancel(store, run_id)


def requeue_run(store: Store, run_id: int | str) -> RunInfo:
    """Queue an interrupted, cancelled or failed run again: a worker carries out the tasks
    it has no result for.

    Raises
    ------
    NotFoundError
    ConflictError
        The run is queued, executing, being cancelled or done.
    """
    return stored_runs.requeue_run(store, run_id)


def list_jobs(store: Store, *, page: Page | None = None) -> list[JobSchema]:
    """The jobs, oldest first (those of ``page``, when given)."""
    return stored_jobs.list_jobs(store, page=page)


def count_jobs(store: Store) -> int:
    return stored_jobs.count_jobs(store)


def get_job(store: Store, job_id: int | str) -> JobSchema:
    """A job's status and, once done, its result.

    Raises
    ------
    NotFoundError
    """
    return stored_jobs.get_job(store, job_id)


def cancel_job(store: Store, job_id: int | str) -> JobSchema:
    """Cancel a job: a queued one at once, a running one by asking its process to stop.

    Raises
    ------
    NotFoundError
    ConflictError
        The job is over (done, failed, cancelled or interrupted).
    """
    return stored_jobs.request_job_cancel(store, job_id)
