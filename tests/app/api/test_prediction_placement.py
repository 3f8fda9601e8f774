"""Where a served prediction runs: on the event loop when the model is known to be quick,
in a worker thread otherwise; the same answer either way."""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from tests.support.synthetic import touch_arff
from touchbench.app.api.deps import INLINE_SECONDS, PredictionPlacement, request_size
from touchbench.app.main import create_app
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.services.datasets import import_file
from touchbench.app.services.models import predict_records, train
from touchbench.app.settings import Settings
from touchbench.app.store.database import Store


def test_a_model_runs_inline_only_once_it_is_known_to_be_quick() -> None:
    loaded: dict[str, int] = {}
    placement = PredictionPlacement(loaded.get)
    assert not placement.runs_inline("m", 1)  # not loaded
    loaded.update({"m": 7, "7": 7})
    assert not placement.runs_inline("m", 1)  # loaded, never timed
    placement.record(7, INLINE_SECONDS / 10, 1)
    assert placement.runs_inline("m", 1) and placement.runs_inline("7", 1)
    assert not placement.runs_inline("m", 20)  # twenty times the size: twice the budget
    assert not placement.runs_inline("other", 1)
    for _ in range(5):  # a model that turns slow leaves the loop within a few calls
        placement.record(7, INLINE_SECONDS * 10, 1)
    assert not placement.runs_inline("m", 1)
    for _ in range(20):  # and comes back once quick again
        placement.record(7, INLINE_SECONDS / 10, 1)
    assert placement.runs_inline("m", 1)
    placement.forget(7)
    assert not placement.runs_inline("m", 1)
    placement.close()


def test_a_quick_model_waits_its_turn_in_the_thread_when_another_prediction_is_under_way() -> None:
    placement = PredictionPlacement({"quick": 7, "slow": 8}.get)
    placement.record(7, INLINE_SECONDS / 10, 1)
    placement.record(8, INLINE_SECONDS * 10, 1)

    def where() -> int:
        time.sleep(0.05)
        return threading.get_ident()

    async def both() -> tuple[int, int, int]:
        slow, quick = await asyncio.gather(
            placement.run("slow", 1, where), placement.run("quick", 1, where)
        )
        alone = await placement.run("quick", 1, where)
        return slow, quick, alone

    loop_thread = threading.get_ident()
    slow, quick, alone = asyncio.run(both())
    placement.close()
    assert slow != loop_thread and quick == slow  # both in the one prediction thread
    assert alone == loop_thread  # alone, the quick model runs on the loop


@pytest.fixture
def client(tmp_path: Path, store_url: str) -> Iterator[TestClient]:
    store = Store(store_url)
    import_file(
        store,
        ImportRequest(file=touch_arff(tmp_path / "touch.arff", with_place=False), name="touch"),
    )
    train(store, TrainRequest(dataset="touch", classifier="nb", target="gesture", name="quick"))
    store.dispose()
    settings = Settings(database_url=store_url, work_dir=tmp_path / "work")
    with TestClient(create_app(settings), base_url="http://localhost") as test_client:
        yield test_client


def test_the_first_prediction_runs_in_a_thread_and_later_ones_on_the_loop(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    service = client.app.state.service  # type: ignore[attr-defined]
    threads: list[int] = []
    record = service.placement.record

    def spy(model_id: int, seconds: float, size: int) -> None:
        """Where the call ran; the time recorded as a tenth of the budget per unit of size
        (an instance of five values is six), so that the placement does not depend on this
        machine's load."""
        threads.append(threading.get_ident())
        record(model_id, size * INLINE_SECONDS / 10, size)

    monkeypatch.setattr(service.placement, "record", spy)
    instance = {"f0": 0.1, "f1": -0.2, "f2": 0.3, "f3": None, "mic": "left"}
    answers = [
        client.post("/api/models/quick/predict", json={"instances": [instance]}) for _ in range(3)
    ]
    assert [answer.status_code for answer in answers] == [200, 200, 200]
    assert answers[0].json() == answers[2].json()
    loop_thread = threads[-1]
    assert threads[0] != loop_thread and threads[1] == loop_thread  # a thread, then the loop
    expected = predict_records(service.store, "quick", [instance]).to_json()
    assert answers[2].json() == expected
    assert answers[2].headers["content-type"] == "application/json"
    many = client.post("/api/models/quick/predict", json={"instances": [instance] * 5000})
    assert many.status_code == 200 and len(many.json()["predictions"]) == 5000
    assert threads[-1] != loop_thread  # five thousand instances are not quick
    client.post("/api/models/quick/predict", json={"instances": [instance]})
    assert threads[-1] == loop_thread
    junk = {**instance, **{f"unknown{i}": 1.0 for i in range(1000)}}
    one = client.post("/api/models/quick/predict", json={"instances": [junk]})
    assert one.status_code == 200 and len(one.json()["predictions"]) == 1
    assert threads[-1] != loop_thread  # one instance, but a thousand values: not quick


def test_a_request_is_as_large_as_its_instances_and_values() -> None:
    assert request_size([]) == 0
    assert request_size([{}, {}]) == 2  # empty instances still cost a row each
    assert request_size([{"a": 1, "b": None}, {"c": "x"}]) == 5


def test_an_unknown_model_is_a_404_on_either_path(client: TestClient) -> None:
    client.post("/api/models/quick/predict", json={"instances": [{"f0": 1.0}]})
    client.post("/api/models/quick/predict", json={"instances": [{"f0": 1.0}]})
    answer = client.post("/api/models/nothing/predict", json={"instances": [{"f0": 1.0}]})
    assert answer.status_code == 404
    assert "no model 'nothing'" in answer.json()["error"]["message"]
