"""On a real service: `GET /api/runs/{id}/leaderboard?aggregate=recording|window` scores a
finished run's stored test-fold predictions the other way, as `touchbench leaderboard
--aggregate` does (tests/app/cli/test_leaderboard_aggregate.py: equal to runs scored so
from the start, nothing fitted), and refuses with 422 naming the query parameter; so do
the run's folds, classes and reliability diagram."""

from __future__ import annotations

import csv
import io
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import pytest

from tests.support.cli_runner import run_cli
from tests.support.recordings import PER_RECORDING, recorded_windows, store_dataset
from tests.support.service import Server
from touchbench.app.errors import FieldError
from touchbench.app.services.certainty import run_certainty
from touchbench.app.services.folds import run_fold_scores
from touchbench.app.store.database import Store

RESCORED = "re-scored per recording from the run's stored test-fold predictions"


def test_leaderboard_rescored_per_recording_and_refused(
    capsys: pytest.CaptureFixture[str], make_sqlite_server: Callable[..., Server]
) -> None:
    server = make_sqlite_server()
    db, api = server.database_url, server.client
    store_dataset(db, recorded_windows(), "takes")
    store_dataset(db, recorded_windows(mixed=True), "mixed")
    for dataset, options in (("takes", ()), ("takes", ("--aggregate", "recording")), ("mixed", ())):
        made = run_cli(capsys, db, "bench", dataset, "-c", "nb,ridge", "-k", "4", *options)
        assert made.code == 0, made.err

    leaderboard = "/api/runs/{}/leaderboard"
    rescored = api.get(leaderboard.format(1), params={"aggregate": "recording"})
    assert rescored.status_code == 200, rescored.text
    board = rescored.json()
    scored = api.get(leaderboard.format(2)).json()
    assert board["aggregate"] == scored["aggregate"] == "recording"
    assert board["notes"][0].startswith(PER_RECORDING) and board["notes"][1].startswith(RESCORED)
    for ours, theirs in zip(board["leaderboard"], scored["leaderboard"], strict=True):
        assert ours["classifier"] == theirs["classifier"] and ours["mark"] == theirs["mark"]
        for name in ("f1_weighted", "accuracy", "kappa"):
            assert ours["metrics"][name] == theirs["metrics"][name]
    back = api.get(leaderboard.format(2), params={"aggregate": "window"}).json()
    plain = api.get(leaderboard.format(1)).json()
    assert back["aggregate"] == "window"
    assert [r["metrics"]["f1_weighted"] for r in back["leaderboard"]] == [
        r["metrics"]["f1_weighted"] for r in plain["leaderboard"]
    ]
    as_csv = api.get(leaderboard.format(1), params={"aggregate": "recording", "format": "csv"})
    assert {row["aggregate"] for row in csv.DictReader(io.StringIO(as_csv.text))} == {"recording"}
    markdown = api.get(
        leaderboard.format(1), params={"aggregate": "recording", "format": "markdown"}
    ).text
    assert PER_RECORDING in markdown and RESCORED in markdown

    mixed = api.get(leaderboard.format(3), params={"aggregate": "recording"})
    assert mixed.status_code == 422, mixed.text
    error = mixed.json()["error"]
    assert error["where"] == "query.aggregate"
    assert "1 recording(s) hold windows of several values of 'gesture'" in error["message"]
    bad = api.get(leaderboard.format(1), params={"aggregate": "take"})
    assert bad.status_code == 422, bad.text
    assert bad.json()["error"]["where"] == "query.aggregate"


