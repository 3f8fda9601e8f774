"""A sequence classifier asked for over HTTP on a flat data set: a 4xx JSON error at once."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.app.api.conftest import Server
from tests.app.cli_runner import run_cli
from tests.app.synthetic import touch_arff


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
    # The run is refused by the engine's check (400), the training by its request's
    # `classifier` field (422, at body.classifier).
    for response, classifier, status in ((run, "minirocket", 400), (model, "multirocket", 422)):
        assert response.status_code == status, response.text
        message = response.json()["error"]["message"]
        assert message.startswith(f"classifier '{classifier}' needs a sequence data set")
    assert model.json()["error"]["where"] == "body.classifier"
    assert api.get("/api/runs").json()["runs"] == []
    assert api.get("/api/models").json()["models"] == []
