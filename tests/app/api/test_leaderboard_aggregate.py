"""On a real service: `GET /api/runs/{id}/leaderboard?aggregate=recording|window` scores a
finished run's stored test-fold predictions the other way, as `touchbench leaderboard
--aggregate` does (tests/app/cli/test_leaderboard_aggregate.py: equal to runs scored so
from the start, nothing fitted), and refuses with 422 naming the query parameter."""

from __future__ import annotations

import csv
import io
from collections.abc import Callable

import pytest

from tests.support.cli_runner import run_cli
from tests.support.recordings import PER_RECORDING, recorded_windows, store_dataset
from tests.support.service import Server

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