def test_folds_and_classes_scored_per_recording_and_refused(
    capsys: pytest.CaptureFixture[str],
    make_sqlite_server: Callable[..., Server],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """`folds` and `classes` with `aggregate=recording` of a run scored per window are those
    of the same run scored per recording from the start, and agree with the re-scored
    leaderboard; an imported run is refused naming the query parameter, before its results
    are read."""
    server = make_sqlite_server()
    db, api = server.database_url, server.client
    store_dataset(db, recorded_windows(), "takes")
    for options in ((), ("--aggregate", "recording")):
        made = run_cli(
            capsys, db, "bench", "takes", "-c", "nb,ridge", "-k", "4", "--seed", "3", *options
        )
        assert made.code == 0, made.err
    exported = tmp_path / "results.arff"
    exported.write_text(run_cli(capsys, db, "leaderboard", "1", "-f", "arff").out)
    imported = run_cli(capsys, db, "import-results", str(exported), "--dataset", "takes")
    assert imported.code == 0, imported.err
    windows, recordings, paper = 1, 2, 3

    def get(path: str, run: int, **params: str) -> Any:
        answer = api.get(f"/api/runs/{run}/{path}", params=params)
        assert answer.status_code == 200, answer.text
        return answer.json()

    folds = get("folds", windows, aggregate="recording")
    assert folds["aggregate"] == "recording" and get("folds", windows)["aggregate"] == "window"
    from_start = get("folds", recordings)
    assert folds["scores"] == from_start["scores"]  # the same floats
    assert folds["scores"] != get("folds", windows)["scores"]
    ranked = [(c["classifier"], c["average_rank"]) for c in folds["ranks"]["classifiers"]]
    assert ranked == [
        (c["classifier"], c["average_rank"]) for c in from_start["ranks"]["classifiers"]
    ]
    board = get("leaderboard", windows, aggregate="recording")
    for row in board["leaderboard"]:
        mean = np.mean(folds["scores"][row["classifier"]])
        assert mean == pytest.approx(row["metrics"]["f1_weighted"]["mean"], abs=1e-12)
    assert get("folds", recordings, aggregate="window")["scores"] == get("folds", windows)["scores"]

    classes = get("classes", windows, aggregate="recording")
    assert classes["aggregate"] == "recording"
    assert classes["classifiers"] == get("classes", recordings)["classifiers"]
    per_window = {c["classifier"]: c for c in get("classes", windows)["classifiers"]}
    for entry in classes["classifiers"]:
        # 16 recordings of 16 windows, each tested once over the 4 folds
        [target] = entry["targets"]
        assert np.sum(target["confusion"]) == 16
        assert np.sum(per_window[entry["classifier"]]["targets"][0]["confusion"]) == 256
    nb = get("classes", windows, aggregate="recording", classifier="nb")["classifiers"]
    assert nb[0]["calibration"]["n_instances"] == 16
    assert per_window["nb"]["calibration"]["n_instances"] == 256
    svg = api.get(f"/api/runs/{windows}/calibration.svg", params={"aggregate": "recording"})
    assert svg.status_code == 200 and svg.text.lstrip().startswith("<?xml")

    # an imported run holds scores, not predictions: refused as its leaderboard is
    assert get("folds", paper, aggregate="window")["aggregate"] == "window"
    for path in ("folds", "classes", "calibration.svg", "leaderboard"):
        refused = api.get(f"/api/runs/{paper}/{path}", params={"aggregate": "recording"})
        assert refused.status_code == 422, (path, refused.text)
        error = refused.json()["error"]
        assert error["where"] == "query.aggregate", path
        assert f"run {paper} was imported: it holds its scores" in error["message"], path
        bad = api.get(f"/api/runs/{windows}/{path}", params={"aggregate": "take"})
        assert bad.status_code == 422 and bad.json()["error"]["where"] == "query.aggregate"

    def unread(*args: object, **kwargs: object) -> NoReturn:
        raise AssertionError("the results of a run refused re-scoring were read")

    monkeypatch.setattr("touchbench.app.services.runs.leaderboard.load_results", unread)
    store = Store(db)
    try:
        for asked in (run_fold_scores, run_certainty):
            with pytest.raises(FieldError) as refused_early:
                asked(store, paper, aggregate="recording")
            assert refused_early.value.field == "aggregate"
    finally:
        store.dispose()
