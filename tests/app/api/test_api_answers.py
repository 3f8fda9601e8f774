"""The answers after a run over HTTP: an ablation kept by `bench --ablate-groups` read back by
the API and the web page; a learning curve as a job of the service's workers, drawn as SVG;
bad requests refused before a job exists.  One SQLite service: the jobs start the engine's
worker processes (the CLI's tests cover the answers on their own)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from tests.app.api.conftest import Server, finished
from tests.app.cli_runner import run_cli
from tests.app.test_answers_jobs import mics_arff


def test_ablation_and_learning_curve_over_http(
    capsys: pytest.CaptureFixture[str],
    make_sqlite_server: Callable[..., Server],
    tmp_path: Path,
) -> None:
    server = make_sqlite_server()
    db, api = server.database_url, server.client
    assert run_cli(capsys, db, "import", str(mics_arff(tmp_path / "mics.arff", n=60))).code == 0
    ablated = run_cli(
        capsys, db, "bench", "mics", "-c", "nb", "--folds", "3", "--ablate-groups", "channel",
        "--json",
    ).json()["run_id"]  # fmt: skip
    ablation = api.get(f"/api/runs/{ablated}/ablation")
    assert ablation.status_code == 200
    assert [e["group"] for e in ablation.json()["entries"]] == ["channel 1", "channel 2"]
    board = api.get(f"/fragments/runs/{ablated}/leaderboard").text
    assert "Which sensor and which features" in board and 'data-table="ablation"' in board
    missing = api.get(f"/api/runs/{ablated + 1}/ablation")
    assert missing.status_code == 404 and "run" in missing.json()["error"]["message"]

    refused = api.post("/api/jobs/ablation", json={"run": ablated, "grouping": "mic"})
    assert refused.status_code == 422
    unknown = api.post("/api/jobs/importance", json={"run": ablated, "classifier": "rf"})
    assert unknown.status_code in (400, 422) and "classifier" in unknown.text
    assert api.get("/api/jobs").json()["jobs"][-1]["kind"] == "ablation"  # none queued

    curve = api.post(
        "/api/jobs/learning-curve",
        json={"dataset": "mics", "classifiers": ["nb"], "fractions": [0.5], "folds": 2},
    )
    assert curve.status_code == 202, curve.text
    job = curve.json()["job"]
    found = server.wait_for(f"/api/jobs/{job}", finished, timeout=300)
    assert found["status"] == "done", found
    assert found["result"]["fractions"] == [0.5, 1.0] and found["result"]["complete"]
    svg = api.get(f"/api/jobs/{job}/learning-curve.svg")
    assert svg.status_code == 200 and "learning curves" in svg.text
    assert api.get(f"/api/jobs/{job - 1}/learning-curve.svg").status_code == 404  # an ablation
