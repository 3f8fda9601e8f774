"""A job carries its typed request: stored as the request's JSON, rebuilt and carried out by
``execute_job``; params that are not a request of the job's kind fail the job, saying so.
On SQLite and PostgreSQL."""

from __future__ import annotations

import socket
import time
from pathlib import Path
from typing import Any

import pytest

from tests.support.synthetic import touch_arff
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.services import jobs
from touchbench.app.services.datasets import import_file
from touchbench.app.services.jobs import execute_job, job_request, submit_training
from touchbench.app.store.database import Store
from touchbench.app.store.jobs import create_job, list_jobs
from touchbench.app.store.models import list_models
from touchbench.app.store.queue import CANCEL_POLL


@pytest.fixture
def store(store_url: str, tmp_path: Path) -> Store:
    store = Store(store_url)
    import_file(store, ImportRequest(file=touch_arff(tmp_path / "touch.arff", n=60)))
    return store


def test_a_training_job_holds_its_request_and_carries_it_out(store: Store) -> None:
    request = TrainRequest(dataset="touch", classifier="nb", target="gesture", name="quick")
    job = submit_training(store, request)
    assert job.params == {**request.model_dump(mode="json"), "host": socket.gethostname()}
    assert job_request(job) == request
    done = execute_job(store, job.id)
    assert done is not None and done.status == "done", done
    assert done.result is not None and done.result["name"] == "quick"
    assert [(m.name, m.targets) for m in list_models(store)] == [("quick", ["gesture"])]

    again = execute_job(store, submit_training(store, request).id)  # a taken name: a version
    assert again is not None and again.status == "done", again
    assert [(m.name, m.version) for m in list_models(store)] == [("quick", 1), ("quick", 2)]
    assert len(list_jobs(store)) == 2


def test_params_that_are_not_a_request_fail_the_job(store: Store) -> None:
    job = create_job(store, "train", {"dataset": "touch", "classifier": "nb", "folds": 3})
    failed = execute_job(store, job.id)
    assert failed is not None and failed.status == "failed"
    assert failed.error is not None
    assert failed.error == (
        f"job {job.id} does not hold a valid train request (folds: Extra inputs are not permitted)"
    )
    assert list_models(store) == []


def test_a_job_that_ends_is_not_taken_for_a_cancel(
    store: Store, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The heartbeat looks for a cancel until it is stopped; a job it sees over (recorded
    ``done`` by its own work) is not one.  The end is held for a few of the heartbeat's
    looks, as a slow store or a busy machine holds it."""
    monkeypatch.setattr(jobs, "_carry_out", lambda *args, **kwargs: {"answer": 42})
    finish = jobs._Stopper.finish

    def slow_finish(self: Any, status: str, **values: Any) -> None:
        finish(self, status, **values)
        time.sleep(5 * CANCEL_POLL)

    monkeypatch.setattr(jobs._Stopper, "finish", slow_finish)
    request = TrainRequest(dataset="touch", classifier="nb", target="gesture")
    try:
        done = execute_job(store, submit_training(store, request).id)
        time.sleep(5 * CANCEL_POLL)  # an interrupt sent late lands here
    except KeyboardInterrupt:
        pytest.fail("the job's own end was taken for a cancel: the main thread was interrupted")
    assert done is not None and (done.status, done.result) == ("done", {"answer": 42})
