"""`touchbench leaderboard RUN --aggregate recording|window`: a finished run's leaderboard
scored again from its stored test-fold predictions, without fitting anything, equal fold by
fold to the run scored that way from the start; and refused in one line where it cannot
be.  SQLite: the store only reads what runs stored (tests/app/services/
test_fold_predictions.py reads the predictions back on both stores)."""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from html import unescape
from itertools import pairwise
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import create_engine, text

from tests.support.cli_runner import one_error_line, run_cli, run_cli_captured
from tests.support.figures import svg_texts
from tests.support.recordings import PER_RECORDING, recorded_windows, store_dataset
from tests.support.stores import copy_sqlite
from tests.support.synthetic import touch_arff
from touchbench.app.services.runs import run_leaderboard
from touchbench.app.store.database import Store
from touchbench.app.store.runs import load_results
from touchbench.benchmark.evaluation.metrics import COST_METRICS
from touchbench.benchmark.results import TaskKey, TaskResult

#: Deterministic classifiers: with probabilities (pooled), without them (votes), a tree and
#: a vote computed from its members' fold predictions.
CLASSIFIERS = "nb,ridge,zeror,j48,ibk,voting-hard"
COSTS = {*COST_METRICS, "inner_time", "inner_cpu_time"}
RESCORED = "re-scored per recording from the run's stored test-fold predictions"


@dataclass(frozen=True)
class _Built:
    """The runs every test reads, made once for the module in a template store; each test
    gets a copy of its own (:func:`db`), so that nothing one test does reaches another."""

    path: Path
    two_runs: tuple[int, int]
    refused_runs: dict[str, int]


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> _Built:
    """Data set `takes` and, in this order, the runs of :func:`two_runs` and of
    :func:`refused_runs`."""
    folder = tmp_path_factory.mktemp("aggregate")
    path = folder / "touchbench.db"
    url = f"sqlite:///{path}"
    store_dataset(url, recorded_windows(), "takes")
    two = _bench(url), _bench(url, "--aggregate", "recording")
    return _Built(path, two, _refused_runs(url, folder))


@pytest.fixture
def db(tmp_path: Path, built: _Built) -> str:
    """A store of the test's own: a copy of the module's template (:func:`built`)."""
    return copy_sqlite(built.path, tmp_path / "touchbench.db")


