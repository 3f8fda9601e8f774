"""`POST /api/runs/import-results` and `GET /api/runs/{id}/leaderboard?beside=`: the same
JSON as the CLI's `import-results` and `leaderboard --beside`; bad uploads 4xx, nothing
stored."""

from __future__ import annotations

from pathlib import Path

import httpx
import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server
from tests.support.synthetic import touch_arff


def _upload(server: Server, path: Path, **fields: str) -> httpx.Response:
    with path.open("rb") as handle:
        return server.client.post(
            "/api/runs/import-results", files={"file": (path.name, handle)}, data=fields
        )


def test_imported_results_answer_as_the_cli_does(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    db = server.database_url
    data = touch_arff(tmp_path / "touch.arff", n=60, with_place=False)
    assert run_cli(capsys, db, "import", str(data)).code == 0
    ours = run_cli(capsys, db, "bench", "touch", "-c", "j48,nb", "--folds", "3", "--json")
    run_id = ours.json()["run_id"]
    exported = run_cli(capsys, db, "leaderboard", str(run_id), "--format", "arff").out
    results = tmp_path / "weka results.arff"
    results.write_text(exported, encoding="utf-8")

    created = _upload(server, results, dataset="touch", name="the paper")
    assert created.status_code == 201, created.text
    run = created.json()
    assert run["classifiers"] == ["J48", "NaiveBayes"] and run["config"]["name"] == "the paper"
    assert run["config"]["source"] == "weka_results.arff"
    listed = run_cli(capsys, db, "runs", "--json").json()["runs"]
    assert [r for r in listed if r["id"] == run["id"]] == [run]
    assert server.client.get(f"/api/runs/{run['id']}").json() == run

    api = server.client.get(f"/api/runs/{run_id}/leaderboard", params={"beside": run["id"]})
    cli = run_cli(capsys, db, "leaderboard", str(run_id), "--beside", str(run["id"]), "--json")
    assert api.status_code == 200 and api.json() == cli.json()
    assert api.json()["beside"][0]["test"] == "by fold number"
    markdown = server.client.get(
        f"/api/runs/{run_id}/leaderboard", params={"beside": run["id"], "format": "markdown"}
    )
    assert "folds paired by number" in markdown.text


def test_bad_result_uploads_are_4xx_and_store_nothing(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    db = server.database_url
    data = touch_arff(tmp_path / "touch.arff", n=60, with_place=False)
    assert run_cli(capsys, db, "import", str(data)).code == 0
    broken = tmp_path / "broken.arff"
    broken.write_text("@relation InstanceResultListener\n@attribute a {'x}\n@data\n'x\n")
    response = _upload(server, broken, dataset="touch")
    assert response.status_code == 400
    error = response.json()["error"]
    assert error["type"] == "DataFormatError" and error["where"].startswith("broken.arff:2")
    plain = _upload(server, data, dataset="touch")
    assert plain.status_code == 400
    assert "not a WEKA Experimenter" in plain.json()["error"]["message"]
    assert server.client.post("/api/runs/import-results").status_code == 422
    long_name = _upload(server, data, dataset="touch", name="x" * 300)
    assert long_name.status_code == 422
    assert server.client.get("/api/runs").json() == {"runs": []}
    beside = server.client.get("/api/runs/1/leaderboard", params={"beside": 1})
    assert beside.status_code == 404


def test_classes_and_calibration_answer_as_the_cli_does(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    db = server.database_url
    data = touch_arff(tmp_path / "touch.arff", n=60, with_place=False)
    assert run_cli(capsys, db, "import", str(data)).code == 0
    run_id = run_cli(capsys, db, "bench", "touch", "-c", "j48,nb", "--folds", "3", "--json").json()[
        "run_id"
    ]
    api = server.client.get(f"/api/runs/{run_id}/classes", params={"classifier": "nb,j48"})
    cli = run_cli(capsys, db, "classes", str(run_id), "-c", "nb,j48", "--json")
    assert api.status_code == 200 and api.json() == cli.json()
    assert [e["classifier"] for e in api.json()["classifiers"]] == ["nb", "j48"]
    svg = server.client.get(f"/api/runs/{run_id}/calibration.svg")
    assert svg.status_code == 200 and svg.headers["content-type"].startswith("image/svg+xml")
    assert "<svg" in svg.text and "nb (ECE" in svg.text
    unknown = server.client.get(f"/api/runs/{run_id}/classes", params={"classifier": "rf"})
    assert unknown.status_code == 400 and "no classifier 'rf'" in unknown.json()["error"]["message"]
    assert server.client.get("/api/runs/99/classes").status_code == 404
