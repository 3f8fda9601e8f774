"""A raced run whose dropped entry has the highest mean over the few folds it ran: the entries
that ran every fold rank first, among themselves, then those a race dropped or a budget cut,
marked so, in every view (``leaderboard`` table, CSV, JSON and Markdown, the HTML report,
the API).  The run is stored fold by fold (deterministic scores, nothing fitted): ``nb``
leads the first folds and falls, ``bagging`` was dropped after fold 3 with a mean of 0.85
over them, above every live entry's mean over 5."""

from __future__ import annotations

import csv
import io
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server
from tests.support.synthetic import touch_arff
from touchbench.app.schemas.run_config import RaceConfig, RunConfig
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset, dataset_digest
from touchbench.app.store.drops import record_drop
from touchbench.app.store.runs import create_run, finish_run, record_result
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.results import Drop, TaskKey, TaskResult

FOLDS = 5
#: Each entry's score on each fold it ran (weighted F1 and accuracy alike).
SCORES = {
    "nb": [0.90, 0.91, 0.92, 0.72, 0.70],  # mean 0.83
    "j48": [0.80, 0.81, 0.79, 0.80, 0.80],  # mean 0.80
    "bagging": [0.85, 0.86, 0.84],  # dropped by the race after fold 3: mean 0.85
    "rf": [0.84, 0.84],  # cut by the budget after fold 2: mean 0.84
}
DROPS = (
    Drop("bagging", "race", 3, p_value=0.004, leader="nb", mean=0.85),
    Drop("rf", "budget", 2),
)
#: Live first by their means over every fold, then the stopped ones by theirs.
ORDER = ["nb", "j48", "bagging", "rf"]


def stored_race(url: str, tmp_path: Path) -> int:
    """A done run raced at 0.01 with a total budget, stored with :data:`SCORES` and
    :data:`DROPS`; its id."""
    store = Store(url)
    try:
        data = read_arff(touch_arff(tmp_path / "touch.arff", n=30, with_place=False))
        dataset, _ = add_dataset(store, data, sha256=dataset_digest(data), name="touch")
        run = create_run(
            store,
            dataset_id=dataset.id,
            kind="multiclass",
            targets=["gesture"],
            classifiers=list(SCORES),
            config=RunConfig(
                folds=FOLDS,
                repeats=1,
                seed=0,
                n_tasks=FOLDS * len(SCORES),
                race=RaceConfig(alpha=0.01),
                budget_total=10.0,
            ),
        )
        for classifier, scores in SCORES.items():
            for fold, score in enumerate(scores):
                metrics = {"f1_weighted": score, "accuracy": score, "fit_time": 0.01}
                confusion = [[2, 0, 0], [0, 2, 0], [0, 1, 1]]
                key = TaskKey(classifier, 0, fold)
                record_result(store, run.id, TaskResult(key, "ok", None, metrics, confusion, 24, 6))
        for drop in DROPS:
            record_drop(store, run.id, drop)
        finish_run(store, run.id, "done")
        return run.id
    finally:
        store.dispose()


def _check_board(board: dict[str, object]) -> None:
    rows = board["leaderboard"]
    assert isinstance(rows, list)
    assert [row["classifier"] for row in rows] == ORDER
    assert [row["rank"] for row in rows] == [1, 2, 3, 4]
    assert board["baseline"] == "nb"
    assert [row["dropped"] and row["dropped"]["reason"] for row in rows] == [
        None,
        None,
        "race",
        "budget",
    ]
    assert [row["n_ok"] for row in rows] == [5, 5, 3, 2]
    bagging = rows[2]["metrics"]["f1_weighted"]["mean"]
    assert bagging == pytest.approx(0.85) and bagging > rows[0]["metrics"]["f1_weighted"]["mean"]


def _order(text: str) -> list[str]:
    """The entries in the order their rows come in ``text`` (a table, a page)."""
    return sorted(ORDER, key=lambda name: text.index(f" {name} "))


def test_entries_that_ran_every_fold_rank_before_dropped_ones_in_every_view(
    capsys: pytest.CaptureFixture[str],
    sqlite_store_url: str,
    tmp_path: Path,
    make_sqlite_server: Callable[..., Server],
) -> None:
    db = sqlite_store_url
    run = str(stored_race(db, tmp_path))

    shown = run_cli(capsys, db, "leaderboard", run, "--json")
    assert shown.code == 0, shown.err
    _check_board(shown.json())

    table = run_cli(capsys, db, "leaderboard", run)
    assert table.code == 0, table.err
    cells = [[cell.strip() for cell in line.split("│")[1:-1]] for line in table.out.splitlines()]
    rows = [row for row in cells if row and row[0].isdigit()]
    assert [(row[0], row[1]) for row in rows] == [(str(i), c) for i, c in enumerate(ORDER, 1)]
    assert rows[2][-1].startswith("dropped after fold 3 (p 0.004 against nb")
    assert rows[3][-1] == "cut by the budget after fold 2, 2 folds run"

    as_csv = run_cli(capsys, db, "leaderboard", run, "-f", "csv").out
    lines = list(csv.DictReader(io.StringIO(as_csv)))
    assert [(line["rank"], line["classifier"]) for line in lines] == [
        (str(rank), name) for rank, name in enumerate(ORDER, start=1)
    ]
    assert [line["dropped_after_fold"] for line in lines] == ["", "", "3", "2"]

    markdown = run_cli(capsys, db, "leaderboard", run, "-f", "markdown").out
    assert _order(markdown) == ORDER
    assert "bagging (dropped after fold 3 (p " in markdown

    report = tmp_path / "report.html"
    made = run_cli(capsys, db, "report", run, "-o", str(report), "--confusions", "0")
    assert made.code == 0, made.err
    html = report.read_text(encoding="utf-8")
    board_html = html[html.index("<h3>Leaderboard</h3>") :]
    board_html = board_html[: board_html.index("</tbody>")]
    assert sorted(ORDER, key=lambda name: board_html.index(f"<td>{name}</td>")) == ORDER

    server = make_sqlite_server()
    answered = server.client.get(f"/api/runs/{run}/leaderboard")
    assert answered.status_code == 200, answered.text
    _check_board(answered.json())
    page = server.client.get(f"/fragments/runs/{run}/leaderboard")
    assert page.status_code == 200, page.text
    rows_html = page.text[page.text.index("<tbody>") :]
    assert sorted(ORDER, key=lambda name: rows_html.index(f'data-classifier="{name}"')) == ORDER
    assert 'data-classifier="bagging" class="dropped"' in rows_html
