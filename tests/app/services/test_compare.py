"""Comparisons across runs read from a real store (SQLite and PostgreSQL): Demšar's worked
example stored as 14 runs, missing cells, the Bayesian view, and bad input on the CLI."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.demsar import DEMSAR_AUC, DEMSAR_NAMES
from tests.support.synthetic import touch_arff
from touchbench.app.errors import NotFoundError
from touchbench.app.schemas.run_config import RunConfig
from touchbench.app.services.compare import compare_runs, comparison_schema
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset, dataset_digest
from touchbench.app.store.runs import create_run, finish_run, record_result
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.results import TaskKey, TaskResult

FOLDS = 2


def stored_runs(
    store: Store,
    tmp_path: Path,
    scores: list[list[float]],
    classifiers: tuple[str, ...],
    *,
    metric: str = "roc_auc",
    failed: frozenset[tuple[int, str]] = frozenset(),
) -> list[int]:
    """One data set (``d0``, ``d1``...) and one finished run per row of ``scores``; every
    fold of a classifier scores its row's value, except the (row, classifier) pairs in
    ``failed``, whose folds all fail."""
    run_ids = []
    for i, row in enumerate(scores):
        data = read_arff(touch_arff(tmp_path / f"{i}.arff", n=12, seed=i, with_place=False))
        info, _ = add_dataset(store, data, sha256=dataset_digest(data), name=f"d{i}")
        run = create_run(
            store,
            dataset_id=info.id,
            kind="multiclass",
            targets=["gesture"],
            classifiers=list(classifiers),
            config=RunConfig(folds=FOLDS, repeats=1, seed=0, n_tasks=FOLDS * len(classifiers)),
        )
        for classifier, value in zip(classifiers, row, strict=True):
            for fold in range(FOLDS):
                ok = (i, classifier) not in failed
                record_result(
                    store,
                    run.id,
                    TaskResult(
                        TaskKey(classifier, 0, fold),
                        "ok" if ok else "error",
                        None if ok else "MemoryError: too big",
                        {metric: value, "f1_weighted": value} if ok else {},
                        [[3, 1, 0], [0, 2, 0], [0, 0, 0]] if ok else None,
                        6,
                        6,
                    ),
                )
        finish_run(store, run.id, "done")
        run_ids.append(run.id)
    return run_ids


def test_demsar_example_from_stored_runs(store: Store, tmp_path: Path) -> None:
    failing = frozenset({(3, "svm")})
    rows = [[*row, 0.5] for row in DEMSAR_AUC.tolist()]
    runs = stored_runs(store, tmp_path, rows, (*DEMSAR_NAMES, "svm"), failed=failing)
    comparison = compare_runs(store, runs, metric="roc_auc")
    ranks = comparison.ranks
    assert comparison.blocks_are == "datasets"
    assert ranks.n_blocks == 14
    assert ranks.classifiers == ("C4.5+m+cf", "C4.5+m", "C4.5+cf", "C4.5")  # svm left out
    assert ranks.friedman.statistic == pytest.approx(9.28, abs=5e-3)
    assert ranks.friedman.iman_davenport == pytest.approx(3.69, abs=5e-3)
    assert ranks.critical_difference == pytest.approx(1.25, abs=5e-3)
    missing = comparison.completed.missing
    assert [(m.block, m.classifier) for m in missing] == [("d3 (gesture)", "svm")]
    assert comparison.completed.dropped_classifiers == ["svm"]
    assert not any("does not reject" in note for note in comparison.notes)  # p = 0.02

    worst = compare_runs(store, runs, metric="roc_auc", missing="worst")
    assert worst.ranks.classifiers[-1] == "svm"
    assert worst.ranks.average_rank("svm") == 5.0  # last everywhere, also where it failed
    dropped_block = compare_runs(store, runs, metric="roc_auc", missing="drop-block")
    assert dropped_block.ranks.n_blocks == 13
    assert dropped_block.completed.dropped_blocks == ["d3 (gesture)"]

    data = comparison_schema(worst).to_json()
    svm = next(c for c in data["classifiers"] if c["classifier"] == "svm")
    assert svm["mean_score"] is None  # an infinite stand-in is no score
    assert svm["scores"]["d3 (gesture)"] is None and svm["scores"]["d0 (gesture)"] == 0.5
    assert data["missing"]["cells"] == [{"block": "d3 (gesture)", "classifier": "svm"}]
    assert data["friedman"]["df"] == 4 and data["nemenyi"]["critical_difference"] > 0


def test_bayesian_pair_and_one_run_as_folds(store: Store, tmp_path: Path) -> None:
    rows = [[0.90, 0.80, 0.85], [0.91, 0.70, 0.80], [0.88, 0.86, 0.87], [0.95, 0.75, 0.9]]
    runs = stored_runs(store, tmp_path, rows, ("rf", "j48", "nb"))
    comparison = compare_runs(store, runs, pair=("rf", "j48"), rope=0.01)
    assert comparison.metric == "f1_weighted"
    pair = comparison.pair
    assert pair is not None and pair.across is not None
    assert pair.across.test == "Bayesian signed-rank test"
    assert pair.across.p_left > 0.9  # rf beats j48 by 0.02 to 0.2 on every data set
    assert [scores.run.id for scores, _ in pair.per_run] == runs
    for _, result in pair.per_run:  # identical folds: the posterior is a point mass
        assert (result.p_left, result.p_rope, result.p_right) == (1.0, 0.0, 0.0)
    single = compare_runs(store, runs[:1])
    assert single.blocks_are == "folds"
    assert single.ranks.blocks == ("fold 1", "fold 2")
    assert any("descriptive" in note for note in single.notes)
    with pytest.raises(ConfigurationError, match="'svm' is not a classifier every run has"):
        compare_runs(store, runs, pair=("rf", "svm"))
    with pytest.raises(ConfigurationError, match="run 1 is given twice"):
        compare_runs(store, [runs[0], runs[0]])
    with pytest.raises(ConfigurationError, match="no 'hamming_score' scores"):
        compare_runs(store, runs, metric="hamming_score")
    with pytest.raises(NotFoundError, match="no run '99'"):
        compare_runs(store, [99])


def test_compare_cli_text_json_plot_and_errors(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    store = Store(store_url)
    rows = [[0.90, 0.80, 0.85], [0.91, 0.70, 0.80], [0.88, 0.86, 0.87], [0.95, 0.75, 0.9]]
    try:
        stored_runs(store, tmp_path, rows, ("rf", "j48", "nb"))
    finally:
        store.dispose()
    text = run_cli(capsys, store_url, "compare", "1", "2", "3", "4", "--bayesian", "rf,j48")
    assert text.code == 0, text.err
    assert "3 classifiers over 4 data sets, ranked by f1_weighted" in text.out
    assert "Friedman: chi2(2) = " in text.err and "Nemenyi: CD = " in text.err
    assert "Bayesian comparison of rf and j48" in text.out
    as_json = run_cli(capsys, store_url, "compare", "1", "2", "3", "4", "--json", "--alpha", "0.1")
    assert as_json.code == 0, as_json.err
    data = as_json.json()  # only JSON on stdout
    assert data["runs"] == [1, 2, 3, 4] and data["alpha"] == 0.1
    assert [c["classifier"] for c in data["classifiers"]] == ["rf", "nb", "j48"]
    assert data["classifiers"][0]["average_rank"] == 1.0
    assert math.isclose(data["friedman"]["chi_square"], 8.0)  # same order on every data set
    assert data["holm"]["control"] == "rf"
    plot = tmp_path / "cd.svg"
    drawn = run_cli(capsys, store_url, "compare", "1", "2", "3", "4", "--plot", str(plot))
    assert drawn.code == 0 and "rf (1.00)" in plot.read_text()
    for args, message in [
        (["compare", "1", "9"], "no run '9'"),
        (["compare", "1", "2", "--missing", "skip"], "unknown missing-cell policy 'skip'"),
        (["compare", "1", "2", "--bayesian", "rf"], "give two classifiers as A,B"),
        (["compare", "1", "2", "--metric", "kappa"], "run 1 has no 'kappa' scores"),
        (["compare", "1", "2", "--plot", str(tmp_path / "cd.pdf")], "unknown plot format"),
        (["compare", "1", "2", "--alpha", "2"], "--alpha"),
    ]:
        result = run_cli(capsys, store_url, *args)
        assert result.code == 2, (args, result.err)
        assert message in result.err
        assert len(result.err.strip().splitlines()) == 1 and "Traceback" not in result.err
    assert not (tmp_path / "cd.pdf").exists()
