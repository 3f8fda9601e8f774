"""The service end to end on a real uvicorn: a run queued over HTTP, carried out by a worker
process, its leaderboard, a model trained as a job, predictions; the same JSON as the CLI."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff
from touchbench.app.store.database import Store
from touchbench.app.store.models import rename_model


def _import(capsys: pytest.CaptureFixture[str], url: str, path: Path, name: str) -> None:
    result = run_cli(capsys, url, "import", str(path), "--name", name)
    assert result.code == 0, result.err


@pytest.mark.slow
def test_run_leaderboard_model_and_predictions_over_http(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    data = touch_arff(tmp_path / "t.arff", n=120)
    _import(capsys, server.database_url, data, "touch")
    api = server.client

    started = api.post(
        "/api/runs",
        json={
            "dataset": "touch",
            "target": "gesture",
            "classifiers": ["nb", "zeror", "j48"],
            "folds": 3,
            "seed": 1,
        },
    )
    assert started.status_code == 202, started.text
    assert started.json()["status"] == "queued"
    run_id = started.json()["id"]
    run = server.wait_for(f"/api/runs/{run_id}", finished)
    assert (run["status"], run["tasks_done"], run["tasks"], run["tasks_failed"]) == (
        "done",
        9,
        9,
        0,
    )

    board = api.get(f"/api/runs/{run_id}/leaderboard")
    assert board.status_code == 200
    cli_board = run_cli(capsys, server.database_url, "leaderboard", str(run_id), "--json")
    assert board.json() == cli_board.json()
    assert board.json()["leaderboard"][-1]["classifier"] == "zeror"
    cli_run = run_cli(capsys, server.database_url, "runs", "--json").json()["runs"][0]
    assert api.get(f"/api/runs/{run_id}").json() == cli_run
    markdown = api.get(f"/api/runs/{run_id}/leaderboard", params={"format": "markdown"})
    assert markdown.status_code == 200 and "| rank | classifier |" in markdown.text
    arff = api.get(f"/api/runs/{run_id}/leaderboard", params={"format": "arff"})
    assert arff.text.startswith("@relation") and "weka.classifiers" in arff.text

    trained = api.post("/api/models", json={"run": run_id, "name": "best"})
    assert trained.status_code == 202, trained.text
    job = server.wait_for(f"/api/jobs/{trained.json()['job']}", finished)
    assert job["status"] == "done", job
    model_id = job["result"]["model_id"]
    model = api.get(f"/api/models/{model_id}").json()
    assert model["name"] == "best" and model["run_id"] == run_id and model["format"] == "skops"
    assert model == run_cli(capsys, server.database_url, "models", "--json").json()["models"][0]

    predicted = api.post(
        f"/api/models/{model_id}/predict",
        json={
            "instances": [
                {"f0": 0.0, "f1": 0.0, "f2": 0, "f3": 0, "mic": "left"},
                {"f0": 4.0, "f1": 2.0, "mic": "elbow"},
            ],
            "missing": "allow",  # the second leaves out f2 and f3
        },
    )
    assert predicted.status_code == 200, predicted.text
    report = predicted.json()
    assert report["model"] == "best@1" and len(report["predictions"]) == 2
    first = report["predictions"][0]
    assert first["gesture"] in {"tap", "slap", "stroke"}
    assert sum(first["probabilities"]["gesture"].values()) == pytest.approx(1.0)
    assert any("'elbow'" in warning for warning in report["warnings"])

    with data.open("rb") as handle:
        from_file = api.post(
            f"/api/models/{model_id}/predict/file", files={"file": ("t.arff", handle)}
        )
    assert from_file.status_code == 200, from_file.text
    assert len(from_file.json()["predictions"]) == 120
    assert from_file.json()["accuracy"]["gesture"] > 0.8
    cli_predicted = run_cli(capsys, server.database_url, "predict", "best", str(data), "--json")
    assert from_file.json()["predictions"] == cli_predicted.json()["predictions"]

    # The service caches loaded models: what other processes do to the store still shows.
    one = {"instances": [{"f0": 0.0, "f1": 0.0, "f2": 0.0, "f3": 0.0, "mic": "left"}]}
    store = Store(server.database_url)
    try:
        rename_model(store, "best", "renamed")
    finally:
        store.dispose()
    assert api.post("/api/models/best/predict", json=one).status_code == 404
    renamed = api.post("/api/models/renamed/predict", json=one)
    assert renamed.status_code == 200 and renamed.json()["model"] == "renamed@1"
    assert run_cli(capsys, server.database_url, "delete-model", "renamed").code == 0
    gone = api.post(f"/api/models/{model_id}/predict", json=one)
    assert gone.status_code == 404 and gone.json()["error"]["type"] == "NotFoundError"


@pytest.mark.slow
def test_a_multi_target_run_and_model(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    _import(capsys, server.database_url, touch_arff(tmp_path / "t.arff", n=90), "touch")
    api = server.client
    started = api.post(
        "/api/runs", json={"dataset": "touch", "classifiers": ["cr:nb", "cc:j48"], "folds": 3}
    )
    assert started.status_code == 202, started.text
    run = server.wait_for(f"/api/runs/{started.json()['id']}", finished)
    assert run["status"] == "done" and run["kind"] == "multitarget"
    board = api.get(f"/api/runs/{run['id']}/leaderboard").json()
    assert board["metric"] == "hamming_score"
    assert set(board["leaderboard"][0]["metrics"]["per_target"]) == {"gesture", "place"}
    job = api.post("/api/models", json={"dataset": "touch", "classifier": "cc:j48"}).json()
    done = server.wait_for(f"/api/jobs/{job['job']}", finished)
    assert done["status"] == "done", done
    report = api.post(
        f"/api/models/{done['result']['model_id']}/predict",
        json={"instances": [{"f0": 4.0, "f1": 2.0, "f2": 0, "f3": 0, "mic": "both"}]},
    ).json()
    row = report["predictions"][0]
    assert row["gesture"] in {"tap", "slap", "stroke"} and row["place"] in {"head", "arm"}
    assert set(row["probabilities"]) == {"gesture", "place"}


def test_cancel_and_resume_over_http(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    _import(capsys, server.database_url, touch_arff(tmp_path / "t.arff", n=60), "touch")
    api, gate = server.client, server.gate
    assert gate is not None
    run_id = api.post(
        "/api/runs",
        json={
            "dataset": "touch",
            "target": "gesture",
            "classifiers": ["gate"],
            "folds": 3,  # a cancel after one task and a resume need a few, not ten
            "repeats": 2,
        },
    ).json()["id"]
    gate.let_through(1)
    server.wait_for(f"/api/runs/{run_id}", lambda body: body["tasks_done"] >= 1)
    gate.wait_started(2)  # the second task waits at the gate while the cancel comes
    cancelled = api.post(f"/api/runs/{run_id}/cancel")
    assert (cancelled.status_code, cancelled.json()["status"]) == (200, "cancelling")
    run = server.wait_for(f"/api/runs/{run_id}", finished)
    assert (run["status"], run["tasks_done"]) == ("cancelled", 1)
    resumed = api.post(f"/api/runs/{run_id}/resume")
    assert resumed.status_code == 202 and resumed.json()["status"] == "queued"
    gate.open()
    run = server.wait_for(f"/api/runs/{run_id}", finished, timeout=600)
    assert (run["status"], run["tasks_done"]) == ("done", 6)
    for refused in ("resume", "cancel"):
        again = api.post(f"/api/runs/{run_id}/{refused}")
        assert again.status_code == 409 and again.json()["error"]["type"] == "ConflictError"


def test_a_tuned_and_stacked_run_over_http_is_the_clis(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    _import(capsys, server.database_url, touch_arff(tmp_path / "t.arff", n=90), "touch")
    api = server.client
    request = {
        "dataset": "touch",
        "target": "gesture",
        "classifiers": ["logistic", "nb"],
        "folds": 3,
        "tune": True,
        "budget": 0.01,
        "stack": 2,
    }
    started = api.post("/api/runs", json=request)
    assert started.status_code == 202, started.text
    run = server.wait_for(f"/api/runs/{started.json()['id']}", finished)
    assert (run["status"], run["tasks_done"], run["tasks_failed"]) == ("done", 12, 0)
    board = api.get(f"/api/runs/{run['id']}/leaderboard").json()
    assert {row["classifier"] for row in board["leaderboard"]} == {
        "logistic",
        "logistic+tuned",
        "nb",
        "stack-top2",
    }
    assert [c["tuned"] for c in board["tuning"]] == ["logistic+tuned"]
    assert {c["classifier"] for c in board["choices"]} == {"logistic+tuned", "stack-top2"}
    cli_board = run_cli(capsys, server.database_url, "leaderboard", str(run["id"]), "--json")
    assert board == cli_board.json()
    for bad, where, message in (
        ({"budget": 0.01, "tune": False}, "body.budget", "is only meaningful with `tune`"),
        ({"stack": 0}, "body.stack", "greater than or equal to 1"),
    ):
        refused = api.post("/api/runs", json={**request, **bad})
        assert refused.status_code == 422, refused.text
        error = refused.json()["error"]
        assert error["where"] == where and message in error["message"], refused.text
