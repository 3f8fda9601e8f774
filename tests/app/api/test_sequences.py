"""A sequence classifier asked for over HTTP on a flat data set: a 4xx JSON error at once."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server
from tests.support.synthetic import touch_arff


def test_sequence_classifiers_on_flat_data_are_refused_with_4xx(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    data = touch_arff(tmp_path / "t.arff", n=60)
    assert run_cli(capsys, server.database_url, "import", str(data), "--name", "touch").code == 0
    api = server.client
    run = api.post(
        "/api/runs",
        json={"dataset": "touch", "target": "gesture", "classifiers": ["minirocket"], "folds": 3},
    )
    model = api.post(
        "/api/models", json={"dataset": "touch", "classifier": "multirocket", "target": "gesture"}
    )
    # The run and the training are each refused at their request's classifier field.
    assert run.status_code == 422 and run.json()["error"]["where"] == "body.classifiers", run.text
    assert model.status_code == 422, model.text
    for response, classifier in ((run, "minirocket"), (model, "multirocket")):
        message = response.json()["error"]["message"]
        assert message.startswith(f"classifier '{classifier}' needs a sequence data set")
    assert model.json()["error"]["where"] == "body.classifier"
    assert api.get("/api/runs").json()["runs"] == []
    assert api.get("/api/models").json()["models"] == []
