"""A run's ranking for the web page, computed once per version of its results and kept
(:func:`app.services.runs.ranked_run`), and pages that read the fold results of the
classifiers they draw only (:func:`app.services.report.page_view`), on SQLite and
PostgreSQL."""

from __future__ import annotations

import gc
import weakref
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import Result, event, select
from sqlalchemy.orm import ORMExecuteState, Session

from tests.support.hostile_inputs import results_arff
from tests.support.synthetic import touch_arff
from touchbench.app.errors import NotFoundError
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.imported import ImportResultsRequest
from touchbench.app.services.datasets import import_file
from touchbench.app.services.imported import import_results
from touchbench.app.services.lifecycle import get_run, run_progress
from touchbench.app.services.report import page_view
from touchbench.app.services.runs import kept, ranked_run, run_leaderboard
from touchbench.app.store.database import Store
from touchbench.app.store.run_progress import RunProgress
from touchbench.app.store.runs import load_results, record_result
from touchbench.app.store.tables import FoldResultRow
from touchbench.benchmark.results import TaskKey, TaskResult


@pytest.fixture
def imported(store: Store, tmp_path: Path) -> int:
    """A run of 40 classifiers imported from a results file."""
    data = touch_arff(tmp_path / "paper.arff", n=90, with_place=False)
    import_file(store, ImportRequest(file=data, name="paper"))
    results = results_arff(tmp_path / "results.arff", n_classifiers=40)
    return import_results(store, ImportResultsRequest(file=results, dataset="paper")).id


def test_a_ranking_is_computed_once_per_version_of_the_results(store: Store, imported: int) -> None:
    first = ranked_run(store, imported)
    assert ranked_run(store, imported) is first
    # what it kept is what the leaderboard says
    fresh = run_leaderboard(store, imported)
    assert [r.classifier for r in first.board.rows] == [r.classifier for r in fresh.board.rows]
    assert first.report == fresh.report()
    assert len(first.board.rows) == 40

    by_kappa = ranked_run(store, imported, metric="kappa")
    assert by_kappa is not first and by_kappa.board.metric == "kappa"
    assert ranked_run(store, imported, metric="kappa") is by_kappa

    # one more fold result: another version, ranked again with it
    best = first.board.rows[-1].classifier
    metrics = {"accuracy": 1.0, "f1_weighted": 1.0, "kappa": 1.0}
    record_result(
        store, imported, TaskResult(TaskKey(best, 1, 0), "ok", None, metrics, None, 81, 9)
    )
    again = ranked_run(store, imported)
    assert again is not first
    assert again.run.n_results == first.run.n_results + 1
    assert again.board.row(best).n_ok == first.board.row(best).n_ok + 1


def test_nothing_is_kept_when_the_computation_fails(store: Store, imported: int) -> None:
    calls: list[int] = []

    def failing() -> int:
        calls.append(1)
        raise ValueError("no")

    for _ in range(2):
        with pytest.raises(ValueError):
            kept(store, [imported], "failing", failing)
    assert len(calls) == 2
    assert kept(store, [imported], "failing", lambda: 7) == 7
    assert kept(store, [imported], "failing", lambda: 8) == 7
    assert kept(store, [str(imported)], "failing", lambda: 9) == 7  # the same run
    with pytest.raises(NotFoundError, match="no run '999'"):
        kept(store, [999], "failing", lambda: 10)


def test_a_page_reads_the_results_of_the_classifiers_it_draws_only(
    store: Store, imported: int
) -> None:
    ranked = ranked_run(store, imported)
    best = [row.classifier for row in ranked.board.rows[:3]]
    view = page_view(store, ranked, best)
    assert {r.key.classifier for r in view.results} == set(best)
    assert len(view.results) == 3 * 10
    # the fold table still has a column per classifier of the run, in ranking order
    table = view.fold_scores()
    assert list(table.classifiers)[:3] == best and len(table.classifiers) == 40


class _Node:
    """An object in a reference cycle (as a figure's artists are)."""

    def __init__(self) -> None:
        self.me = self


def test_a_computation_leaves_the_collector_on_and_its_cycles_freed(
    store: Store, imported: int
) -> None:
    left: list[weakref.ref[_Node]] = []

    def compute() -> str:
        assert not gc.isenabled()  # no full collection's pause while it computes
        left.append(weakref.ref(_Node()))  # garbage in a cycle: only the collector frees it
        return "made"

    assert kept(store, [imported], "cycle", compute) == "made"
    assert gc.isenabled()
    assert left[0]() is None  # collected before what survived was frozen


def test_a_cycle_alive_during_a_computation_is_freed_once_dropped(
    store: Store, imported: int
) -> None:
    """What other requests hold while a run is ranked stays in the collector's reach: a
    cycle of theirs dropped afterwards is freed (nothing frozen)."""
    held = _Node()  # another request's, in flight while the ranking is computed
    watched = weakref.ref(held)
    assert kept(store, [imported], "held", lambda: "made") == "made"
    del held
    gc.collect()
    assert watched() is None


