"""The direct prediction route answers what FastAPI's own handling of the same endpoint
answers (reports, errors and their places, the API key), and refuses, when it is built, an
endpoint asking for what it cannot provide."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Annotated, Any

import httpx
import pytest
from fastapi import APIRouter, Depends, Header, Response
from fastapi.testclient import TestClient
from pydantic import SecretStr

from tests.support.synthetic import touch_arff
from touchbench.app.api.deps import ServiceDep, StoreDep, require_api_key
from touchbench.app.api.direct import DirectRoute
from touchbench.app.api.routes.models import predict_instances
from touchbench.app.main import create_app
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.models import PredictionReport, PredictRequest, TrainRequest
from touchbench.app.services.datasets import import_file
from touchbench.app.services.models import train
from touchbench.app.settings import Settings
from touchbench.app.store.database import Store

DIRECT = "/api/models/{model}/predict"
THROUGH_FASTAPI = "/fastapi/models/{model}/predict"
KEY = "k3y-of-the-lab-2026"


@pytest.fixture
def client(tmp_path: Path) -> Iterator[TestClient]:
    """The service with a model ``touch-nb``, and the prediction endpoint mounted a second
    time as a plain FastAPI route."""
    url = f"sqlite:///{tmp_path / 'touchbench.db'}"
    store = Store(url)
    import_file(store, ImportRequest(file=touch_arff(tmp_path / "touch.arff"), name="touch"))
    train(store, TrainRequest(dataset="touch", classifier="bcc:nb", name="touch-nb"))
    store.dispose()
    settings = Settings(database_url=url, work_dir=tmp_path / "work", api_key=SecretStr(KEY))
    app = create_app(settings)
    app.add_api_route(
        THROUGH_FASTAPI.replace("{model}", "{model_ref}"),
        predict_instances,
        methods=["POST"],
        response_model=PredictionReport,
        dependencies=[Depends(require_api_key)],
    )
    with TestClient(app, base_url="http://localhost", headers={"X-API-Key": KEY}) as test_client:
        yield test_client


def _both(client: TestClient, model: str, **request: Any) -> tuple[httpx.Response, httpx.Response]:
    direct = client.post(DIRECT.format(model=model), **request)
    plain = client.post(THROUGH_FASTAPI.format(model=model), **request)
    return direct, plain


def test_predictions_are_the_same_as_through_fastapi(client: TestClient) -> None:
    instances = [
        {"f0": 0.1, "f1": 2.0, "f2": -0.3, "f3": 1.0, "mic": "left"},
        {"f0": 4.2, "f1": None, "f2": 0.0, "f3": 7, "mic": "both", "unused": "x"},
        {"f0": 2.0},
    ]
    for model in ("touch-nb", "1"):
        direct, plain = _both(client, model, json={"instances": instances, "missing": "allow"})
        assert direct.status_code == plain.status_code == 200, direct.text
        assert direct.json() == plain.json()
        report = PredictionReport.model_validate(direct.json())
        assert (len(report.predictions), report.targets) == (3, ["gesture", "place"])


@pytest.mark.parametrize(
    ("body", "headers"),
    [
        ({"instances": []}, None),
        ({}, None),
        ({"instances": [{"f0": [1]}]}, None),
        ({"instances": [{"f0": {"nested": 1}}]}, None),
        ({"instances": [{"f0": 1}], "extra": True}, None),
        ({"instances": [{"f0": 1}] * 10_001}, None),
        ({"instances": "f0=1"}, None),
        ([{"f0": 1}], None),
        ({"instances": [{"f0": 1}]}, {"Content-Type": "text/plain"}),
        ({"instances": [{"f0": 1}]}, {"Content-Type": "application/x-www-form-urlencoded"}),
        ({"instances": [{"f0": 1e308 * 10}], "missing": "allow"}, None),  # the service's 400
        ({"instances": [{"f0": "not a number"}], "missing": "allow"}, None),
        ({"instances": [{"f0": 1}]}, None),  # f1, f2, f3 and mic left out: the service's 422
    ],
)
def test_bad_bodies_are_answered_as_through_fastapi(
    client: TestClient, body: object, headers: dict[str, str] | None
) -> None:
    content = json.dumps(body)
    direct, plain = _both(
        client,
        "touch-nb",
        content=content,
        headers=headers or {"Content-Type": "application/json"},
    )
    assert 400 <= direct.status_code < 500, direct.text
    assert direct.status_code == plain.status_code, (direct.text, plain.text)
    assert direct.json()["error"]["where"] == plain.json()["error"]["where"]
    assert direct.json()["error"]["type"] == plain.json()["error"]["type"]


def test_what_is_not_json_or_not_a_model_is_a_4xx_either_way(client: TestClient) -> None:
    for content in (b"{", b"", b"\xff\xfe", b"[" * 5000 + b"]" * 5000):
        direct, plain = _both(
            client, "touch-nb", content=content, headers={"Content-Type": "application/json"}
        )
        assert direct.status_code == 422, direct.text
        assert direct.json()["error"]["where"].startswith("body")
        assert 400 <= plain.status_code < 500
    direct, plain = _both(client, "no-such-model", json={"instances": [{"f0": 1}]})
    assert direct.status_code == plain.status_code == 404
    assert direct.json() == plain.json()


def test_the_api_key_is_checked_as_on_every_route(client: TestClient) -> None:
    body = {"instances": [{"f0": 1}]}
    for headers, status in (({"X-API-Key": ""}, 403), ({"X-API-Key": "wrong"}, 403)):
        direct, plain = _both(client, "touch-nb", json=body, headers=headers)
        assert direct.status_code == plain.status_code == status
        assert direct.json() == plain.json()
    del client.headers["X-API-Key"]
    direct, plain = _both(client, "touch-nb", json=body)
    assert direct.status_code == plain.status_code == 401
    assert direct.json() == plain.json()
    assert direct.headers["WWW-Authenticate"] == "X-API-Key"


def _sync(model_ref: str, body: PredictRequest, service: ServiceDep) -> Response:
    raise NotImplementedError


async def _unsupported_query(model_ref: str, body: PredictRequest, limit: int = 1) -> Response:
    raise NotImplementedError


async def _unsupported_header(
    model_ref: str, body: PredictRequest, x_trace: Annotated[str, Header()]
) -> Response:
    raise NotImplementedError


async def _unsupported_dependency(
    model_ref: str, body: PredictRequest, store: StoreDep
) -> Response:
    raise NotImplementedError


async def _unsupported_path_type(model_ref: int, body: PredictRequest) -> Response:
    raise NotImplementedError


async def _no_body(model_ref: str, service: ServiceDep) -> Response:
    raise NotImplementedError


async def _supported(model_ref: str, body: PredictRequest, service: ServiceDep) -> Response:
    raise NotImplementedError


@pytest.mark.parametrize(
    ("endpoint", "problem"),
    [
        (_sync, "must be async"),
        (_unsupported_query, "query"),
        (_unsupported_header, "header"),
        (_unsupported_dependency, "cannot provide the dependency"),
        (_unsupported_path_type, "must be a str"),
        (_no_body, "exactly one body"),
    ],
)
def test_a_direct_route_refuses_what_it_cannot_provide(
    endpoint: Callable[..., Any], problem: str
) -> None:
    router = APIRouter(route_class=DirectRoute)
    with pytest.raises(TypeError, match=problem):
        router.post("/m/{model_ref}/predict")(endpoint)
    router.post("/m/{model_ref}/predict")(_supported)  # what the prediction route asks


def test_the_upload_limit_holds_on_the_direct_route(tmp_path: Path) -> None:
    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'touchbench.db'}",
        work_dir=tmp_path / "work",
        max_upload_mb=0.001,
    )
    with TestClient(create_app(settings), base_url="http://localhost") as small:
        answer = small.post(
            DIRECT.format(model="any"), json={"instances": [{f"a{i}": 1.0 for i in range(200)}]}
        )
    assert answer.status_code == 413, answer.text
    assert answer.json()["error"]["where"] == "body"
