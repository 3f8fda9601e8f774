"""What a job would refuse is refused before the job exists: a recordings upload with a bad
extractor, event detection or name; training under a taken name, from a run without
results, on a target without any known value.  On SQLite, over HTTP."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx

from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff
from touchbench.app.store.database import Store
from touchbench.app.store.tables import RunRow

#: A data set whose second target, place, has no known value.
UNLABELLED_PLACE = """@relation 'half: -C 2'
@attribute gesture {tap, slap}
@attribute place {head, arm}
@attribute f0 numeric
@data
""" + "".join(f"{'tap' if i % 2 else 'slap'},?,{i % 2 + 0.1 * i}\n" for i in range(20))


def _jobs(server: Server) -> list[dict[str, Any]]:
    listing = server.client.get("/api/jobs")
    assert listing.status_code == 200, listing.text
    jobs: list[dict[str, Any]] = listing.json()["jobs"]
    return jobs


def _error(response: httpx.Response, status: int, where: str | None = None) -> str:
    assert response.status_code == status, response.text
    error = response.json()["error"]
    if where is not None:
        assert error["where"] == where, error
    message: str = error["message"]
    return message


def _upload_session(server: Server, **fields: str) -> httpx.Response:
    return server.client.post(
        "/api/datasets/recordings",
        files=[("recordings", ("s1.wav", b"not read before the request is checked"))],
        data=fields,
    )


def test_a_recordings_upload_is_refused_before_any_job(
    sqlite_server: Server, tmp_path: Path
) -> None:
    path = touch_arff(tmp_path / "touch.arff", n=30)
    with path.open("rb") as handle:
        assert sqlite_server.client.post(
            "/api/datasets", files={"file": (path.name, handle)}
        ).is_success

    message = _error(_upload_session(sqlite_server, events="nope"), 422, "body.events")
    assert message.startswith("unknown event detection 'nope' (known: ")
    message = _error(_upload_session(sqlite_server, extractor="nope"), 422, "body.extractor")
    assert message.startswith("unknown extractor 'nope' (known: uc3m-audio, ")
    message = _error(_upload_session(sqlite_server, segment="2"), 422, "body.segment")
    assert message == "only applies to `events` 'none', not 'snr'"
    _error(_upload_session(sqlite_server, samplerate="-5"), 422, "body.samplerate")
    _error(_upload_session(sqlite_server, name="42"), 422, "body.name")
    message = _error(_upload_session(sqlite_server, fields="pdc"), 422, "body.fields")
    assert message == "needs `topic`: the bag topic the fields belong to"
    _error(_upload_session(sqlite_server, sample_format="U8"), 422, "body.sample_format")
    _error(_upload_session(sqlite_server, channels="0"), 422, "body.channels")
    message = _error(_upload_session(sqlite_server, name="touch"), 409)
    assert message.startswith("a dataset named 'touch' already exists (id 1)")

    assert _jobs(sqlite_server) == []
    assert not list((sqlite_server.work_dir / "uploads").glob("*/*")), "an upload was kept"


def test_training_is_refused_before_any_job(sqlite_server: Server, tmp_path: Path) -> None:
    api = sqlite_server.client
    for path in (touch_arff(tmp_path / "touch.arff", n=60), tmp_path / "half.arff"):
        if path.name == "half.arff":
            path.write_text(UNLABELLED_PLACE, encoding="utf-8")
        with path.open("rb") as handle:
            assert api.post("/api/datasets", files={"file": (path.name, handle)}).is_success
    trained = api.post(
        "/api/models",
        json={"dataset": "touch", "classifier": "nb", "target": "gesture", "name": "mine"},
    )
    assert trained.status_code == 202, trained.text
    job = sqlite_server.wait_for(f"/api/jobs/{trained.json()['job']}", finished)
    assert job["status"] == "done", job
    assert job["params"]["name"] == "mine" and job["params"]["target"] == "gesture"

    at = api.post("/api/models", json={"dataset": "touch", "classifier": "nb", "name": "mine@2"})
    assert _error(at, 422, "body.name").startswith("a model name cannot hold '@'")

    store = Store(sqlite_server.database_url)
    try:  # a run that failed before any result (written as failed: no worker takes it)
        with store.session() as session:
            row = RunRow(
                dataset_id=1,
                kind="multi-target",
                targets=["gesture", "place"],
                classifiers=["cc:nb"],
                config={},
                status="failed",
            )
            session.add(row)
            session.flush()
            run_id = row.id
    finally:
        store.dispose()
    empty_run = api.post("/api/models", json={"run": run_id})
    assert _error(empty_run, 409) == f"run {run_id} has no results yet (it is failed)"
    absent_run = api.post("/api/models", json={"run": run_id + 1})
    assert _error(absent_run, 404).startswith(f"no run '{run_id + 1}'")

    unlabelled = api.post(
        "/api/models", json={"dataset": "half", "classifier": "nb", "target": "place"}
    )
    assert _error(unlabelled, 422, "body.target") == (
        "no instance has a known value of the target ('place'): nothing to train on"
    )
    both = api.post("/api/models", json={"dataset": "half", "classifier": "cc:nb"})
    assert _error(both, 422, "body.dataset") == (
        "no instance has a known value of every target ('gesture', 'place'): nothing to train on"
    )
    unknown_target = api.post(
        "/api/models", json={"dataset": "touch", "classifier": "nb", "target": "nope"}
    )
    assert _error(unknown_target, 422, "body.target").startswith(
        "the data set has no attribute 'nope'"
    )
    with_run = api.post("/api/models", json={"run": run_id, "classifier": "nb"})
    assert _error(with_run, 422, "body.classifier").startswith("is not taken with `run`")
    alone = api.post("/api/models", json={"classifier": "nb"})
    assert _error(alone, 422, "body.dataset").startswith("is required")

    assert [job["id"] for job in _jobs(sqlite_server)] == [trained.json()["job"]]
