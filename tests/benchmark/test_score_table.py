"""Score tables: missing cells are reported and handled by an explicit policy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.score_table import MissingCell, ScoreTable, fold_score_table
from touchbench.benchmark.evaluation.statistics import compare_classifiers
from touchbench.benchmark.results import TaskKey, TaskResult


def table_with_a_hole() -> ScoreTable:
    scores = np.array(
        [
            [0.90, 0.80, 0.70],
            [0.85, np.nan, 0.75],
            [0.95, 0.70, 0.60],
            [0.80, 0.82, 0.81],
        ]
    )
    return ScoreTable(scores, ["d1", "d2", "d3", "d4"], ["rf", "svm", "j48"])


def test_missing_cells_are_listed() -> None:
    assert table_with_a_hole().missing_cells() == [MissingCell("d2", "svm")]


def test_drop_classifier() -> None:
    done = table_with_a_hole().complete("drop-classifier")
    assert done.table.classifiers == ("rf", "j48")
    assert done.table.blocks == ("d1", "d2", "d3", "d4")
    assert done.dropped_classifiers == ["svm"] and done.dropped_blocks == []
    assert done.missing == [MissingCell("d2", "svm")]
    assert not np.isnan(done.table.scores).any()


def test_drop_block() -> None:
    done = table_with_a_hole().complete("drop-block")
    assert done.table.blocks == ("d1", "d3", "d4")
    assert done.table.classifiers == ("rf", "svm", "j48")
    assert done.dropped_blocks == ["d2"]


@pytest.mark.parametrize("lower", [False, True])
def test_worst_ranks_a_missing_cell_last(lower: bool) -> None:
    table = table_with_a_hole()
    if lower:
        table = ScoreTable(1 - table.scores, table.blocks, table.classifiers)
    done = table.complete("worst", lower_is_better=lower)
    assert done.table.shape == (4, 3)
    result = compare_classifiers(done.table, lower_is_better=lower)
    svm = result.classifiers.index("svm")
    assert result.ranks[done.table.blocks.index("d2"), svm] == 3.0
    assert math.isinf(result.mean_scores[svm])


def test_bad_tables() -> None:
    with pytest.raises(ConfigurationError, match="unknown missing-cell policy 'skip'"):
        table_with_a_hole().complete("skip")  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="classifier 'rf' appears twice"):
        ScoreTable(np.zeros((1, 2)), ["d"], ["rf", "rf"])
    with pytest.raises(ConfigurationError, match=r"shape \(2, 2\)"):
        ScoreTable(np.zeros((2, 2)), ["d"], ["rf", "j48"])


def _result(classifier: str, fold: int, value: float, *, repeat: int = 0) -> TaskResult:
    ok = not math.isnan(value)
    return TaskResult(
        TaskKey(classifier, repeat, fold),
        "ok" if ok else "error",
        None if ok else "ValueError: boom",
        {"accuracy": value} if ok else {},
        None,
        90,
        10,
    )


def test_fold_score_table_from_results() -> None:
    results = [
        _result("rf", 0, 0.9),
        _result("rf", 1, 0.8),
        _result("j48", 0, 0.7),
        _result("j48", 1, math.nan),
        _result("rf", 0, 0.85, repeat=1),
    ]
    table = fold_score_table(results, "accuracy")
    assert table.classifiers == ("rf", "j48")
    assert table.blocks == ("fold 1", "fold 2", "repeat 2 fold 1")
    np.testing.assert_array_equal(table.scores, [[0.9, 0.7], [0.8, np.nan], [0.85, np.nan]])
    assert table.missing_cells() == [
        MissingCell("fold 2", "j48"),
        MissingCell("repeat 2 fold 1", "j48"),
    ]
    only = fold_score_table(results, "accuracy", classifiers=["j48"])
    assert only.classifiers == ("j48",)
