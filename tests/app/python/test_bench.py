"""``touchbench.bench`` and ``touchbench.train`` from Python, on SQLite: every kind
of data (a DataFrame, arrays, an ARFF file, a stored name), an estimator of the test's own
beside catalogue ids, leave-one-group-out on a grouped table, bad input refused naming its
column with nothing stored, and a run that the CLI then lists; an interrupted run keeps
what finished, on SQLite and PostgreSQL."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.neighbors import KNeighborsClassifier

import touchbench
from tests.support.cli_runner import run_cli
from tests.support.grasp_table import FEATURES, OBJECTS, grasp_arff
from touchbench.app.errors import FieldError, NotFoundError
from touchbench.app.python.progress import RunBar
from touchbench.app.services.runs import RunOptions, fold_plan, prepare_problem
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.app.store.runs import get_run


class NearestMean(ClassifierMixin, BaseEstimator):
    """The test's own estimator: each class's mean, the nearest one predicted."""

    def __init__(self, shrink: float = 0.0) -> None:
        self.shrink = shrink

    def fit(self, X: np.ndarray, y: np.ndarray) -> NearestMean:
        self.classes_ = np.unique(y)
        self.means_ = np.array([X[y == c].mean(axis=0) * (1 - self.shrink) for c in self.classes_])
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        distances = ((X[:, None, :] - self.means_[None]) ** 2).sum(axis=2)
        return self.classes_[distances.argmin(axis=1)]


def grasps() -> pd.DataFrame:
    """The grasp table as a DataFrame: object, trial, six taxels, slipped."""
    rng = np.random.default_rng(0)
    rows = []
    for name in OBJECTS:
        for trial in range(10):
            values = rng.normal(size=len(FEATURES))
            values[0] += 2.5 * (trial % 2)
            rows.append([name, trial + 1, *values, "yes" if trial % 2 else "no"])
    return pd.DataFrame(rows, columns=["object", "trial", *FEATURES, "slipped"])


def runs_listed(capsys: pytest.CaptureFixture[str], store_url: str) -> list[dict]:
    return run_cli(capsys, store_url, "runs", "--json").json()["runs"]


def stored_counts(store_url: str) -> tuple[int, int]:
    """Data sets and runs in the store."""
    store = Store(store_url)
    try:
        from sqlalchemy import func, select

        from touchbench.app.store.tables import DatasetRow, RunRow

        with store.session() as session:
            return (
                int(session.scalar(select(func.count()).select_from(DatasetRow)) or 0),
                int(session.scalar(select(func.count()).select_from(RunRow)) or 0),
            )
    finally:
        store.dispose()


def test_a_dataframe_with_groups_left_out_one_at_a_time_and_an_estimator_of_our_own(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str
) -> None:
    board = touchbench.bench(
        grasps(),
        target="slipped",
        classifiers=["nb", "zeror", NearestMean(), ("knn3", KNeighborsClassifier(3))],
        folds="logo",
        groups="object",
        ignore=["trial"],
        store=sqlite_store_url,
        progress=False,
    )
    assert isinstance(board, touchbench.Leaderboard)
    assert board.schema.folds == f"leave-one-group-out, {len(OBJECTS)} groups"
    table = board.to_pandas()
    assert set(table.index) == {"nb", "zeror", "NearestMean", "knn3"}
    assert (table["folds"] == len(OBJECTS)).all() and (table["n_failed"] == 0).all()
    # the first taxel tells slips apart: our estimator learns it, zeror cannot
    assert table.loc["NearestMean", "f1_weighted_mean"] > 0.8
    assert table.loc["zeror", "mark"] == "*" and board.best != "zeror"
    assert "leave-one-group-out, 8 groups" in board._repr_html_()

    # the run is the CLI's too
    listed = runs_listed(capsys, sqlite_store_url)
    assert [r["id"] for r in listed] == [board.run_id]
    assert listed[0]["classifiers"] == ["nb", "zeror", "NearestMean", "knn3"]
    store = Store(sqlite_store_url)
    try:
        run = get_run(store, board.run_id)
        dataset = load_dataset(store, run.dataset_name)
    finally:
        store.dispose()
    # the group and ignored columns never reach the features
    assert dataset.schema.feature_names == FEATURES
    prepared = prepare_problem(dataset)
    assert prepared.problem.X.shape == (80, len(FEATURES))
    plan = fold_plan(prepared, RunOptions.from_config(run.config))
    groups = prepared.problem.groups
    assert groups is not None and len(plan.folds) == len(OBJECTS)
    for fold in plan.folds:
        assert not set(groups[fold.train]) & set(groups[fold.test])


def test_arrays_an_arff_file_and_a_stored_name(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    frame = grasps()
    X, y = frame[list(FEATURES)].to_numpy(), frame["slipped"].to_numpy()
    pair = touchbench.bench((X, y), classifiers=["nb", "zeror"], folds=4, store=sqlite_store_url,
                            progress=False)  # fmt: skip
    assert pair.schema.folds == "stratified 4-fold" and pair.schema.targets == ["y"]
    assert pair.best == "nb"

    path = grasp_arff(tmp_path / "grasps.arff")
    arff = touchbench.bench(path, classifiers=["nb"], folds=3, groups="object",
                            ignore=["trial"], store=sqlite_store_url, progress=False)  # fmt: skip
    assert arff.schema.dataset == "grasps" and arff.schema.folds == "stratified group 3-fold"

    again = touchbench.bench("grasps", classifiers=["nb"], folds="logo", store=sqlite_store_url,
                             progress=False)  # fmt: skip
    assert again.schema.folds == "leave-one-group-out, 8 groups"
    assert [r["folds"] for r in runs_listed(capsys, sqlite_store_url)] == [
        "stratified 4-fold",
        "stratified group 3-fold",
        "leave-one-group-out, 8 groups",
    ]

    model = touchbench.train("grasps", classifier="nb", store=sqlite_store_url)
    predicted = model.predict(frame)
    assert predicted.shape == (80,) and set(predicted) <= {"yes", "no"}
    assert (predicted == frame["slipped"]).mean() > 0.8
    proba = model.predict_proba(frame)
    assert list(proba.columns) == ["no", "yes"]
    np.testing.assert_allclose(proba.sum(axis=1), 1.0)


@pytest.mark.parametrize(
    ("change", "options", "field", "words"),
    [
        (None, {"target": "slipt"}, "target", "no column named 'slipt' in the DataFrame"),
        (None, {"groups": "objekt"}, "groups", "no column named 'objekt' in the DataFrame"),
        (None, {"ignore": ["trial", "trail"]}, "ignore", "no column named 'trail'"),
        ("one value", {}, "target", "column 'slipped' of the DataFrame has a single value"),
        ("mixed", {}, "data", "column 'taxel2' of the DataFrame mixes types (float, str)"),
        (None, {"folds": "lobo"}, "folds", "must be a number of folds or logo"),
        (None, {"folds": "logo", "repeats": 2}, "repeats", "must be 1 with `folds` logo"),
        (None, {"classifiers": ["nb", "rff"]}, "classifiers", "unknown classifier 'rff'"),
        (None, {"classifiers": [object()]}, "classifiers", "neither a classifier id nor"),
    ],
)
def test_bad_input_is_one_exception_naming_the_column_and_stores_nothing(
    sqlite_store_url: str, change: str | None, options: dict, field: str, words: str
) -> None:
    frame = grasps()
    if change == "one value":
        frame["slipped"] = "no"
    elif change == "mixed":
        frame["taxel2"] = frame["taxel2"].astype(object)
        frame.loc[3, "taxel2"] = "broken"
    asked = {"target": "slipped", "groups": "object", "ignore": ["trial"], **options}
    with pytest.raises(FieldError) as refused:
        touchbench.bench(frame, classifiers=asked.pop("classifiers", ["nb"]),
                         store=sqlite_store_url, progress=False, **asked)  # fmt: skip
    assert refused.value.field == field
    assert words in refused.value.message, refused.value.message
    assert stored_counts(sqlite_store_url) == (0, 0)


def test_leave_one_group_out_on_data_without_groups_is_a_field_error(tmp_path: Path) -> None:
    with pytest.raises(FieldError) as refused:
        touchbench.bench(grasps().drop(columns=["object"]), target="slipped", classifiers=["nb"],
                         folds="logo", store=tmp_path / "t.db", progress=False)  # fmt: skip
    assert refused.value.field == "folds" and "needs groups" in refused.value.message
    with pytest.raises(NotFoundError):
        touchbench.bench("nothing-stored", classifiers=["nb"], store=tmp_path / "t.db")


def test_an_interrupt_stops_the_run_and_keeps_what_finished(
    store_url: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    heard: list[str] = []
    original = RunBar._result

    def interrupted_after_two(self: RunBar, result: object) -> None:
        original(self, result)  # type: ignore[arg-type]
        heard.append("result")
        if len(heard) == 2:
            raise KeyboardInterrupt

    monkeypatch.setattr(RunBar, "_result", interrupted_after_two)
    with pytest.raises(KeyboardInterrupt):
        touchbench.bench(grasps(), target="slipped", classifiers=["nb", "zeror"], folds=4,
                         store=store_url, progress=False)  # fmt: skip
    store = Store(store_url)
    try:
        run = get_run(store, 1)
    finally:
        store.dispose()
    assert run.status == "interrupted" and 2 <= run.n_results < run.n_tasks


def test_a_temporary_store_and_a_lazy_import() -> None:
    board = touchbench.bench(grasps(), target="slipped", classifiers=["nb", "zeror"], folds=3,
                             progress=False)  # fmt: skip
    assert board.best == "nb" and board.plot("folds") is not None
    code = (
        "import sys, touchbench; assert not any(m.startswith('touchbench.') for m in sys.modules)"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
