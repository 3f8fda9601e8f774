"""What a leaderboard scores and lists, on SQLite: ``bench --aggregate
recording`` (a recording's windows as one prediction) in every view and refused where it
means nothing, and a stopped run's classifiers that never started.  That pooling beats
the windows: tests/benchmark/test_recordings.py."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import create_engine, text

from tests.support.cli_runner import run_cli
from tests.support.recordings import PER_RECORDING, recorded_windows, store_dataset
from tests.support.synthetic import touch_arff


def test_per_recording_scores_and_never_started_classifiers_in_every_view(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    store_dataset(sqlite_store_url, recorded_windows(), "takes")
    bench = run_cli(
        capsys, sqlite_store_url, "bench", "takes", "-c", "nb,ridge,zeror", "-k", "4",
        "--aggregate", "recording", "--json",
    )  # fmt: skip
    assert bench.code == 0, bench.err
    board = bench.json()
    assert board["aggregate"] == "recording" and board["notes"][0].startswith(PER_RECORDING)
    assert board["folds"] == "stratified group 4-fold"
    assert [row["classifier"] for row in board["leaderboard"]] == ["nb", "ridge", "zeror"]
    # 4 recordings a test fold, 2 classes: the confusion matrices count recordings
    classes = run_cli(capsys, sqlite_store_url, "classes", "1", "-c", "nb", "--json").json()
    assert np.sum(classes["classifiers"][0]["targets"][0]["confusion"]) == 16
    table = run_cli(capsys, sqlite_store_url, "leaderboard", "1")
    assert "scored per recording" in table.out and PER_RECORDING in table.err
    markdown = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "-f", "markdown").out
    assert PER_RECORDING in markdown
    arff = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "-f", "arff").out
    assert arff.startswith(f"% {PER_RECORDING}")
    report = tmp_path / "report.html"
    assert run_cli(capsys, sqlite_store_url, "report", "1", "-o", str(report)).code == 0
    assert PER_RECORDING in html.unescape(report.read_text(encoding="utf-8"))

    # what a cancel leaves when it comes while nb runs: ridge and zeror never started
    engine = create_engine(sqlite_store_url)
    try:
        with engine.begin() as connection:
            connection.execute(text("DELETE FROM fold_results WHERE classifier <> 'nb'"))
            connection.execute(text("UPDATE runs SET status = 'cancelled'"))
    finally:
        engine.dispose()
    board = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "--json").json()
    rows = {row["classifier"]: row for row in board["leaderboard"]}
    assert list(rows) == ["nb", "ridge", "zeror"]
    assert rows["nb"]["dropped"] is None and rows["nb"]["n_ok"] == 4
    for name in ("ridge", "zeror"):
        assert rows[name]["dropped"]["reason"] == "not started", rows[name]
        assert rows[name]["dropped"]["note"] == "never started" and rows[name]["n_ok"] == 0
    note = "2 classifier(s) never started (the run is cancelled): ridge, zeror"
    assert board["notes"] == [board["notes"][0], note]
    table = run_cli(capsys, sqlite_store_url, "leaderboard", "1")
    assert "never started" in table.out and note in table.err
    markdown = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "-f", "markdown").out
    assert "| zeror (never started) |" in markdown.replace("| 3 | zeror", "| zeror")
    assert note in markdown
    arff = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "-f", "arff").out
    assert "% zeror: never started" in arff and f"% {note}" in arff
    assert run_cli(capsys, sqlite_store_url, "report", "1", "-o", str(report)).code == 0
    page = report.read_text(encoding="utf-8")
    assert "never started" in page and note in page


def test_per_recording_scores_are_refused_where_they_mean_nothing(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    run_cli(
        capsys, sqlite_store_url, "import", str(touch_arff(tmp_path / "t.arff")), "--name", "touch"
    )
    store_dataset(sqlite_store_url, recorded_windows(mixed=True), "mixed")
    for name, words in (
        ("touch", "--aggregate: needs windows grouped by recording, and data set 'touch' has"),
        ("mixed", "--aggregate: 1 recording(s) hold windows of several values of 'gesture'"),
    ):
        result = run_cli(
            capsys, sqlite_store_url, "bench", name, "-c", "nb", "--target", "gesture",
            "--aggregate", "recording",
        )  # fmt: skip
        assert result.code == 2
        lines = result.err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"touchbench: error: {words}"), result.err
    bad = run_cli(capsys, sqlite_store_url, "bench", "touch", "-c", "nb", "--aggregate", "take")
    assert bad.code == 2 and "--aggregate: Input should be 'window' or 'recording'" in bad.err
