"""`touchbench import-results` and `leaderboard --beside`: WEKA Experimenter's results
files as runs of their own, ranked beside ours, on SQLite and PostgreSQL."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.synthetic import touch_arff

UC3M = "uc3m-touch"


def _bench(capsys: pytest.CaptureFixture[str], db: str, *options: str) -> int:
    result = run_cli(capsys, db, "bench", "touch", "-c", "j48,nb", "--json", *options)
    assert result.code == 0, result.err
    return int(result.json()["run_id"])


def _exported(capsys: pytest.CaptureFixture[str], db: str, run: int, path: Path) -> Path:
    result = run_cli(capsys, db, "leaderboard", str(run), "--format", "arff")
    assert result.code == 0, result.err
    path.write_text(result.out, encoding="utf-8")
    return path


@pytest.fixture
def touch(capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path) -> str:
    path = touch_arff(tmp_path / "touch.arff", n=90, with_place=False)
    assert run_cli(capsys, store_url, "import", str(path)).code == 0
    return store_url


def test_our_results_file_imports_back_ranks_beside_us_and_reports_and_compares(
    capsys: pytest.CaptureFixture[str], touch: str, tmp_path: Path
) -> None:
    """Our run's results file imports back as a run that ranks beside ours; `report` and
    `compare` put the imported classifiers beside ours (one run and import for both)."""
    ours = _bench(capsys, touch, "--folds", "5")
    results = _exported(capsys, touch, ours, tmp_path / "results.arff")
    imported = run_cli(
        capsys, touch, "import-results", str(results), "--dataset", "touch", "--json"
    )
    assert imported.code == 0, imported.err
    run = imported.json()
    assert run["status"] == "done" and run["targets"] == ["gesture"]
    assert run["classifiers"] == ["J48", "NaiveBayes"]
    assert run["config"]["origin"] == "imported" and run["tasks_done"] == 10
    schemes = {s["classifier"]: s for s in run["config"]["schemes"]}
    assert schemes["J48"]["scheme"] == "weka.classifiers.trees.J48"
    assert schemes["J48"]["options"] == "-C 0.25 -M 2"

    mine = run_cli(capsys, touch, "leaderboard", str(ours), "--json").json()
    theirs = run_cli(capsys, touch, "leaderboard", str(run["id"]), "--json").json()
    score = {r["classifier"]: r["metrics"]["f1_weighted"]["mean"] for r in mine["leaderboard"]}
    imported_score = {
        r["classifier"]: r["metrics"]["f1_weighted"]["mean"] for r in theirs["leaderboard"]
    }
    assert imported_score["J48"] == pytest.approx(score["j48"], abs=1e-12)
    assert imported_score["NaiveBayes"] == pytest.approx(score["nb"], abs=1e-12)

    both = run_cli(
        capsys, touch, "leaderboard", str(ours), "--beside", str(run["id"]), "--json"
    ).json()
    rows = {r["classifier"]: r for r in both["leaderboard"]}
    assert set(rows) == {"j48", "nb", "J48", "NaiveBayes"}
    assert rows["J48"]["run_id"] == run["id"] and rows["j48"]["run_id"] is None
    [beside] = both["beside"]
    assert beside["origin"] == "imported" and beside["test"] == "by fold number"
    assert "not the same test instances" in beside["note"]
    # the same folds, read back: the t-test compares them, and finds them equal
    others = [r for r in both["leaderboard"] if r["classifier"] != both["baseline"]]
    assert all(r["tested"] for r in others)
    twin = {"j48": "J48", "nb": "NaiveBayes"}
    assert rows[twin.get(both["baseline"], both["baseline"])]["mark"] == ""
    table = run_cli(capsys, touch, "leaderboard", str(ours), "--beside", str(run["id"]))
    assert table.code == 0 and "folds paired by number" in table.err

    # report and compare put the imported classifiers beside ours
    compared = run_cli(capsys, touch, "compare", str(ours), str(run["id"]), "--json")
    assert compared.code == 0, compared.err
    ranked = {row["classifier"] for row in compared.json()["classifiers"]}
    assert ranked == {"j48", "nb", "J48", "NaiveBayes"}
    assert any(
        f"run {run['id']}" in note and "paired by number" in note
        for note in compared.json()["notes"]
    )
    page = tmp_path / "report.html"
    made = run_cli(capsys, touch, "report", str(ours), str(run["id"]), "-o", str(page))
    assert made.code == 0, made.err
    html = page.read_text(encoding="utf-8")
    assert "folds paired by number" in html and ">NaiveBayes<" in html


def test_runs_whose_folds_do_not_pair_compare_by_their_means(
    capsys: pytest.CaptureFixture[str], touch: str, tmp_path: Path
) -> None:
    five = _bench(capsys, touch, "--folds", "5")
    three = _bench(capsys, touch, "--folds", "3")
    same = _bench(capsys, touch, "--folds", "5")
    board = run_cli(
        capsys,
        touch,
        "leaderboard",
        str(five),
        "--beside",
        str(three),
        "--beside",
        str(same),
        "--json",
    ).json()
    tests = {b["run_id"]: b["test"] for b in board["beside"]}
    assert tests == {three: "means", same: "paired"}
    rows = {r["classifier"]: r for r in board["leaderboard"]}
    assert set(rows) == {
        "j48",
        "nb",
        f"j48@run{three}",
        f"nb@run{three}",
        f"j48@run{same}",
        f"nb@run{same}",
    }
    assert not rows[f"nb@run{three}"]["tested"] and rows[f"nb@run{three}"]["mark"] == ""
    text = run_cli(capsys, touch, "leaderboard", str(five), "--beside", str(three))
    assert "means only" in text.err and " = " in text.out


def test_bad_results_input_is_one_line_exit_2(
    capsys: pytest.CaptureFixture[str], touch: str, tmp_path: Path
) -> None:
    data = touch_arff(tmp_path / "plain.arff", n=30, with_place=False)
    refused = run_cli(capsys, touch, "import-results", str(data), "--dataset", "touch")
    assert refused.code == 2 and "plain.arff: not a WEKA Experimenter results file" in refused.err
    assert len(refused.err.strip().splitlines()) == 1
    ours = _bench(capsys, touch, "--folds", "5")
    results = _exported(capsys, touch, ours, tmp_path / "results.arff")
    unknown = run_cli(capsys, touch, "import-results", str(results))
    assert unknown.code == 2
    assert unknown.err.startswith("touchbench: error: --dataset: no stored data set has")
    wrong = run_cli(
        capsys, touch, "import-results", str(results), "--dataset", "touch", "--target", "x"
    )
    assert wrong.code == 2 and "--target: 'x' is not a target" in wrong.err
    other = run_cli(capsys, touch, "leaderboard", str(ours), "--beside", str(ours))
    assert other.code == 2 and "--beside: run" in other.err
    runs = run_cli(capsys, touch, "runs", "--json").json()["runs"]
    assert [r["id"] for r in runs] == [ours]


@pytest.mark.shared
def test_the_papers_results_import_with_their_names_and_scores(
    capsys: pytest.CaptureFixture[str], store_url: str, shared_datasets: Path
) -> None:
    for robot in ("mini", "maggie"):
        data = shared_datasets / UC3M / robot / "gesture_and_place.arff"
        assert run_cli(capsys, store_url, "import", str(data), "--name", robot).code == 0
    mini = shared_datasets / UC3M / "mini" / "weka_results_gesture.arff"
    ambiguous = run_cli(capsys, store_url, "import-results", str(mini))
    assert ambiguous.code == 2 and "(mini, maggie): name the one" in ambiguous.err
    expected = {
        ("mini", "gesture"): {"RandomForest": 0.844, "Logistic": 0.842, "LMT": 0.840, "SMO": 0.798},
        ("maggie", "gesture"): {
            "RandomForest": 0.851,
            "FURIA": 0.825,
            "SMO": 0.806,
            "J48": 0.797,
            "IBk": 0.727,
            "NaiveBayes": 0.572,
        },
        ("maggie", "place"): {"NeuralNetwork": 0.963, "RandomForest": 0.963, "SMO": 0.959},
    }
    for (robot, task), scores in expected.items():
        path = shared_datasets / UC3M / robot / f"weka_results_{task}.arff"
        result = run_cli(
            capsys, store_url, "import-results", str(path), "--dataset", robot, "--json"
        )
        assert result.code == 0, result.err
        run = result.json()
        assert run["targets"] == [task] and run["status"] == "done"  # from WEKA's Remove filter
        board = run_cli(capsys, store_url, "leaderboard", str(run["id"]), "--json").json()
        means = {r["classifier"]: r["metrics"]["f1_weighted"]["mean"] for r in board["leaderboard"]}
        for name, score in scores.items():
            assert means[name] == pytest.approx(score, abs=5e-4), name
    repeats = run_cli(capsys, store_url, "runs", "--json").json()["runs"][0]["config"]
    assert (repeats["folds"], repeats["repeats"]) == (10, 2)


@pytest.mark.shared
def test_the_damaged_results_file_is_refused_at_line_207(
    capsys: pytest.CaptureFixture[str], store_url: str, shared_datasets: Path
) -> None:
    data = shared_datasets / UC3M / "mini" / "gesture_and_place.arff"
    assert run_cli(capsys, store_url, "import", str(data), "--name", "mini").code == 0
    path = shared_datasets / UC3M / "mini" / "weka_results_place.arff"
    result = run_cli(capsys, store_url, "import-results", str(path), "--dataset", "mini")
    assert result.code == 2
    assert "weka_results_place.arff:207: unterminated quote" in result.err
    assert len(result.err.strip().splitlines()) == 1
    assert run_cli(capsys, store_url, "runs", "--json").json() == {"runs": []}
