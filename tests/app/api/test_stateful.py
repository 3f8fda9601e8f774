"""Schemathesis's stateful run on a real ``touchbench serve``, once with a key of each role
(read, predict, write): call sequences that follow OpenAPI links between the operations
(an upload to the data set it made, a training to its job, a listing to its first
model...) meet no server error, and every answer conforms to the document (status,
content type, body)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server
from tests.support.synthetic import touch_arff

KEYS = {
    "read": "stateful-read-key-0001",
    "predict": "stateful-predict-key-0002",
    "write": "stateful-write-key-0003",
}

#: Links added to the service's document: (producer path, method, status) -> the
#: consumers (path, method) and the expression that gives their path parameter.
LINKS: dict[tuple[str, str, str], list[tuple[str, str, str, str]]] = {
    ("/api/datasets", "post", "201"): [
        ("/api/datasets/{dataset}", "get", "dataset", "$response.body#/id"),
        ("/api/datasets/{dataset}/arff", "get", "dataset", "$response.body#/id"),
        ("/api/datasets/{dataset}/rename", "post", "dataset", "$response.body#/id"),
        ("/api/datasets/{dataset}", "delete", "dataset", "$response.body#/id"),
    ],
    ("/api/datasets", "get", "200"): [
        ("/api/datasets/{dataset}", "get", "dataset", "$response.body#/datasets/0/name"),
        ("/api/datasets/{dataset}/arff", "get", "dataset", "$response.body#/datasets/0/id"),
    ],
    ("/api/datasets/recordings", "post", "202"): [
        ("/api/jobs/{job_id}", "get", "job_id", "$response.body#/job"),
    ],
    ("/api/models", "post", "202"): [
        ("/api/jobs/{job_id}", "get", "job_id", "$response.body#/job"),
        ("/api/jobs/{job_id}/cancel", "post", "job_id", "$response.body#/job"),
    ],
    ("/api/models", "get", "200"): [
        ("/api/models/{model_ref}", "get", "model_ref", "$response.body#/models/0/id"),
        ("/api/models/{model_ref}/predict", "post", "model_ref", "$response.body#/models/0/name"),
    ],
    ("/api/runs", "post", "202"): [
        ("/api/runs/{run_id}", "get", "run_id", "$response.body#/id"),
        ("/api/runs/{run_id}/cancel", "post", "run_id", "$response.body#/id"),
    ],
}


def with_links(document: dict[str, Any]) -> dict[str, Any]:
    """``document`` with :data:`LINKS` in its responses (by the consumers' operationIds)."""
    paths = document["paths"]
    for (path, method, status), consumers in LINKS.items():
        response = paths[path][method]["responses"][status]
        links = response.setdefault("links", {})
        for target, target_method, parameter, expression in consumers:
            operation_id = paths[target][target_method]["operationId"]
            links[f"{target_method}-{target}"] = {
                "operationId": operation_id,
                "parameters": {parameter: expression},
            }
    return document


@pytest.fixture
def keyed_server(make_server: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> Server:
    """A service with one key of each role, a data set ``touch`` and a model of it."""
    keys = ",".join(f"{role}-robot:{role}:{key}" for role, key in KEYS.items())
    server: Server = make_server(api_keys=keys)
    run_cli(capsys, server.database_url, "import", str(touch_arff(tmp_path / "touch.arff", n=30)))
    trained = run_cli(
        capsys, server.database_url, "train", "touch", "-c", "nb", "--target", "gesture"
    )
    assert trained.code == 0, trained.err
    return server


def test_stateful_sequences_with_each_role_meet_no_server_error(keyed_server: Server) -> None:
    # heavy imports: schemathesis and hypothesis load for this test only
    import schemathesis
    from hypothesis import HealthCheck, Phase, settings
    from schemathesis.checks import (
        content_type_conformance,
        not_a_server_error,
        response_schema_conformance,
        status_code_conformance,
    )

    document = keyed_server.client.get("/openapi.json").json()
    schema = schemathesis.openapi.from_dict(with_links(document))
    # a loaded machine may take seconds for a first answer that loads scikit-learn
    schema.config.update(base_url=keyed_server.url, request_timeout=120)
    checks = [
        not_a_server_error,
        status_code_conformance,
        content_type_conformance,
        response_schema_conformance,
    ]
    seen: dict[str, set[int]] = {}
    for role, key in KEYS.items():
        statuses = seen.setdefault(role, set())

        class Workflow(schema.as_state_machine()):  # type: ignore[misc]
            api_key = key
            answered = statuses

            def before_call(self, case: schemathesis.Case) -> None:
                case.headers["X-API-Key"] = self.api_key

            def validate_response(
                self, response: Any, case: schemathesis.Case, **kwargs: Any
            ) -> None:
                self.answered.add(response.status_code)
                case.validate_response(response, checks=checks)

        Workflow.run(
            settings=settings(
                max_examples=6,
                stateful_step_count=4,
                deadline=None,
                phases=[Phase.generate],
                suppress_health_check=list(HealthCheck),
                database=None,
                derandomize=True,  # the same sequences each time: a failure comes back
            )
        )
    # each key was used: its role shows in what the service answered
    assert 403 in seen["read"], seen
    assert any(200 <= status < 300 for status in seen["write"]), seen
