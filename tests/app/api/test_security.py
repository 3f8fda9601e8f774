"""The API key, loopback-only without one, and the OpenAPI document: schemathesis finds no
server error and no answer that breaks its own schema."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server
from tests.support.synthetic import touch_arff


def test_the_api_key_guards_everything_but_health_and_docs(
    make_sqlite_server: Callable[..., Server],
) -> None:
    server = make_sqlite_server(api_key="s3cret-key-of-the-lab")
    bare = httpx.Client(base_url=server.url, timeout=30)
    try:
        assert bare.get("/healthz").status_code == 200
        assert bare.get("/openapi.json").status_code == 200
        assert bare.get("/docs").status_code == 200
        missing = bare.get("/api/runs")
        assert missing.status_code == 401 and missing.json()["error"]["type"] == "Unauthorized"
        wrong = bare.get("/api/datasets", headers={"X-API-Key": "s3cret-key-of-the-lac"})
        assert wrong.status_code == 403 and wrong.json()["error"]["type"] == "Forbidden"
        assert bare.post("/api/runs", json={"dataset": "x"}).status_code == 401
        # Every operation the OpenAPI document lists, the direct prediction route included.
        operations = bare.get("/openapi.json").json()["paths"]
        for path, methods in operations.items():
            for method in set(methods) - ({"get"} if path == "/healthz" else set()):
                answer = bare.request(method.upper(), re.sub(r"\{\w+\}", "1", path))
                assert answer.status_code == 401, (method, path, answer.text)
        assert "/api/models/{model_ref}/predict" in operations
    finally:
        bare.close()
    assert server.client.get("/api/runs").status_code == 200  # the client sends the key


def test_serve_listens_beyond_loopback_only_with_a_key(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("TOUCHBENCH_API_KEY", raising=False)
    url = f"sqlite:///{tmp_path / 's.db'}"
    refused = run_cli(capsys, url, "serve", "--host", "0.0.0.0")
    assert refused.code == 2
    assert "TOUCHBENCH_API_KEY is not set" in refused.err and "--insecure" in refused.err


def test_openapi_describes_every_route_with_models(sqlite_server: Server) -> None:
    document = sqlite_server.client.get("/openapi.json").json()
    paths = document["paths"]
    for path in (
        "/healthz",
        "/api/datasets",
        "/api/datasets/{dataset}",
        "/api/datasets/{dataset}/arff",
        "/api/datasets/recordings",
        "/api/runs",
        "/api/runs/{run_id}",
        "/api/runs/{run_id}/cancel",
        "/api/runs/{run_id}/resume",
        "/api/runs/{run_id}/leaderboard",
        "/api/models",
        "/api/models/{model_ref}",
        "/api/models/{model_ref}/predict",
        "/api/models/{model_ref}/predict/file",
        "/api/jobs/{job_id}",
    ):
        assert path in paths, path
    for path, operations in paths.items():
        for method, operation in operations.items():
            answers = operation["responses"]
            success = next(code for code in answers if code.startswith("2"))
            assert "content" in answers[success], (method, path)
            if path.startswith("/api/"):
                assert {"404", "422"} <= set(answers), (method, path)


@pytest.mark.slow
def test_schemathesis_finds_no_server_error(
    capsys: pytest.CaptureFixture[str], sqlite_server: Server, tmp_path: Path
) -> None:
    import schemathesis
    from hypothesis import HealthCheck, Phase, settings
    from schemathesis.checks import (
        content_type_conformance,
        not_a_server_error,
        response_schema_conformance,
    )

    run_cli(capsys, sqlite_server.database_url, "import", str(touch_arff(tmp_path / "touch.arff")))
    run_cli(capsys, sqlite_server.database_url, "train", "touch", "-c", "nb", "--target", "gesture")
    schema = schemathesis.openapi.from_url(f"{sqlite_server.url}/openapi.json")
    failures: list[str] = []
    checks = (not_a_server_error, response_schema_conformance, content_type_conformance)
    for operation in schema.get_all_operations():
        api_operation = operation.ok()

        @settings(
            max_examples=12,
            deadline=None,
            phases=[Phase.explicit, Phase.generate],
            suppress_health_check=list(HealthCheck),
            database=None,
        )
        def exercise(case: schemathesis.Case) -> None:
            try:
                case.call_and_validate(checks=checks, timeout=60)
            except Exception as failure:  # collected, so that one report lists all
                failures.append(f"{case.method} {case.path}: {str(failure)[:400]}")

        strategy = api_operation.as_strategy()
        from hypothesis import given

        given(strategy)(exercise)()
    assert not failures, "\n".join(failures[:10])


def test_references_that_no_row_can_have_are_404_on_both_stores(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    # "²" passes str.isdigit but not int(); "١" (Arabic-Indic one) passes int() as 1.
    run_cli(capsys, server.database_url, "import", str(touch_arff(tmp_path / "touch.arff")))
    run_cli(capsys, server.database_url, "train", "touch", "-c", "nb", "--target", "gesture")
    api = server.client
    for method, path in (
        ("GET", "/api/datasets/%C2%B3/arff"),
        ("GET", "/api/datasets/%D9%A1"),
        ("DELETE", "/api/models/%C2%B2"),
        ("POST", "/api/models/%D9%A1/predict"),
        ("GET", "/api/datasets/a%00b"),  # PostgreSQL refuses NUL in a query
        ("DELETE", "/api/models/%09"),
    ):
        body = {"instances": [{"f0": 1.0}]} if method == "POST" else None
        answer = api.request(method, path, json=body)
        assert answer.status_code == 404, (path, answer.text)
        assert answer.json()["error"]["type"] == "NotFoundError"
    run = api.post("/api/runs", json={"dataset": "touch\u0000", "classifiers": ["nb"]})
    assert run.status_code == 404 and run.json()["error"]["type"] == "NotFoundError"
    assert api.get("/api/datasets/1").status_code == 200
    assert len(api.get("/api/models").json()["models"]) == 1


def test_target_counts_and_names_are_told_apart() -> None:
    from touchbench.app.schemas.datasets import parse_targets
    from touchbench.app.store.naming import is_row_id

    assert (parse_targets("2"), parse_targets("-2"), parse_targets("²")) == (2, -2, ["²"])
    assert parse_targets("--2") == ["--2"] and parse_targets("a, b") == ["a", "b"]
    assert [is_row_id(t) for t in ("7", "²", "١", "0", "99999999999")] == [True] + [False] * 4
