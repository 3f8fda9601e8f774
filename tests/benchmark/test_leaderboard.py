"""Leaderboards: ranks, means and deviations, WEKA's marks, failures listed last."""

from __future__ import annotations

import math

import numpy as np
import pytest

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.leaderboard import build_leaderboard
from touchbench.benchmark.evaluation.significance import corrected_resampled_ttest
from touchbench.benchmark.results import TaskKey, TaskResult

OFFSETS = np.linspace(-0.02, 0.02, 10)


def fold_results(
    classifier: str, f1: np.ndarray, log_loss: np.ndarray | None = None
) -> list[TaskResult]:
    return [
        TaskResult(
            key=TaskKey(classifier, 0, k),
            status="ok",
            error=None,
            metrics={
                "f1_weighted": float(f1[k]),
                "log_loss": float(log_loss[k]) if log_loss is not None else math.nan,
                "fit_time": 0.1,
            },
            confusion=[[1]],
            n_train=90,
            n_test=10,
        )
        for k in range(len(f1))
    ]


def failed(classifier: str, status: str, error: str, fold: int) -> TaskResult:
    return TaskResult(TaskKey(classifier, 0, fold), status, error, {}, None, 90, 10)  # type: ignore[arg-type]


@pytest.fixture
def results() -> list[TaskResult]:
    best = 0.85 + OFFSETS
    close = best - 0.001 + 0.01 * np.resize([1, -1], 10)
    worse = 0.60 + OFFSETS[::-1]
    return (
        fold_results("rf", best, log_loss=0.4 + OFFSETS)
        + fold_results("svm", close)
        + fold_results("zeror", worse, log_loss=1.3 + OFFSETS)
        + [failed("broken", "error", "ValueError: boom", k) for k in range(10)]
        + fold_results("flaky", best + 0.1)[:7]
        + [failed("flaky", "timeout", "timed out after 1 s", k) for k in (7, 8, 9)]
    )


def test_rank_means_and_marks_against_the_best(results: list[TaskResult]) -> None:
    board = build_leaderboard(results)
    assert [row.classifier for row in board.rows] == ["flaky", "rf", "svm", "zeror", "broken"]
    assert [row.rank for row in board.rows] == [1, 2, 3, 4, 5]
    assert board.baseline == "flaky"
    rf = board.row("rf")
    assert rf.metrics["f1_weighted"][0] == pytest.approx(0.85)
    assert rf.metrics["f1_weighted"][1] == pytest.approx(np.std(OFFSETS, ddof=1))
    assert rf.metrics["fit_time"] == (pytest.approx(0.1), 0.0)
    assert math.isnan(board.row("svm").metrics["log_loss"][0])
    flaky = board.row("flaky")
    assert (flaky.n_ok, flaky.n_failed, flaky.errors) == (7, 3, ["timed out after 1 s"])
    broken = board.row("broken")
    assert (broken.n_ok, broken.n_failed, broken.errors, broken.mark) == (
        0,
        10,
        ["ValueError: boom"],
        "",
    )
    # against flaky, on the 7 folds both completed: rf, svm and zeror are all worse
    assert [board.row(c).mark for c in ("rf", "svm", "zeror")] == ["*", "*", "*"]
    assert board.summary == (0, 0, 3)


def test_marks_with_a_chosen_baseline(results: list[TaskResult]) -> None:
    board = build_leaderboard(results, baseline="rf")
    assert board.row("flaky").mark == "v"
    assert board.row("svm").mark == ""
    assert board.row("zeror").mark == "*"
    assert board.row("rf").mark == ""
    assert board.summary == (1, 1, 1)
    # the mark agrees with the t-test on the paired folds
    rf = np.array([r.metrics["f1_weighted"] for r in results if r.key.classifier == "rf"])
    svm = np.array([r.metrics["f1_weighted"] for r in results if r.key.classifier == "svm"])
    assert corrected_resampled_ttest(svm, rf, test_train_ratio=1 / 9)[2] == 0


def test_lower_is_better_metrics_rank_ascending_and_flip_marks(results: list[TaskResult]) -> None:
    board = build_leaderboard(results, metric="log_loss")
    assert [row.classifier for row in board.rows][:2] == ["rf", "zeror"]
    assert board.baseline == "rf"
    assert board.row("zeror").mark == "*"  # higher log loss: significantly worse
    # classifiers without the metric come after the ranked ones, failures last
    assert [row.classifier for row in board.rows][-1] == "broken"
    assert board.summary == (0, 0, 1)


def test_to_json_has_mean_and_std_and_no_nan(results: list[TaskResult]) -> None:
    data = build_leaderboard(results, baseline="rf").to_json()
    assert data["metric"] == "f1_weighted" and data["baseline"] == "rf"
    assert data["summary"] == {"better": 1, "same": 1, "worse": 1}
    first = data["leaderboard"][0]
    assert first["classifier"] == "flaky" and first["mark"] == "v"
    assert set(first["metrics"]["f1_weighted"]) == {"mean", "std"}
    svm = next(row for row in data["leaderboard"] if row["classifier"] == "svm")
    assert svm["metrics"]["log_loss"] == {"mean": None, "std": None}


def test_equal_means_share_a_rank() -> None:
    scores = 0.7 + OFFSETS
    board = build_leaderboard(fold_results("a", scores) + fold_results("b", scores[::-1]))
    assert [row.rank for row in board.rows] == [1, 1]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"metric": "f2"}, "unknown metric 'f2' for this run"),
        ({"baseline": "j48"}, "baseline 'j48' is not in this run"),
        ({"baseline": "broken"}, "baseline 'broken' has no successful fold"),
    ],
)
def test_bad_requests(results: list[TaskResult], kwargs: dict, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        build_leaderboard(results, **kwargs)


def test_no_results_at_all() -> None:
    with pytest.raises(ConfigurationError, match="no results to rank"):
        build_leaderboard([])
    board = build_leaderboard(
        [failed("x", "error", "boom", 0), failed("y", "timeout", "timed out", 0)]
    )
    assert board.baseline is None and board.summary == (0, 0, 0)
    assert [(r.rank, r.classifier, r.n_failed, r.errors) for r in board.rows] == [
        (1, "x", 1, ["boom"]),
        (2, "y", 1, ["timed out"]),
    ]
