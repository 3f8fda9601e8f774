"""ONNX twins on a real service, on SQLite and PostgreSQL: made by a job (one per model at a
time, whoever asks at once), never inside a GET; a read key reads and writes nothing; a
stored twin that cannot be loaded is reported and not served."""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx
import pytest
from sqlalchemy import create_engine, text

from tests.support.rows import count_rows
from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.services.datasets import import_file
from touchbench.app.services.models import train
from touchbench.app.store.database import Store

WRITE = "lab-write-key-0123456789"
READ = "viewer-read-key-0123456789"


@pytest.fixture
def tree(store_url: str, tmp_path: Path) -> str:
    """The test's store, holding the data set ``touch`` and the model ``tree`` (cart: a
    twin is made and served as a forest's is, at a fraction of its cost)."""
    store = Store(store_url)
    try:
        arff = touch_arff(tmp_path / "touch.arff", n=60, with_place=False)
        import_file(store, ImportRequest(file=arff, name="touch"))
        train(store, TrainRequest(dataset="touch", classifier="cart", name="tree"))
    finally:
        store.dispose()
    return store_url


@pytest.mark.slow
def test_requests_at_once_make_one_twin_by_one_job_and_a_get_writes_nothing(
    tree: str, make_server: Callable[..., Server]
) -> None:
    server = make_server(api_key=WRITE, api_keys=f"viewer:read:{READ}", job_workers="1")
    reader = httpx.Client(base_url=server.url, headers={"X-API-Key": READ}, timeout=60)
    missing = reader.get("/api/models/tree/onnx")
    assert missing.status_code == 404, missing.text
    assert "has no ONNX twin yet; POST /api/models/tree/onnx makes it (a job)" in missing.text
    assert reader.post("/api/models/tree/onnx").status_code == 403
    assert count_rows(tree, "model_exports") == count_rows(tree, "jobs") == 0

    no_converter = server.client.post(
        "/api/models", json={"dataset": "touch", "classifier": "gate", "onnx": True}
    )
    assert no_converter.status_code == 422, no_converter.text
    assert no_converter.json()["error"]["where"] == "body.onnx"
    assert "classifier 'gate' has no ONNX converter" in no_converter.text

    # the one worker busy with a training held at the gate: the export waits, queued
    assert server.gate is not None
    held = server.client.post(
        "/api/models", json={"dataset": "touch", "classifier": "gate", "name": "held"}
    )
    assert held.status_code == 202, held.text
    server.gate.wait_started(1)
    with ThreadPoolExecutor(3) as clients:
        answers = list(clients.map(lambda _: server.client.post("/api/models/tree/onnx"), "abc"))
    assert [answer.status_code for answer in answers] == [202] * 3, answers[0].text
    (job,) = {answer.json()["job"] for answer in answers}
    assert answers[0].json()["kind"] == "export"
    under_way = reader.get("/api/models/tree/onnx")
    assert under_way.status_code == 409, under_way.text
    assert f"being made by job {job}; GET /api/jobs/{job} says when it is done" in under_way.text

    server.gate.open()
    done = server.wait_for(f"/api/jobs/{job}", finished)
    assert done["status"] == "done", done
    kinds = sorted(j["kind"] for j in server.client.get("/api/jobs").json()["jobs"])
    assert kinds == ["export", "train"]  # one conversion for the three requests
    graph = reader.get("/api/models/tree/onnx")
    assert graph.status_code == 200, graph.text
    twin = reader.get("/api/models/tree").json()["onnx"]
    assert twin == {
        "format": "onnx",
        "sha256": hashlib.sha256(graph.content).hexdigest(),
        "size_bytes": len(graph.content),
        "problem": None,
    }
    assert done["result"]["sha256"] == twin["sha256"]
    instance = {"f0": 0.1, "f1": -0.2, "f2": 0.3, "f3": None, "mic": "left"}
    onnx = server.client.post(
        "/api/models/tree/predict", json={"instances": [instance], "engine": "onnx"}
    )
    assert onnx.status_code == 200 and onnx.json()["warnings"] == [], onnx.text
    reader.close()


def test_a_twin_that_cannot_be_loaded_is_reported_and_not_served(
    tree: str, make_server: Callable[..., Server]
) -> None:
    """Garbage bytes whose digest matches: ``auto`` predictions fall back to the model
    itself, with a warning in each answer and one in the log; the model's JSON says why;
    ``engine: onnx`` is refused naming the problem; never a 500."""
    garbage = b"not an onnx graph"
    engine = create_engine(tree.replace("postgresql://", "postgresql+psycopg://", 1))
    with engine.begin() as connection:
        connection.execute(
            text(
                "INSERT INTO model_exports (model_id, format, sha256, size_bytes, created_at, "
                "data) SELECT id, 'onnx', :s, :n, created_at, :d FROM models"
            ),
            {"s": hashlib.sha256(garbage).hexdigest(), "n": len(garbage), "d": garbage},
        )
    engine.dispose()
    server = make_server()
    instance = {"f0": 0.1, "f1": -0.2, "f2": 0.3, "f3": None, "mic": "left"}
    native = server.client.post(
        "/api/models/tree/predict", json={"instances": [instance], "engine": "native"}
    )
    assert native.status_code == 200, native.text
    for _ in range(3):
        auto = server.client.post("/api/models/tree/predict", json={"instances": [instance]})
        assert auto.status_code == 200, auto.text
        assert auto.json()["predictions"] == native.json()["predictions"]
        (warning,) = auto.json()["warnings"]
        assert "its ONNX twin cannot be loaded (" in warning and "INVALID_PROTOBUF" in warning
    problem = server.client.get("/api/models/tree").json()["onnx"]["problem"]
    assert "INVALID_PROTOBUF" in problem
    refused = server.client.post(
        "/api/models/tree/predict", json={"instances": [instance], "engine": "onnx"}
    )
    assert refused.status_code == 422, refused.text
    assert refused.json()["error"]["where"] == "body.engine"
    assert "its ONNX twin cannot be loaded" in refused.json()["error"]["message"]
    assert server.log is not None
    logged = server.log.read_text()
    assert logged.count("its ONNX twin cannot be loaded") == 1, logged[-2000:]
