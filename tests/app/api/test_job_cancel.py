"""Jobs follow the runs' queue protocol: a cancel over HTTP stops a running job within its
heartbeat's look (or its grace for work in native code), a queued one at once; a finished
job refuses it (409); a lost process leaves a cancelling job cancelled."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest
from sqlalchemy import update

from tests.support.cli_runner import run_cli
from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff
from touchbench.app.errors import ConflictError
from touchbench.app.store.database import Store
from touchbench.app.store.jobs import (
    claim_job,
    create_job,
    finish_job,
    get_job,
    mark_lost_jobs,
    request_job_cancel,
)
from touchbench.app.store.tables import JobRow


def _training(
    capsys: pytest.CaptureFixture[str], server: Server, path: Path, classifier: str
) -> int:
    imported = run_cli(capsys, server.database_url, "import", str(touch_arff(path, n=60)))
    assert imported.code == 0, imported.err
    started = server.client.post(
        "/api/models", json={"dataset": "t", "classifier": classifier, "target": "gesture"}
    )
    assert started.status_code == 202, started.text
    return int(started.json()["job"])


@pytest.mark.parametrize("classifier", ["gate", "gate-stubborn"])
@pytest.mark.slow
def test_a_running_job_is_cancelled_over_http(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path, classifier: str
) -> None:
    job_id = _training(capsys, server, tmp_path / "t.arff", classifier)
    assert server.gate is not None
    server.gate.wait_started(1)  # the job's fit waits at the gate: it is running
    asked = server.client.post(f"/api/jobs/{job_id}/cancel")
    assert (asked.status_code, asked.json()["status"]) == (200, "cancelling"), asked.text
    # a stubborn fit (native code) does not hear the interrupt: its process ends it
    job = server.wait_for(f"/api/jobs/{job_id}", finished, timeout=120)
    assert (job["status"], job["result"]) == ("cancelled", None)
    assert server.client.get("/api/models").json()["models"] == []
    again = server.client.post(f"/api/jobs/{job_id}/cancel")
    assert again.status_code == 409 and again.json()["error"]["type"] == "ConflictError"
    assert "already cancelled" in again.json()["error"]["message"]


def test_a_queued_job_is_cancelled_at_once_and_a_finished_one_refuses(store: Store) -> None:
    queued = create_job(store, "train", {})
    assert request_job_cancel(store, queued.id).status == "cancelled"
    assert not claim_job(store, queued.id)  # nobody takes a cancelled job
    done = create_job(store, "train", {})
    assert claim_job(store, done.id, owner="elsewhere:1@1")
    finish_job(store, done.id, "done", result={})
    with pytest.raises(ConflictError, match=f"job {done.id} is already done"):
        request_job_cancel(store, done.id)


@pytest.mark.parametrize(("asked", "left"), [(False, "interrupted"), (True, "cancelled")])
def test_a_lost_process_leaves_its_job_interrupted_or_cancelled(
    store: Store, asked: bool, left: str
) -> None:
    job = create_job(store, "train", {})
    gone = f"{socket.gethostname()}:{2**22 + 7}@1"  # no process of this host has that pid
    assert claim_job(store, job.id, owner=gone)
    if asked:
        with store.session() as session:
            session.execute(update(JobRow).values(status="cancelling", cancel_requested=True))
    assert mark_lost_jobs(store) == [job.id]
    assert get_job(store, job.id).status == left
    with pytest.raises(ConflictError, match=f"job {job.id} is already {left}"):
        request_job_cancel(store, job.id)
