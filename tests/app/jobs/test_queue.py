"""The dispatcher's queue read from a real store (SQLite and PostgreSQL): queued runs and
jobs in the order they were queued, whichever table holds them, without the items already
taken, and an upload's extraction job only on the host that received the upload."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from pathlib import Path

from sqlalchemy import update

from tests.support.synthetic import touch_arff
from touchbench.app.jobs.queue import Item, next_item, waiting
from touchbench.app.schemas.run_config import RunConfig
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset, dataset_digest
from touchbench.app.store.jobs import create_job
from touchbench.app.store.runs import create_run
from touchbench.app.store.tables import JobRow, RunRow
from touchbench.benchmark.io.arff import read_arff

START = datetime(2026, 1, 1, tzinfo=UTC)


def _queued_run(store: Store, dataset_id: int, minute: int) -> Item:
    run = create_run(
        store,
        dataset_id=dataset_id,
        kind="multiclass",
        targets=["gesture"],
        classifiers=["nb"],
        config=RunConfig(folds=2, repeats=1, seed=0, n_tasks=2),
    )
    _queued_at(store, RunRow, run.id, minute)
    return Item("run", run.id)


def _queued_job(store: Store, minute: int, **params: str) -> Item:
    job = create_job(store, "extract", dict(params))
    _queued_at(store, JobRow, job.id, minute)
    return Item("job", job.id)


def _queued_at(store: Store, table: type[RunRow] | type[JobRow], row_id: int, minute: int) -> None:
    """Say when a row was queued: rows made one after the other may share a timestamp."""
    _set(store, table, row_id, created_at=START + timedelta(minutes=minute))


def _set(store: Store, table: type[RunRow] | type[JobRow], row_id: int, **values: object) -> None:
    with store.session() as session:
        session.execute(update(table).where(table.id == row_id).values(**values))


def test_runs_and_jobs_come_oldest_first_and_jobs_only_on_their_host(
    store: Store, tmp_path: Path
) -> None:
    data = read_arff(touch_arff(tmp_path / "t.arff", n=12))
    dataset, _ = add_dataset(store, data, sha256=dataset_digest(data), name="touch")
    newest_run = _queued_run(store, dataset.id, minute=5)
    oldest_job = _queued_job(store, minute=1, host="here")
    elsewhere = _queued_job(store, minute=0, host="there")  # its upload is on another disk
    oldest_run = _queued_run(store, dataset.id, minute=2)
    anywhere = _queued_job(store, minute=3)  # a job that names no host: any host takes it
    done = _queued_run(store, dataset.id, minute=0)
    _set(store, RunRow, done.id, status="done")
    finished_job = _queued_job(store, minute=0, host="here")
    _set(store, JobRow, finished_job.id, status="done")

    assert waiting(store, host="here") == [oldest_job, oldest_run, anywhere, newest_run]
    assert waiting(store, host="there") == [elsewhere, oldest_run, anywhere, newest_run]
    assert next_item(store, host="here") == oldest_job
    assert next_item(store, taken={oldest_job, oldest_run}, host="here") == anywhere
    everything = {oldest_job, oldest_run, anywhere, newest_run}
    assert next_item(store, taken=everything, host="here") is None


def test_an_empty_queue_has_no_next_item(store: Store) -> None:
    assert waiting(store) == []
    assert next_item(store) is None
