"""Leave-one-group-out over HTTP, on a real service over SQLite: ``"folds":
"logo"`` in ``POST /api/runs`` makes one fold per group of an uploaded table, and the run's
JSON, its leaderboard and its web page say so, as the CLI does."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.grasp_table import OBJECTS, grasp_csv
from tests.support.service import Server, finished, upload


def test_a_run_leaving_one_object_out_says_so_everywhere(
    capsys: pytest.CaptureFixture[str], sqlite_server: Server, tmp_path: Path
) -> None:
    uploaded = upload(
        sqlite_server, grasp_csv(tmp_path / "grasps.csv"), groups="object", ignore="trial"
    )
    assert uploaded.status_code == 201, uploaded.text
    api = sqlite_server.client
    started = api.post(
        "/api/runs", json={"dataset": "grasps", "classifiers": ["nb", "zeror"], "folds": "logo"}
    )
    assert started.status_code == 202, started.text
    run = sqlite_server.wait_for(f"/api/runs/{started.json()['id']}", finished)
    said = f"leave-one-group-out, {len(OBJECTS)} groups"
    assert run["status"] == "done" and run["folds"] == said
    assert run["config"]["split"] == "leave-one-group-out" and run["tasks"] == 2 * len(OBJECTS)
    board = api.get(f"/api/runs/{run['id']}/leaderboard").json()
    assert board["folds"] == said
    assert {row["n_ok"] for row in board["leaderboard"]} == {len(OBJECTS)}
    cli = run_cli(
        capsys, sqlite_server.database_url, "leaderboard", str(run["id"]), "--json"
    ).json()
    assert cli == board
    assert said in api.get(f"/fragments/runs/{run['id']}/progress").text
