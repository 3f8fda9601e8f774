"""`touchbench classifiers / bench / runs / leaderboard`: a stored run and a killed run's resume
on SQLite and PostgreSQL, the views and refusals on SQLite."""

from __future__ import annotations

import csv
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.gate import Gate
from tests.support.rows import count_of, wait_for_count
from tests.support.synthetic import touch_arff
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset, dataset_digest
from touchbench.benchmark.io.arff import loads_arff

METRIC_KEYS = {
    "accuracy",
    "balanced_accuracy",
    "f1_weighted",
    "f1_macro",
    "precision_weighted",
    "recall_weighted",
    "kappa",
    "mcc",
    "roc_auc",
    "log_loss",
    "fit_time",
    "predict_time",
}


def imported(capsys: pytest.CaptureFixture[str], db: str, path: Path) -> int:
    result = run_cli(capsys, db, "import", str(path), "--json")
    assert result.code == 0, result.err
    return int(result.json()["id"])


def test_classifiers_lists_at_least_fifty_with_capabilities(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    result = run_cli(capsys, f"sqlite:///{tmp_path}/t.db", "classifiers", "--json")
    assert result.code == 0
    entries = result.json()["classifiers"]
    ids = {e["id"] for e in entries}
    assert len(entries) >= 50
    assert {"zeror", "j48", "rf", "nb", "ibk", "logistic", "svm-rbf", "mlp", "xgb"} <= ids
    j48 = next(e for e in entries if e["id"] == "j48")
    assert j48["weka_name"] == "weka.classifiers.trees.J48"
    rf = next(e for e in entries if e["id"] == "rf")
    assert rf["weka_name"] is None  # scikit-learn's forest: not WEKA's defaults (issue 13)
    assert rf["probabilities"] is True


def test_bench_json_leaderboard_and_stored_run(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    imported(capsys, store_url, touch_arff(tmp_path / "touch.arff"))
    result = run_cli(
        capsys,
        store_url,
        "bench",
        "touch",
        "--target",
        "gesture",
        "--classifiers",
        "zeror,nb,j48",
        "--folds",
        "3",
        "--json",
    )
    assert result.code == 0, result.err
    report = result.json()
    board = {row["classifier"]: row for row in report["leaderboard"]}
    assert set(board) == {"zeror", "nb", "j48"}
    for row in board.values():
        assert set(row["metrics"]) >= METRIC_KEYS
        assert set(row["metrics"]["f1_weighted"]) == {"mean", "std"}
    assert board["nb"]["metrics"]["accuracy"]["mean"] > 0.8
    assert board["zeror"]["metrics"]["accuracy"]["mean"] < 0.45
    assert report["leaderboard"][-1]["classifier"] == "zeror"
    assert board["zeror"]["mark"] == "*"  # significantly worse than the best
    runs = run_cli(capsys, store_url, "runs", "--json").json()["runs"]
    assert [(r["id"], r["status"], r["tasks_done"], r["tasks"]) for r in runs] == [
        (report["run_id"], "done", 9, 9)
    ]


def test_leaderboard_formats(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    imported(capsys, sqlite_store_url, touch_arff(tmp_path / "touch.arff"))
    run_id = run_cli(
        capsys,
        sqlite_store_url,
        "bench",
        "touch",
        "--target",
        "gesture",
        "--classifiers",
        "zeror,nb",
        "--folds",
        "3",
        "--json",
    ).json()["run_id"]
    as_csv = run_cli(capsys, sqlite_store_url, "leaderboard", str(run_id), "--format", "csv")
    rows = list(csv.DictReader(io.StringIO(as_csv.out)))
    assert [r["classifier"] for r in rows] == ["nb", "zeror"]
    assert float(rows[0]["f1_weighted_mean"]) > float(rows[1]["f1_weighted_mean"])
    markdown = run_cli(capsys, sqlite_store_url, "leaderboard", str(run_id), "--format", "markdown")
    assert "| 1 | nb |" in markdown.out and "(v/ /*)" in markdown.out
    table = run_cli(capsys, sqlite_store_url, "leaderboard", str(run_id), "--baseline", "zeror")
    assert table.code == 0 and "nb" in table.out
    by_accuracy = run_cli(
        capsys, sqlite_store_url, "leaderboard", str(run_id), "--metric", "accuracy", "--json"
    ).json()
    assert by_accuracy["metric"] == "accuracy"
    arff = run_cli(capsys, sqlite_store_url, "leaderboard", str(run_id), "--format", "arff")
    results = loads_arff(arff.out)
    names = [a.name for a in results.schema.attributes]
    assert names[:4] == ["Key_Dataset", "Key_Run", "Key_Fold", "Key_Scheme"]
    assert "Percent_correct" in names and "Weighted_avg_F_measure" in names
    assert results.n_instances == 6


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--classifiers", "rff"], "did you mean 'rf'"),
        (["--target", "colour"], "colour"),
    ],
)
def test_bad_benchmark_requests_exit_2(
    args: list[str],
    expected: str,
    capsys: pytest.CaptureFixture[str],
    sqlite_store_url: str,
    tmp_path: Path,
) -> None:
    imported(capsys, sqlite_store_url, touch_arff(tmp_path / "touch.arff", n=30))
    base = ["bench", "touch", "--target", "gesture", "--classifiers", "zeror"]
    if "--target" in args:
        base = ["bench", "touch", "--classifiers", "zeror"]
    if "--classifiers" in args:
        base = ["bench", "touch", "--target", "gesture"]
    result = run_cli(capsys, sqlite_store_url, *base, *args)
    assert result.code == 2, result.err
    assert len(result.err.strip().splitlines()) == 1
    assert expected in result.err


def test_too_many_folds_fall_back_with_a_warning(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    imported(capsys, sqlite_store_url, touch_arff(tmp_path / "touch.arff", n=30))
    result = run_cli(
        capsys,
        sqlite_store_url,
        "bench",
        "touch",
        "--target",
        "gesture",
        "--classifiers",
        "zeror",
        "--folds",
        "40",
        "--json",
    )
    assert result.code == 0, result.err
    assert "only 10 instance(s): using 10 folds instead of 40" in " ".join(result.err.split())
    run = run_cli(capsys, sqlite_store_url, "runs", "--json").json()["runs"][0]
    assert (run["config"]["folds"], run["config"]["folds_requested"], run["tasks"]) == (10, 40, 10)


def test_one_class_target_and_unknown_run_exit_2(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    imported(
        capsys,
        sqlite_store_url,
        touch_arff(tmp_path / "touch.arff", one_class=True, with_place=False),
    )
    one = run_cli(capsys, sqlite_store_url, "bench", "touch", "--classifiers", "zeror")
    assert one.code == 2 and "single class" in one.err
    unknown = run_cli(capsys, sqlite_store_url, "leaderboard", "999")
    assert unknown.code == 2 and "no run '999'" in unknown.err
    resume = run_cli(capsys, sqlite_store_url, "bench", "--resume", "999")
    assert resume.code == 2 and "no run '999'" in resume.err


@pytest.mark.slow
def test_a_killed_run_resumes_without_repeating_or_duplicating(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    imported(capsys, store_url, touch_arff(tmp_path / "touch.arff", n=300))
    gate = Gate(tmp_path / "gate")  # its fits wait for the test: killed after exactly 13 tasks
    environment = {**os.environ, **gate.environment()}
    bench = [sys.executable, "-m", "touchbench.app.cli.main", "--db", store_url, "bench"]
    command = [*bench, "touch", "--target", "gesture", "-c", "zeror,gate,nb", "--folds", "10"]
    child = subprocess.Popen(
        command, env=environment, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    gate.let_through(3)
    deadline = time.monotonic() + 120
    wait_for_count(store_url, "SELECT count(*) FROM fold_results", 13, child, deadline)
    gate.wait_started(4)
    os.kill(child.pid, signal.SIGKILL)
    child.wait()
    assert count_of(store_url, "SELECT count(*) FROM fold_results") == 13
    first_ids = count_of(store_url, "SELECT max(id) FROM fold_results")

    gate.open()
    resumed = subprocess.run(
        [*bench, "--resume", "1", "--json"], env=environment, capture_output=True, timeout=600
    )
    assert resumed.returncode == 0, resumed.stderr.decode()
    assert count_of(store_url, "SELECT count(*) FROM fold_results") == 30
    distinct = count_of(
        store_url,
        "SELECT count(*) FROM (SELECT DISTINCT classifier, repeat, fold FROM fold_results) t",
    )
    assert distinct == 30
    # rows written before the kill are kept, not rewritten
    assert count_of(store_url, f"SELECT count(*) FROM fold_results WHERE id <= {first_ids}") == 13
    board = json.loads(resumed.stdout)["leaderboard"]
    assert {row["classifier"] for row in board} == {"zeror", "gate", "nb"}
    assert all(row["n_ok"] == 10 for row in board)


def test_an_empty_dataset_cannot_be_benchmarked(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    # `import` refuses a file without instances, so the empty data set is stored directly.
    store = Store(sqlite_store_url)
    empty = loads_arff("@relation e\n@attribute a numeric\n@attribute c {x,y}\n@data\n")
    add_dataset(store, empty, sha256=dataset_digest(empty))
    store.dispose()
    result = run_cli(capsys, sqlite_store_url, "bench", "e", "-c", "zeror")
    assert result.code == 2 and "dataset 'e' has no instances" in result.err
    assert run_cli(capsys, sqlite_store_url, "runs", "--json").json() == {"runs": []}


def test_classifiers_say_the_cost_on_a_data_sets_shape(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    url = f"sqlite:///{tmp_path}/t.db"
    hinted = run_cli(capsys, url, "classifiers", "--json").json()
    assert hinted["cost"].startswith("the catalogue's hint at 2,000 instances")
    run_cli(capsys, url, "import", str(touch_arff(tmp_path / "t.arff", n=60)), "--name", "small")
    shaped = run_cli(capsys, url, "classifiers", "--json", "--dataset", "small").json()
    assert shaped["cost"].startswith("estimated for small: 60 instances x ")
    before = {e["id"]: e["cost"] for e in hinted["classifiers"]}
    after = {e["id"]: e["cost"] for e in shaped["classifiers"]}
    # slow at the reference shape, fast on 60 instances: the estimate, not the label
    assert before["gp"] == "slow" and after["gp"] == "fast"
    assert set(after.values()) <= {"fast", "slow"}
    listing = run_cli(capsys, url, "classifiers", "--dataset", "small").out
    assert "(cost: estimated for small: 60 instances" in listing
    missing = run_cli(capsys, url, "classifiers", "--dataset", "nope")
    assert missing.code == 2 and len(missing.err.strip().splitlines()) == 1
