"""Fold predictions in the store (app/store/predictions.py), on SQLite and PostgreSQL: what
a run's tasks predicted goes in with them and comes back bit for bit, and a resumed run's
stored results get theirs back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import text

from tests.support.rows import count_rows
from tests.support.synthetic import touch_arff
from touchbench.app.schemas.run_config import RunConfig
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset, dataset_digest
from touchbench.app.store.predictions import (
    attach_predictions,
    load_predictions,
    record_predictions,
)
from touchbench.app.store.runs import create_run, load_results, record_result
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.predictions import FoldPredictions
from touchbench.benchmark.results import TaskKey, TaskResult


def _run(store: Store, tmp_path: Path) -> int:
    data = read_arff(touch_arff(tmp_path / "touch.arff", n=12, seed=0, with_place=False))
    info, _ = add_dataset(store, data, sha256=dataset_digest(data), name="touch")
    run = create_run(
        store,
        dataset_id=info.id,
        kind="multiclass",
        targets=["gesture"],
        classifiers=["nb"],
        config=RunConfig.load({"folds": 2, "repeats": 1, "seed": 0, "n_tasks": 2}),
    )
    return run.id


def _result(fold: int, inner: bool) -> TaskResult:
    rng = np.random.default_rng(fold)
    proba = rng.dirichlet(np.ones(4), size=6)
    result = TaskResult(TaskKey("nb", 0, fold), "ok", None, {"accuracy": 0.5}, None, 18, 6)
    result.predictions = FoldPredictions.of_classes(np.arange(6) + 6 * fold, proba.argmax(1), proba)
    if inner:
        result.inner_predictions = FoldPredictions.of_classes(
            np.arange(18), np.arange(18) % 4, None
        )
    return result


def test_fold_predictions_are_stored_with_their_task_and_come_back_bit_for_bit(
    store: Store, store_url: str, tmp_path: Path
) -> None:
    run_id = _run(store, tmp_path)
    results = [_result(0, inner=True), _result(1, inner=False)]
    for result in results:
        record_result(store, run_id, result)
        record_predictions(store, run_id, result)
        record_predictions(store, run_id, result)  # a task recorded twice is left as it is
    assert count_rows(store_url, "fold_predictions") == 3
    tests = load_predictions(store, run_id)
    assert set(tests) == {r.key for r in results}
    for result in results:
        assert result.predictions is not None
        assert tests[result.key].same_as(result.predictions)
    inner = load_predictions(store, run_id, part="inner")
    assert set(inner) == {TaskKey("nb", 0, 0)}
    read = load_results(store, run_id)
    assert all(r.predictions is None for r in read)  # the results' own columns lack them
    attach_predictions(store, run_id, read)
    by_key = {r.key: r for r in read}
    for result in results:
        back = by_key[result.key]
        assert back.predictions is not None and result.predictions is not None
        assert back.predictions.same_as(result.predictions)
        assert (back.inner_predictions is None) == (result.inner_predictions is None)


def test_a_damaged_blob_is_refused_not_unpickled(
    store: Store, store_url: str, tmp_path: Path
) -> None:
    import pickle

    run_id = _run(store, tmp_path)
    record_predictions(store, run_id, _result(0, inner=False))
    with store.session() as session:
        session.execute(
            text("UPDATE fold_predictions SET data = :data"),
            {"data": pickle.dumps({"labels": [1, 2]})},
        )
    with pytest.raises(DataFormatError, match="not an encoding of fold predictions"):
        load_predictions(store, run_id)


def test_a_run_s_predictions_go_with_the_run(store: Store, store_url: str, tmp_path: Path) -> None:
    run_id = _run(store, tmp_path)
    record_predictions(store, run_id, _result(0, inner=True))
    with store.session() as session:
        session.execute(text("DELETE FROM runs WHERE id = :id"), {"id": run_id})
    assert count_rows(store_url, "fold_predictions") == 0