def test_a_run_s_progress_reads_the_same_whatever_its_size(store: Store, tmp_path: Path) -> None:
    """The progress a page polls every second: as many statements, and as much read, for
    a run of 30 classifiers as for one of 1,000 (counted by SQL aggregates)."""
    data = touch_arff(tmp_path / "paper.arff", n=90, with_place=False)
    import_file(store, ImportRequest(file=data, name="paper"))
    runs = {
        n: import_results(
            store,
            ImportResultsRequest(
                file=results_arff(tmp_path / f"results{n}.arff", n_classifiers=n), dataset="paper"
            ),
        ).id
        for n in (30, 1000)
    }
    read: dict[int, list[int]] = {}  # run's classifiers -> characters of each answer

    def reads(n: int) -> RunProgress:
        def measured(state: ORMExecuteState) -> Result[Any]:
            answer = state.invoke_statement().freeze()
            read[n].append(sum(len(str(value)) for row in answer() for value in row))
            return answer()

        read[n] = []
        event.listen(Session, "do_orm_execute", measured, retval=True)
        try:
            return run_progress(store, runs[n])
        finally:
            event.remove(Session, "do_orm_execute", measured)

    small, large = reads(30), reads(1000)
    assert len(read[30]) == len(read[1000]) == 3  # the run, its results, its drops
    assert sum(read[1000]) <= sum(read[30]) + 20  # a few more digits in its counts
    for n, progress in ((30, small), (1000, large)):
        whole = get_run(store, runs[n])
        assert (progress.n_results, progress.n_failed, progress.n_dropped) == (10 * n, 0, 0)
        assert (progress.n_tasks, progress.n_classifiers) == (whole.n_tasks, n)
        assert progress.folds_text == whole.folds_text
        assert (progress.dataset_name, progress.status, progress.origin) == (
            "paper",
            "done",
            "imported",
        )
    with pytest.raises(NotFoundError, match="no run '999'"):
        run_progress(store, 999)


def test_a_ranking_reads_what_the_full_read_reads_but_the_confusion_matrices(
    store: Store, imported: int
) -> None:
    """The ranking's read (JSON cells decoded as one document, without the confusion
    matrices, sorted in Python) gives the results and the report of the full read, and the
    results the column's own decoding gives: on a run with failed folds, undefined scores,
    per-target scores, chosen parameters, regression scores and names SQL may sort apart."""
    nan = float("nan")
    for fold in range(3):
        for name, status in (("Zeta+tuned", "ok"), ("Zeta", "ok"), ("bcc:rf", "error")):
            metrics = {"accuracy": 0.5 + fold / 10, "f1_weighted": 0.4 + fold / 7, "kappa": nan}
            metrics["mae"] = 1e-05 * (fold + 1)
            record_result(
                store,
                imported,
                TaskResult(
                    TaskKey(name, 0, fold),
                    status,  # type: ignore[arg-type]
                    None if status == "ok" else f"failed on fold {fold}",
                    metrics if status == "ok" else {},
                    [[3, 1], [0, 5]] if status == "ok" else None,
                    81,
                    9,
                    per_target={"x": {"accuracy": 0.25 * fold, "roc_auc": nan}, "b": {"mae": 2.0}},
                    params={"max_depth": None, "C": 10 ** (fold - 1)} if "+tuned" in name else None,
                ),
            )
    with store.session() as session:  # the column's own decoding, row by row
        stored = {
            (r.classifier, r.repeat, r.fold): (r.status, r.metrics, r.confusion)
            for r in session.scalars(select(FoldResultRow).where(FoldResultRow.run_id == imported))
        }
    full = load_results(store, imported)
    assert [(r.key.classifier, r.key.repeat, r.key.fold) for r in full] == sorted(stored)
    for result in full:
        key = result.key
        status, metrics, confusion = stored[(key.classifier, key.repeat, key.fold)]
        assert result.status == status and result.confusion == confusion
        assert result.params == metrics.pop("params", None)
        per_target = metrics.pop("per_target", None)
        assert repr(result.per_target) == repr(per_target and _nan(per_target))
        assert repr(result.metrics) == repr(_nan(metrics))
    narrow = load_results(store, imported, confusion=False)
    assert repr([replace(r, confusion=None) for r in full]) == repr(narrow)

    for metric in (None, "kappa", "accuracy"):
        ranked = ranked_run(store, imported, metric=metric)
        fresh = run_leaderboard(store, imported, metric=metric)
        # byte for byte (the models hold NaN, which equals nothing)
        assert ranked.report.model_dump_json() == fresh.report().model_dump_json()
        assert ranked.report.tuning and ranked.report.choices
    row = ranked.board.row("bcc:rf")
    assert (row.n_ok, row.n_failed) == (0, 3)


def _nan(scores: Any) -> Any:
    """Stored scores as a read gives them: null (undefined) as NaN."""
    if isinstance(scores, dict):
        return {name: _nan(value) for name, value in scores.items()}
    return float("nan") if scores is None else scores
