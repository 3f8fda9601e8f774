"""On a real service: a run scored per recording and a cancelled run's classifiers that
never started, as the API and the web page say them; a raw recording uploaded to a model
trained on extracted features, predicted with its recipe.  One service on SQLite: the
store's part is tested on both stores by tests/app/cli/test_scores.py."""

from __future__ import annotations

import html
from collections.abc import Callable
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text

from tests.support.cli_runner import run_cli
from tests.support.recordings import PER_RECORDING, recorded_windows, store_dataset, write_take
from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff


def test_scores_per_recording_never_started_and_raw_recordings_predicted(
    capsys: pytest.CaptureFixture[str], make_sqlite_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_sqlite_server()
    db, api = server.database_url, server.client
    store_dataset(db, recorded_windows(), "takes")
    run_cli(capsys, db, "import", str(touch_arff(tmp_path / "t.arff")), "--name", "touch")
    body = {"classifiers": ["nb", "zeror"], "folds": 4, "aggregate": "recording"}
    refused = api.post("/api/runs", json={**body, "dataset": "touch", "target": "gesture"})
    assert refused.status_code == 422, refused.text
    error = refused.json()["error"]
    assert error["where"] == "body.aggregate"
    assert error["message"].startswith("needs windows grouped by recording, and data set")
    started = api.post("/api/runs", json={**body, "dataset": "takes"})
    assert started.status_code == 202, started.text
    run_id = started.json()["id"]
    assert server.wait_for(f"/api/runs/{run_id}", finished)["status"] == "done"
    board = api.get(f"/api/runs/{run_id}/leaderboard").json()
    assert board["aggregate"] == "recording" and board["notes"][0].startswith(PER_RECORDING)
    assert board["leaderboard"][0]["metrics"]["f1_weighted"]["mean"] > 0.85
    page = html.unescape(api.get(f"/fragments/runs/{run_id}/leaderboard").text)
    assert PER_RECORDING in page

    # what a cancel leaves when it comes while nb runs: zeror never started
    engine = create_engine(db)
    try:
        with engine.begin() as connection:
            connection.execute(text("DELETE FROM fold_results WHERE classifier = 'zeror'"))
            connection.execute(text("UPDATE runs SET status = 'cancelled'"))
    finally:
        engine.dispose()
    board = api.get(f"/api/runs/{run_id}/leaderboard").json()
    zeror = board["leaderboard"][-1]
    assert zeror["classifier"] == "zeror" and zeror["dropped"]["reason"] == "not started"
    note = "1 classifier(s) never started (the run is cancelled): zeror"
    assert board["notes"][1:] == [note]
    markdown = api.get(f"/api/runs/{run_id}/leaderboard", params={"format": "markdown"}).text
    assert "zeror (never started)" in markdown and note in markdown
    page = api.get(f"/fragments/runs/{run_id}/leaderboard").text
    assert "never started" in page and note in page

    # a raw recording, uploaded
    rows = ["file,state"]
    for take in range(4):
        kind = "slip" if take % 2 else "still"
        write_take(tmp_path / f"take-{take}.csv", kind, seed=take)
        rows.append(f"take-{take}.csv,{kind}")
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    takes = [str(tmp_path / f"take-{take}.csv") for take in range(4)]
    extracted = run_cli(
        capsys, db, "extract", *takes, "--labels", str(tmp_path / "labels.csv"),
        "-e", "taxel-dft", "--samplerate", "100", "--name", "slips",
    )  # fmt: skip
    assert extracted.code == 0, extracted.err
    trained = run_cli(capsys, db, "train", "slips", "--classifier", "nb", "--json")
    assert trained.code == 0, trained.err
    model = trained.json()["name"]

    unseen = tmp_path / "unseen.csv"
    write_take(unseen, "slip", seed=42)
    with unseen.open("rb") as handle:
        answer = api.post(
            f"/api/models/{model}/predict/file", files={"file": (unseen.name, handle)}
        )
    assert answer.status_code == 200, answer.text
    report = answer.json()
    states = [row["state"] for row in report["predictions"]]
    assert len(states) > 50 and states.count("slip") > 0.9 * len(states)
    assert any(w.startswith("unseen.csv: column 'timestamp'") for w in report["warnings"])
    # the same answer as `touchbench predict MODEL unseen.csv`
    local = run_cli(capsys, db, "predict", model, str(unseen), "--json").json()
    assert local["predictions"] == report["predictions"]

    # a recording the recipe cannot read is named as the client named it
    two = tmp_path / "two.csv"
    two.write_text("timestamp,tdc,tac\n0.00,1,2\n0.01,1,2\n")
    with two.open("rb") as handle:
        upload = {"file": (two.name, handle)}
        refused = api.post(f"/api/models/{model}/predict/file", files=upload)
    assert refused.status_code == 400, refused.text
    message = refused.json()["error"]["message"]
    assert message.startswith("two.csv: ") and str(server.work_dir) not in message, message
