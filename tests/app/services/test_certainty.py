"""`touchbench classes` and `calibration`: per-class scores, confusion matrices and the
calibration of a run's classifiers from what each fold stored, on SQLite."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.cli_runner import run_cli, run_cli_captured
from tests.support.stores import copy_sqlite
from tests.support.synthetic import position_arff, touch_arff


@pytest.fixture(scope="module")
def benched(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, int]:
    """A template store holding the run every test reads, made once for the module: its
    file and the run's id."""
    folder = tmp_path_factory.mktemp("certainty")
    url = f"sqlite:///{folder / 'touchbench.db'}"
    path = touch_arff(folder / "touch.arff", n=90)
    assert run_cli_captured(url, "import", str(path)).code == 0
    result = run_cli_captured(
        url, "bench", "touch", "--target", "gesture", "-c", "j48,nb,svm-rbf", "--folds", "5",
        "--json",
    )  # fmt: skip
    assert result.code == 0, result.err
    return folder / "touchbench.db", int(result.json()["run_id"])


@pytest.fixture
def run(sqlite_store_url: str, benched: tuple[Path, int]) -> int:
    """The run, in the test's own store (a copy of the module's template: nothing one test
    does reaches another)."""
    template, run_id = benched
    copy_sqlite(template, Path(sqlite_store_url.removeprefix("sqlite:///")))
    return run_id


def test_classes_sum_the_folds_and_score_each_class(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, run: int
) -> None:
    result = run_cli(capsys, sqlite_store_url, "classes", str(run), "--json")
    assert result.code == 0, result.err
    certainty = result.json()
    assert certainty["targets"] == ["gesture"]
    entries = {e["classifier"]: e for e in certainty["classifiers"]}
    assert set(entries) == {"j48", "nb", "svm-rbf"}
    nb = entries["nb"]
    [target] = nb["targets"]
    assert target["labels"] == ["tap", "slap", "stroke"]
    confusion = np.array(target["confusion"])
    assert confusion.sum() == 90 and [c["support"] for c in target["classes"]] == [30, 30, 30]
    for k, scores in enumerate(target["classes"]):
        assert scores["recall"] == pytest.approx(confusion[k, k] / confusion[k].sum())
        assert scores["precision"] == pytest.approx(confusion[k, k] / confusion[:, k].sum())
    calibration = nb["calibration"]
    assert calibration["n_instances"] == 90 and calibration["n_folds"] == 5
    assert sum(b["count"] for b in calibration["bins"]) == 90
    gap = sum(
        b["count"] * abs(b["accuracy"] - b["confidence"]) for b in calibration["bins"] if b["count"]
    )
    assert calibration["ece"] == pytest.approx(gap / 90)
    # an SVM without probabilities has a confusion matrix but no calibration, and says why
    assert entries["svm-rbf"]["calibration"] is None
    assert "without probabilities" in entries["svm-rbf"]["calibration_note"]
    text = run_cli(capsys, sqlite_store_url, "classes", str(run), "-c", "nb")
    assert text.code == 0 and "stroke" in text.out and "expected calibration error" in text.err


def test_calibration_draws_the_reliability_diagram(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, run: int, tmp_path: Path
) -> None:
    svg = tmp_path / "reliability.svg"
    result = run_cli(capsys, sqlite_store_url, "calibration", str(run), "-o", str(svg))
    assert result.code == 0, result.err
    text = svg.read_text(encoding="utf-8")
    assert text.lstrip().startswith("<?xml") and "<svg" in text
    assert "nb (ECE" in text and "svm-rbf" not in text
    assert "ECE" in result.out


def test_bad_certainty_requests_are_one_line_exit_2(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, run: int, tmp_path: Path
) -> None:
    unknown = run_cli(capsys, sqlite_store_url, "classes", str(run), "-c", "rf")
    assert unknown.code == 2 and f"run {run} has no classifier 'rf'" in unknown.err
    assert len(unknown.err.strip().splitlines()) == 1
    missing = run_cli(capsys, sqlite_store_url, "calibration", "99")
    assert missing.code == 2 and "no run '99'" in missing.err
    wrong = run_cli(
        capsys, sqlite_store_url, "calibration", str(run), "-o", str(tmp_path / "x.txt")
    )
    assert wrong.code == 2
    nothing = run_cli(
        capsys,
        sqlite_store_url,
        "calibration",
        str(run),
        "-c",
        "svm-rbf",
        "-o",
        str(tmp_path / "s.svg"),
    )
    assert nothing.code == 2 and "kept calibration bins" in nothing.err
    position = position_arff(tmp_path / "contact.arff", n=30)
    assert run_cli(capsys, sqlite_store_url, "import", str(position)).code == 0
    regression = run_cli(
        capsys, sqlite_store_url, "bench", "contact", "-c", "ridge", "--folds", "3", "--json"
    ).json()["run_id"]
    refused = run_cli(capsys, sqlite_store_url, "classes", str(regression))
    assert refused.code == 2 and "is a regression" in refused.err


def test_the_report_says_how_sure(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, run: int, tmp_path: Path
) -> None:
    page = tmp_path / "report.html"
    made = run_cli(
        capsys, sqlite_store_url, "report", str(run), "-o", str(page), "--confusions", "2"
    )
    assert made.code == 0, made.err
    html = page.read_text(encoding="utf-8")
    assert "How sure: per class and calibration" in html
    assert html.count('data-table="classes"') == 2  # the two best classifiers
    assert "expected calibration error, 10 bins" in html and "Reliability of the best" in html
    assert "without probabilities" in html  # svm-rbf's note


def test_importance_explains_a_runs_classifier_on_its_folds(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, run: int
) -> None:
    result = run_cli(
        capsys, sqlite_store_url, "importance", str(run), "-c", "nb", "--repeats", "1", "--json"
    )
    assert result.code == 0, result.err
    found = result.json()
    assert (found["classifier"], found["target"], found["n_folds"]) == ("nb", "gesture", 5)
    names = [f["name"] for f in found["features"]]
    assert sorted(names) == ["f0", "f1", "f2", "f3", "mic"]
    assert names[0] == "f0"  # the synthetic gesture is f0's shift
    bad = run_cli(capsys, sqlite_store_url, "importance", str(run), "-c", "rf")
    assert bad.code == 2 and bad.err.startswith("touchbench: error: --classifier: 'rf' is not")
    many = run_cli(capsys, sqlite_store_url, "importance", str(run), "-c", "nb", "--repeats", "99")
    assert many.code == 2 and "--repeats" in many.err
