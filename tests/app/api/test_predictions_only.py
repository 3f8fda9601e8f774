"""``touchbench serve --predictions-only`` beside a full service on the same store (issue 36):
the robots' side (models listed and described, predictions over REST, of a file and over
the live WebSocket) answers as the full service does and follows its alias moves; every
other route is refused without touching the store; it neither dispatches jobs nor
recovers or resumes runs, which stay the full service's."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx
import pytest

import touchbench
from tests.support.live import pcm_blocks, stream, ws_url
from tests.support.recordings import extract_sessions
from tests.support.service import Server
from tests.support.synthetic import touch_arff
from touchbench.app.jobs.dispatcher import POLL, dispatch_address
from touchbench.app.jobs.leadership import Leadership
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.schemas.runs import BenchRequest
from touchbench.app.schemas.status import Status
from touchbench.app.services.datasets import import_file
from touchbench.app.services.models import train
from touchbench.app.services.runs import create_run
from touchbench.app.services.simulation import write_session
from touchbench.app.store.database import Store
from touchbench.app.store.runs import finish_run, get_run

KEY = "split-key-of-the-lab"
PREDICTIONS_ONLY = ("--predictions-only",)


def _sessions_model(store: Store, folder: Path) -> Path:
    """Models ``pin@1`` (``cc:j48``) and ``pin@2`` (``cc:nb``) of extracted sessions; a
    session they never saw."""
    extract_sessions(store, folder, sessions=3, touches=8)
    for classifier in ("cc:j48", "cc:nb"):
        train(store, TrainRequest(dataset="touch", classifier=classifier, name="pin"))
    unseen, _ = write_session(folder, "unseen", n_touches=5, seed=99)
    return unseen


def _predict_file(server: Server, ref: str, path: Path) -> dict[str, Any]:
    with path.open("rb") as handle:
        answer = server.client.post(
            f"/api/models/{ref}/predict/file", files={"file": (path.name, handle)}
        )
    assert answer.status_code == 200, answer.text
    body: dict[str, Any] = answer.json()
    return body


def _instance(server: Server, ref: str) -> dict[str, float]:
    """One instance of the model's own attributes (zeros)."""
    model = server.client.get(f"/api/models/{ref}")
    assert model.status_code == 200, model.text
    return dict.fromkeys(model.json()["features"], 0.0)


def test_the_robots_side_answers_as_the_full_service_and_follows_its_aliases(
    make_server: Callable[..., Server], store_url: str, tmp_path: Path
) -> None:
    store = Store(store_url)
    try:
        unseen = _sessions_model(store, tmp_path)
    finally:
        store.dispose()
    full = make_server(api_key=KEY)
    robots = make_server(api_key=KEY, arguments=PREDICTIONS_ONLY)

    assert httpx.get(f"{robots.url}/api/models").status_code == 401  # the same keys
    assert robots.client.get("/healthz").json()["status"] == "ok"
    listed = robots.client.get("/api/models")
    assert listed.status_code == 200 and listed.headers["x-total-count"] == "2"
    assert full.client.post("/api/models/pin@1/promote").status_code == 200
    instance = {"instances": [_instance(robots, "pin@champion")]}
    said = robots.client.post("/api/models/pin@champion/predict", json=instance)
    assert said.status_code == 200 and said.json()["model"] == "pin@1", said.text

    # the full service moves the alias; the robots' process answers with the new version
    assert full.client.post("/api/models/pin@2/promote").status_code == 200
    said = robots.client.post("/api/models/pin@champion/predict", json=instance)
    assert said.status_code == 200 and said.json()["model"] == "pin@2", said.text
    assert said.json() == full.client.post("/api/models/pin@2/predict", json=instance).json()

    # a file, and a stream over the live WebSocket: what the full service answers
    assert _predict_file(robots, "pin@1", unseen) == _predict_file(full, "pin@1", unseen)
    rate, channels, blocks = pcm_blocks(unseen)
    header = {"samplerate": rate, "channels": channels, "format": "S16LE", "api_key": KEY}
    streamed = [stream(ws_url(server, "pin@1"), header, blocks) for server in (robots, full)]
    (messages, code, reason), (expected, _, _) = streamed
    assert (code, reason) == (1000, "stream ended") and len(messages) == 5

    def without_latency(touches: list[dict[str, Any]]) -> list[dict[str, Any]]:
        return [{k: v for k, v in touch.items() if k != "latency_ms"} for touch in touches]

    assert without_latency(messages) == without_latency(expected)

    # touchbench.Client pointed at it: the robots' methods work, the others say why not
    with touchbench.Client(robots.url, api_key=KEY) as client:
        assert [model.version for model in client.models()] == [1, 2]
        assert client.predict("pin@1", instance["instances"]).model == "pin@1"
        with pytest.raises(touchbench.ServiceError, match="is not served here"):
            client.datasets()