@pytest.fixture
def no_fitting(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The engine and every estimator refuse to run: what is asked of them is counted."""
    asked: list[str] = []

    def refuse(what: str) -> Any:
        def refused(*args: Any, **kwargs: Any) -> Any:
            asked.append(what)
            raise AssertionError(f"{what} called: a leaderboard fitted again")

        return refused

    monkeypatch.setattr("touchbench.benchmark.run.engine.run_tasks", refuse("run_tasks"))
    monkeypatch.setattr("touchbench.benchmark.run.task.build_estimator", refuse("build"))
    monkeypatch.setattr("touchbench.benchmark.estimators.build_estimator", refuse("build"))
    return asked


def _bench(db: str, *options: str) -> int:
    result = run_cli_captured(
        db, "bench", "takes", "-c", CLASSIFIERS, "-k", "4", "--seed", "3", "--json", *options
    )
    assert result.code == 0, result.err
    return int(result.json()["run_id"])


def _scores(result: TaskResult) -> dict[str, float]:
    return {k: v for k, v in result.metrics.items() if k not in COSTS}


def _assert_same_folds(ours: list[TaskResult], theirs: list[TaskResult]) -> None:
    """Every fold of ``ours`` scores exactly as the same fold of ``theirs``."""
    mine: dict[TaskKey, TaskResult] = {r.key: r for r in ours}
    other: dict[TaskKey, TaskResult] = {r.key: r for r in theirs}
    assert set(mine) == set(other) and len(mine) == 9 * 4  # 6 entries, 3 helpers of the vote
    for key, result in mine.items():
        assert result.ok, result.error
        assert _scores(result) == _scores(other[key]), key  # exactly: same floats
        assert result.confusion == other[key].confusion, key
        assert result.calibration == other[key].calibration, key
        assert result.per_target == other[key].per_target, key


def _ranked(board: dict[str, Any]) -> list[tuple[Any, ...]]:
    """Each row's rank, name, mark, p-value and scores (not its costs)."""
    return [
        (
            row["rank"],
            row["classifier"],
            row["mark"],
            row["p_value"],
            {k: v for k, v in row["metrics"].items() if k not in COSTS},
        )
        for row in board["leaderboard"]
    ]


@pytest.fixture
def two_runs(built: _Built) -> tuple[int, int]:
    """Run 1 scored per window, run 2 per recording: the same tasks on the same folds."""
    return built.two_runs


def test_rescored_runs_equal_runs_scored_so_from_the_start(
    capsys: pytest.CaptureFixture[str],
    db: str,
    two_runs: tuple[int, int],
    no_fitting: list[str],
) -> None:
    """A per-window run re-scored per recording is, fold by fold and metric by metric, the
    same run made with `bench --aggregate recording` (same folds and seed), and the other
    way round; nothing is fitted."""
    windows, recordings = two_runs
    store = Store(db)
    try:
        as_windows, as_recordings = load_results(store, windows), load_results(store, recordings)
        rescored = run_leaderboard(store, windows, aggregate="recording")
        assert rescored.rescored == "recording" and rescored.per_recording
        _assert_same_folds(rescored.results, as_recordings)
        back = run_leaderboard(store, recordings, aggregate="window")
        assert back.rescored == "window" and not back.per_recording
        _assert_same_folds(back.results, as_windows)
        # asked as the run scored: its stored scores, nothing re-scored
        same = run_leaderboard(store, windows, aggregate="window")
        assert same.rescored is None and same.results == as_windows
        # the costs stay as the run measured them
        measured = {r.key: r.metrics["fit_time"] for r in as_windows if r.ok}
        assert {r.key: r.metrics["fit_time"] for r in rescored.results} == measured
    finally:
        store.dispose()

    def leaderboard(run: int, *options: str) -> str:
        result = run_cli(capsys, db, "leaderboard", str(run), *options)
        assert result.code == 0, result.err
        return result.out + result.err

    ours = run_cli(capsys, db, "leaderboard", str(windows), "--aggregate", "recording", "--json")
    assert ours.code == 0, ours.err
    board, theirs = ours.json(), run_cli(capsys, db, "leaderboard", str(recordings), "--json")
    assert board["aggregate"] == theirs.json()["aggregate"] == "recording"
    assert _ranked(board) == _ranked(theirs.json())  # the same ranks, marks and t-tests
    assert board["notes"][0].startswith(PER_RECORDING) and board["notes"][1].startswith(RESCORED)
    helpers = "fitted only as members of ensembles: logistic, rf, svm-rbf ("
    assert [note.startswith(helpers) for note in board["notes"][2:]] == [True]
    back_board = run_cli(
        capsys, db, "leaderboard", str(recordings), "--aggregate", "window", "--json"
    ).json()
    plain = run_cli(capsys, db, "leaderboard", str(windows), "--json").json()
    assert back_board["aggregate"] == "window" and _ranked(back_board) == _ranked(plain)
    assert back_board["notes"][0].startswith("re-scored per window from the run's stored")

    # every view says it
    table = leaderboard(windows, "--aggregate", "recording")
    assert "scored per recording" in table and PER_RECORDING in table
    assert RESCORED in " ".join(table.split())
    rows = list(
        csv.DictReader(io.StringIO(leaderboard(windows, "--aggregate", "recording", "-f", "csv")))
    )
    assert {row["aggregate"] for row in rows} == {"recording"}
    assert [row["classifier"] for row in rows] == [row[1] for row in _ranked(board)]
    plain_rows = csv.DictReader(io.StringIO(leaderboard(windows, "-f", "csv")))
    assert {row["aggregate"] for row in plain_rows} == {"window"}
    markdown = leaderboard(windows, "--aggregate", "recording", "-f", "markdown")
    assert PER_RECORDING in markdown and RESCORED in markdown
    arff = leaderboard(windows, "--aggregate", "recording", "-f", "arff")
    assert arff.startswith(f"% {PER_RECORDING}")
    assert no_fitting == []


@pytest.fixture
def refused_runs(built: _Built) -> dict[str, int]:
    """Runs that cannot be scored per recording (see :func:`_refused_runs`)."""
    return dict(built.refused_runs)


def _refused_runs(db: str, folder: Path) -> dict[str, int]:
    """Runs that cannot be scored per recording: on a data set without recordings, on one
    with a recording of two labels, a run imported from a results file, and a run stored
    before runs kept their fold predictions (its predictions deleted)."""
    store_dataset(db, recorded_windows(mixed=True), "mixed")
    path = touch_arff(folder / "touch.arff", n=60, with_place=False)
    assert run_cli_captured(db, "import", str(path), "--name", "touch").code == 0
    runs = {}
    for name, dataset in (("ungrouped", "touch"), ("mixed", "mixed"), ("old", "takes")):
        made = run_cli_captured(db, "bench", dataset, "-c", "nb,zeror", "-k", "4", "--json")
        assert made.code == 0, made.err
        runs[name] = int(made.json()["run_id"])
    exported = folder / "results.arff"
    exported.write_text(run_cli_captured(db, "leaderboard", str(runs["old"]), "-f", "arff").out)
    imported = run_cli_captured(db, "import-results", str(exported), "--dataset", "takes", "--json")
    assert imported.code == 0, imported.err
    runs["imported"] = int(imported.json()["id"])
    engine = create_engine(db)
    try:
        with engine.begin() as connection:
            connection.execute(
                text("DELETE FROM fold_predictions WHERE run_id = :run"), {"run": runs["old"]}
            )
    finally:
        engine.dispose()
    return runs


def test_rescoring_is_refused_in_one_line_where_it_cannot_be(
    capsys: pytest.CaptureFixture[str],
    db: str,
    refused_runs: dict[str, int],
    no_fitting: list[str],
) -> None:
    runs = refused_runs
    for name, words in (
        ("ungrouped", "--aggregate: needs windows grouped by recording, and data set 'touch' "),
        ("mixed", "--aggregate: 1 recording(s) hold windows of several values of 'gesture'"),
        ("imported", f"--aggregate: run {runs['imported']} was imported: it holds its scores"),
        ("old", f"--aggregate: run {runs['old']} has no stored fold predictions for 8 of its"),
    ):
        for form in ((), ("--json",), ("-f", "csv")):
            refused = run_cli(
                capsys, db, "leaderboard", str(runs[name]), "--aggregate", "recording", *form
            )
            line = one_error_line(refused, words)
            assert refused.out == "", name
        if name == "old":
            assert "run the benchmark again to score it per recording" in line
    bad = run_cli(capsys, db, "leaderboard", str(runs["old"]), "--aggregate", "take")
    one_error_line(bad, "--aggregate: Input should be 'window' or 'recording'")
    # as the runs scored, each still has its leaderboard
    for run in runs.values():
        shown = run_cli(capsys, db, "leaderboard", str(run), "--aggregate", "window", "--json")
        assert shown.code == 0 and shown.json()["aggregate"] == "window", shown.err
    assert no_fitting == []


def test_leaderboard_help_tells_aggregate(capsys: pytest.CaptureFixture[str], db: str) -> None:
    shown = run_cli(capsys, db, "leaderboard", "--help")
    assert shown.code == 0
    words = " ".join(shown.out.replace("│", " ").split())
    assert "--aggregate" in words and "stored test-fold predictions" in words
    assert "nothing is fitted again" in words


def test_plot_scores_per_recording_when_asked(
    capsys: pytest.CaptureFixture[str],
    db: str,
    tmp_path: Path,
    two_runs: tuple[int, int],
    refused_runs: dict[str, int],
    no_fitting: list[str],
) -> None:
    """`plot RUN --aggregate recording` draws the folds, the CD diagram and a confusion
    matrix of the run scored per recording: those of the run scored so from the start (but
    for the run named in the title), not the run's own; refused in one line for an
    imported run."""
    windows, recordings = two_runs

    def texts(run: int, kind: str, *options: str) -> list[str]:
        out = tmp_path / f"{run}-{kind}-{len(options)}.svg"
        made = run_cli(capsys, db, "plot", str(run), "--kind", kind, "-o", str(out), *options)
        assert made.code == 0, made.err
        return [t.replace(f"run {run}", "run N") for t in svg_texts(out.read_text())]

    for kind in ("folds", "cd", "confusion"):
        rescored = texts(windows, kind, "--aggregate", "recording")
        assert rescored == texts(recordings, kind), kind
        assert rescored != texts(windows, kind), kind
        assert texts(recordings, kind, "--aggregate", "window") == texts(windows, kind), kind
    # the confusion matrix counts the 16 recordings, not their 256 windows
    cells = texts(windows, "confusion", "--aggregate", "recording", "-c", "nb")
    counts = [int(count) for share, count in pairwise(cells) if "." in share and count.isdigit()]
    assert sum(counts) == 16, cells

    imported = refused_runs["imported"]
    for kind in ("folds", "cd", "confusion"):
        refused = run_cli(
            capsys, db, "plot", str(imported), "--kind", kind, "-o", str(tmp_path / "x.svg"),
            "--aggregate", "recording",
        )  # fmt: skip
        one_error_line(refused, f"--aggregate: run {imported} was imported: it holds its scores")
    bad = run_cli(
        capsys, db, "plot", str(windows), "-o", str(tmp_path / "x.svg"), "--aggregate", "take"
    )
    one_error_line(bad, "--aggregate: Input should be 'window' or 'recording'")
    assert not (tmp_path / "x.svg").exists()
    assert no_fitting == []


def test_report_scores_per_recording_when_asked(
    capsys: pytest.CaptureFixture[str],
    db: str,
    tmp_path: Path,
    two_runs: tuple[int, int],
    refused_runs: dict[str, int],
    no_fitting: list[str],
) -> None:
    """`report RUN --aggregate recording` shows the leaderboard the run would have had per
    recording (that of the run scored so from the start), saying so; refused in one line
    for data without recordings."""
    windows, recordings = two_runs
    board = run_cli(capsys, db, "leaderboard", str(recordings), "--json").json()
    report = tmp_path / "report.html"
    made = run_cli(
        capsys, db, "report", str(windows), "-o", str(report), "--aggregate", "recording"
    )
    assert made.code == 0, made.err
    page = " ".join(unescape(report.read_text(encoding="utf-8")).split())
    assert PER_RECORDING in page and RESCORED in page
    for row in board["leaderboard"]:
        mean = row["metrics"]["f1_weighted"]["mean"]
        assert f"<td>{row['classifier']}</td>" in page and f"{mean:.4f}" in page
    as_scored = tmp_path / "plain.html"
    assert run_cli(capsys, db, "report", str(windows), "-o", str(as_scored)).code == 0
    assert RESCORED not in " ".join(unescape(as_scored.read_text(encoding="utf-8")).split())

    for name, words in (
        ("ungrouped", "--aggregate: needs windows grouped by recording"),
        ("mixed", "--aggregate: 1 recording(s) hold windows of several values of 'gesture'"),
    ):
        refused = run_cli(
            capsys, db, "report", str(refused_runs[name]), "-o", str(report), "--aggregate",
            "recording",
        )  # fmt: skip
        one_error_line(refused, words)
    bad = run_cli(capsys, db, "report", str(windows), "-o", str(report), "--aggregate", "take")
    one_error_line(bad, "--aggregate: Input should be 'window' or 'recording'")
    assert no_fitting == []


def test_classes_and_calibration_score_per_recording_when_asked(
    capsys: pytest.CaptureFixture[str],
    db: str,
    tmp_path: Path,
    two_runs: tuple[int, int],
    refused_runs: dict[str, int],
    no_fitting: list[str],
) -> None:
    """`classes` and `calibration RUN --aggregate recording` of a run scored per window are
    those of the same run scored per recording from the start (one pooled prediction per
    recording); refused in one line where the leaderboard is.  The members `voting-hard`
    fitted for itself (helpers: rows of their own) are shown beside the run's classifiers."""
    windows, recordings = two_runs
    listed = run_cli(capsys, db, "classes", str(windows), "--json")
    assert listed.code == 0, listed.err
    names = {entry["classifier"] for entry in listed.json()["classifiers"]}
    assert names == {*CLASSIFIERS.split(","), "logistic", "rf", "svm-rbf"}

    def shown(command: str, run: int, *options: str) -> dict[str, Any]:
        made = run_cli(capsys, db, command, str(run), "--json", *options)
        assert made.code == 0, made.err
        body: dict[str, Any] = made.json()
        return body

    for command in ("classes", "calibration"):
        rescored = shown(command, windows, "--aggregate", "recording")
        assert rescored["aggregate"] == "recording"
        assert rescored["classifiers"] == shown(command, recordings)["classifiers"]
        as_scored = shown(command, windows)
        assert as_scored["aggregate"] == "window"
        assert shown(command, recordings, "--aggregate", "window") == as_scored | {
            "run_id": recordings
        }
    pooled = {
        c["classifier"]: c
        for c in shown("classes", windows, "--aggregate", "recording")["classifiers"]
    }
    for entry in shown("classes", windows)["classifiers"]:
        [per_window] = entry["targets"]
        [per_recording] = pooled[entry["classifier"]]["targets"]
        assert sum(map(sum, per_window["confusion"])) == 16 * sum(
            map(sum, per_recording["confusion"])
        )
    diagram = tmp_path / "reliability.svg"
    drawn = run_cli(
        capsys, db, "calibration", str(windows), "-o", str(diagram), "--aggregate", "recording"
    )
    assert drawn.code == 0 and diagram.read_text().lstrip().startswith("<?xml"), drawn.err

    for command in ("classes", "calibration"):
        refused = run_cli(
            capsys, db, command, str(refused_runs["ungrouped"]), "--aggregate", "recording"
        )
        one_error_line(refused, "--aggregate: needs windows grouped by recording")
        bad = run_cli(capsys, db, command, str(windows), "--aggregate", "take")
        one_error_line(bad, "--aggregate: Input should be 'window' or 'recording'")
    assert no_fitting == []
