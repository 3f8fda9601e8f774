"""``bench --race`` and ``--budget-total`` from the command line: bad values
refused in one line and a raced run's drop in every view, on SQLite; a race interrupted by
Ctrl-C that resumes to the leaderboard of an uninterrupted one, on SQLite and PostgreSQL."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import text

from tests.support.cli_runner import run_cli
from tests.support.gate import Gate
from tests.support.processes import bench_process, scalar, store_engine, wait_for_results
from tests.support.service import ROOT
from tests.support.synthetic import touch_arff

RACE = ["--target", "gesture", "--folds", "5", "--race", "--seed", "3"]
#: Runs each command line of the JSON list in argv[1] with touchbench's main, in order.
BENCH_TWICE = (
    "import json, sys\n"
    "from touchbench.app.cli.main import main\n"
    "for command in json.loads(sys.argv[1]):\n"
    "    code = main(command)\n"
    "    if code:\n"
    "        sys.exit(code)\n"
)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--race", "--folds", "2"], "--race: needs at least 3 folds"),
        (["--race", "--race-alpha", "0"], "--race-alpha: Input should be greater than 0"),
        (["--race", "--race-alpha", "0.5"], "--race-alpha: Input should be less than 0.5"),
        (["--race-alpha", "0.05"], "--race-alpha: is only meaningful with --race"),
        (["--budget-total", "-1"], "--budget-total: Input should be greater than 0"),
        (["--budget-total", "inf"], "--budget-total: Input should be a finite number"),
    ],
)
def test_bad_race_and_budget_values_are_refused_in_one_line(
    capsys: pytest.CaptureFixture[str],
    sqlite_store_url: str,
    tmp_path: Path,
    args: list[str],
    words: str,
) -> None:
    run_cli(
        capsys, sqlite_store_url, "import", str(touch_arff(tmp_path / "t.arff")), "--name", "touch"
    )
    result = run_cli(capsys, sqlite_store_url, "bench", "touch", "-c", "zeror,nb", *args)
    assert result.code == 2
    lines = result.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"touchbench: error: {words}"), result.err
    assert scalar(sqlite_store_url, "SELECT count(*) FROM runs") == 0


def _rows(board: dict[str, Any]) -> list[tuple[Any, ...]]:
    """What a leaderboard says of each row, without the costs (wall times differ)."""
    return [
        (
            row["rank"],
            row["classifier"],
            row["mark"],
            row["p_value"],
            row["n_ok"],
            row["metrics"]["f1_weighted"]["mean"],
            row["dropped"],
        )
        for row in board["leaderboard"]
    ]


def test_a_raced_run_says_what_it_dropped_in_every_view(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    path = touch_arff(tmp_path / "t.arff", n=150)
    run_cli(capsys, sqlite_store_url, "import", str(path), "--name", "touch")
    bench = run_cli(
        capsys, sqlite_store_url, "bench", "touch", "-c", "zeror,nb,j48", *RACE, "-j", "2"
    )
    assert bench.code == 0, bench.err
    assert "dropped after fold 3" in bench.out and "raced at alpha 0.01" in bench.err
    board = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "--json").json()
    assert board["race"]["alpha"] == 0.01 and board["race"]["dropped"] == 1
    assert board["budget"] is None
    zeror = next(row for row in board["leaderboard"] if row["classifier"] == "zeror")
    assert zeror["dropped"]["reason"] == "race" and zeror["dropped"]["after_fold"] == 3
    assert zeror["n_ok"] == 3 and zeror["dropped"]["p_value"] <= 0.01
    assert zeror["dropped"]["mean"] == pytest.approx(zeror["metrics"]["f1_weighted"]["mean"])
    assert zeror["dropped"]["leader"] == board["baseline"]
    assert all(row["dropped"] is None for row in board["leaderboard"] if row is not zeror)
    # the stored run: 3 + 5 + 5 results, one drop record
    assert scalar(sqlite_store_url, "SELECT count(*) FROM fold_results") == 13
    assert scalar(sqlite_store_url, "SELECT after_fold FROM entry_drops") == 3
    markdown = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "-f", "markdown").out
    assert "zeror (dropped after fold 3 (p " in markdown and "raced at alpha 0.01" in markdown
    csv = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "-f", "csv").out
    assert "dropped_after_fold" in csv.splitlines()[0] and ',3,"dropped after fold 3 (p ' in csv
    arff = run_cli(capsys, sqlite_store_url, "leaderboard", "1", "-f", "arff").out
    assert arff.startswith("% raced at alpha 0.01") and "% zeror: dropped after fold 3" in arff
    report = tmp_path / "report.html"
    assert run_cli(capsys, sqlite_store_url, "report", "1", "-o", str(report)).code == 0
    html = report.read_text(encoding="utf-8")
    assert "dropped after fold 3" in html and "raced at alpha 0.01" in html


def _execute(url: str, statement: str) -> None:
    engine = store_engine(url)
    try:
        with engine.begin() as connection:
            connection.execute(text(statement))
    finally:
        engine.dispose()


def test_a_budget_that_fits_cuts_nothing_and_a_resume_gets_what_is_left(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    run_cli(
        capsys, sqlite_store_url, "import", str(touch_arff(tmp_path / "t.arff")), "--name", "touch"
    )
    bench = run_cli(
        capsys, sqlite_store_url, "bench", "touch", "-c", "zeror,nb", "--target", "gesture",
        "-k", "3", "--budget-total", "60", "--json",
    )  # fmt: skip
    assert bench.code == 0, bench.err
    board = bench.json()
    assert 0 < board["budget"].pop("minutes_spent") < 60
    assert board["budget"] == {
        "minutes": 60.0,
        "cut": [],
        "tasks_not_run": 0,
        "note": "total budget 60 min: 0 task(s) not run",
    }
    assert board["race"] is None
    # the run, interrupted once its budget was spent with nb's folds still to run: the
    # resume gets what is left of the budget (nothing), not the whole budget again
    _execute(sqlite_store_url, "DELETE FROM fold_results WHERE classifier = 'nb'")
    _execute(sqlite_store_url, "UPDATE runs SET status = 'interrupted', seconds_spent = 3600")
    resumed = run_cli(capsys, sqlite_store_url, "bench", "--resume", "1", "--json")
    assert resumed.code == 0, resumed.err
    budget = resumed.json()["budget"]
    assert budget["cut"] == ["nb"] and budget["tasks_not_run"] == 3
    assert budget["minutes_spent"] >= 60
    assert scalar(sqlite_store_url, "SELECT count(*) FROM fold_results") == 3
    listed = run_cli(capsys, sqlite_store_url, "runs", "--json").json()["runs"][0]
    assert (listed["tasks_done"], listed["tasks_dropped"], listed["tasks"]) == (3, 3, 6)
    assert "3 done, 3 dropped / 6" in run_cli(capsys, sqlite_store_url, "runs").out


@pytest.mark.slow
def test_a_race_interrupted_by_ctrl_c_resumes_to_the_uninterrupted_leaderboard(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    """The gate entry predicts the majority class (zero-rule): the race drops it after the
    third fold.  The run is interrupted while its third fold waits at the gate, before the
    first decision; the resumed run goes on racing."""
    path = touch_arff(tmp_path / "t.arff", n=150)
    run_cli(capsys, store_url, "import", str(path), "--name", "touch")
    args = ["touch", "-c", "gate,nb,j48", *RACE, "-j", "1"]
    gate = Gate(tmp_path / "gate")
    child = bench_process(store_url, gate, *args)
    gate.let_through(2)
    wait_for_results(store_url, child, 6)  # two rounds of three
    gate.wait_started(3)
    child.send_signal(signal.SIGINT)
    _, err = child.communicate(timeout=60)
    assert child.returncode == 130, err.decode()
    assert scalar(store_url, "SELECT status FROM runs WHERE id = 1") == "interrupted"
    stored = scalar(store_url, "SELECT count(*) FROM fold_results")
    assert 6 <= stored < 9
    gate.open()
    environment = {**os.environ, **gate.environment()}
    # the resumed run, then an uninterrupted one, in one process (the gate is a plugin, read
    # when the catalogue is imported: not in this one)
    commands = [["--db", store_url, "bench", *c] for c in (["--resume", "1"], args)]
    done = subprocess.run(
        [sys.executable, "-c", BENCH_TWICE, json.dumps(commands)],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr.decode()
    resumed, uninterrupted = (
        _rows(run_cli(capsys, store_url, "leaderboard", run_id, "--json").json())
        for run_id in ("1", "2")
    )
    assert resumed == uninterrupted
    gate_row = next(row for row in resumed if row[1] == "gate")
    assert gate_row[6]["after_fold"] == 3 and gate_row[4] == 3


def test_a_race_on_data_that_allow_fewer_folds_is_refused_before_it_exists(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    path = tmp_path / "tiny.arff"
    rows = "".join(f"{i},{label}\n" for i, label in enumerate("xxyyzz"))
    path.write_text(f"@relation tiny\n@attribute a numeric\n@attribute c {{x,y,z}}\n@data\n{rows}")
    run_cli(capsys, sqlite_store_url, "import", str(path))
    result = run_cli(
        capsys, sqlite_store_url, "bench", "tiny", "-c", "zeror,nb", "--race", "-k", "3"
    )
    assert result.code == 2
    assert result.err.strip() == (
        "touchbench: error: --race: needs at least 3 folds in all, and the data allow 2 (the "
        "smallest class has only 2 instance(s): using 2 folds instead of 3)"
    )
    assert scalar(sqlite_store_url, "SELECT count(*) FROM runs") == 0