#: Requests only the full service answers: each changes the store, queues work or shows
#: what robots do not need.
MANAGEMENT = [
    ("POST", "/api/models", {"dataset": "touch", "classifier": "cc:nb", "name": "pin"}),
    ("POST", "/api/models/pin@1/aliases", {"alias": "champion"}),
    ("POST", "/api/models/pin@1/promote", None),
    ("POST", "/api/models/pin/rollback", None),
    ("DELETE", "/api/models/pin@1/aliases/champion", None),
    ("POST", "/api/models/pin@1/onnx", None),
    ("GET", "/api/datasets", None),
    ("POST", "/api/runs", {"dataset": "touch", "target": "gesture", "classifiers": ["nb"]}),
    ("GET", "/api/jobs", None),
    ("GET", "/api/extractors", None),
    ("GET", "/", None),
    ("GET", "/fragments/models", None),
]


def test_every_other_route_is_refused_and_nothing_changes(
    make_sqlite_server: Callable[..., Server], sqlite_store_url: str, tmp_path: Path
) -> None:
    store = Store(sqlite_store_url)
    try:
        _sessions_model(store, tmp_path)
    finally:
        store.dispose()
    full = make_sqlite_server(api_key=KEY)
    assert full.client.post("/api/models/pin@1/promote").status_code == 200
    robots = make_sqlite_server(api_key=KEY, arguments=PREDICTIONS_ONLY)
    before = full.client.get("/api/models").json()

    # "/api/models" and "/api/models/pin@1" are served for GET here: another method too is
    # answered as not served, not "Method Not Allowed"
    for method, path, body in [*MANAGEMENT, ("DELETE", "/api/models/pin@1", None)]:
        answer = robots.client.request(method, path, json=body)
        assert answer.status_code == 404, (method, path, answer.status_code, answer.text)
        message = answer.json()["error"]["message"]
        assert message.startswith(f"{method} {path} is not served here"), message
        assert "--predictions-only" in message, message

    # the full service's guards stand in front of its prediction routes too
    foreign = robots.client.post(
        "/api/models/pin@1/predict", json={"instances": []}, headers={"Origin": "http://evil.test"}
    )
    assert foreign.status_code == 403 and "evil.test" in foreign.json()["error"]["message"]
    rebound = robots.client.get("/api/models", headers={"Host": "evil.test"})
    assert rebound.status_code == 400, rebound.text
    zeros = robots.client.post(
        "/api/models/pin@1/predict",
        content=bytes(17 * 2**20),
        headers={"Content-Type": "application/json"},
    )
    assert zeros.status_code == 413, zeros.text

    assert full.client.get("/api/models").json() == before
    assert full.client.get("/api/jobs").headers["x-total-count"] == "0"
    documented = set(robots.client.get("/openapi.json").json()["paths"])
    assert documented == {
        "/healthz",
        "/api/models",
        "/api/models/{model_ref}",
        "/api/models/{model_ref}/onnx",
        "/api/models/{model_ref}/predict",
        "/api/models/{model_ref}/predict/file",
    }


def test_it_neither_dispatches_nor_recovers_runs(
    make_sqlite_server: Callable[..., Server], sqlite_store_url: str, tmp_path: Path
) -> None:
    store = Store(sqlite_store_url)
    try:
        import_file(store, ImportRequest(file=touch_arff(tmp_path / "t.arff", n=60), name="t"))
        request = BenchRequest(dataset="t", target="gesture", classifiers=["nb"], folds=2)
        lost = create_run(store, request).id
        finish_run(store, lost, Status.RUNNING)  # as a killed process leaves it: no owner
        queued = create_run(store, request).id

        robots = make_sqlite_server(resume_on_start="1", arguments=PREDICTIONS_ONLY)
        time.sleep(4 * POLL)  # a dispatcher would have taken the address and the run by now
        assert get_run(store, lost).status == Status.RUNNING  # neither marked lost nor resumed
        assert get_run(store, queued).status == Status.QUEUED  # not dispatched
        leadership = Leadership(dispatch_address(store), "the test")
        try:
            assert leadership.leading is False and leadership.dispatches(), (
                "the predictions-only process holds the store's dispatch address"
            )
        finally:
            leadership.release()
        assert robots.client.get("/healthz").status_code == 200

        full = make_sqlite_server(resume_on_start="1")  # the full service takes both
        for run in (queued, lost):
            assert full.wait_for(f"/api/runs/{run}", _ended)["status"] == "done"
    finally:
        store.dispose()


def _ended(body: dict[str, Any]) -> bool:
    return body["status"] in {"done", "failed", "cancelled"}
