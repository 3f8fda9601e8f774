"""The answers after a run over HTTP: an ablation kept by `bench --ablate-groups` read back by
the API and the web page; bad requests for the three jobs refused before a job exists.  One
SQLite service; the answers' work (and a job carried out as the service's workers do) is
tested through the CLI (tests/app/services/test_answers.py), where it costs no service."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server
from tests.support.synthetic import mics_arff


def test_a_kept_ablation_over_http_and_refused_jobs(
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

    nope = {"dataset": "mics", "classifiers": ["nope"], "fractions": [0.5]}
    refused_curve = api.post("/api/jobs/learning-curve", json=nope)
    assert refused_curve.status_code in (400, 422) and "classifiers" in refused_curve.text
    jobs = api.get("/api/jobs").json()["jobs"]
    assert [job["kind"] for job in jobs] == ["ablation"]  # nothing refused was queued
    not_a_curve = api.get(f"/api/jobs/{jobs[0]['id']}/learning-curve.svg")
    assert not_a_curve.status_code == 404 and "not a learning curve" in not_a_curve.text
