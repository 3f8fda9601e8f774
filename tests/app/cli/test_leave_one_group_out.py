"""Leave-one-group-out on the command line, on SQLite: `bench --folds logo`
makes one fold per group of an imported table (its `--groups` column), never with a group on
both sides, says so in every view, and is refused in one line where it means nothing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.cli_runner import one_error_line, run_cli
from tests.support.grasp_table import FEATURES, OBJECTS, grasp_csv
from touchbench.app.services.runs import RunOptions, fold_plan, prepare_problem
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.app.store.runs import get_run


@pytest.mark.parametrize("spelling", ["logo", "leave-one-group-out"])
def test_leave_one_group_out_has_a_fold_per_group_and_every_view_says_so(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path, spelling: str
) -> None:
    path = grasp_csv(tmp_path / "grasps.csv")
    imported = run_cli(
        capsys, sqlite_store_url, "import", str(path), "--groups", "object", "--ignore", "trial"
    )
    assert imported.code == 0, imported.err
    bench = run_cli(
        capsys, sqlite_store_url, "bench", "grasps", "-c", "nb,zeror", "--folds", spelling, "--json"
    )
    assert bench.code == 0, bench.err
    board = bench.json()
    assert board["folds"] == f"leave-one-group-out, {len(OBJECTS)} groups"
    assert {row["n_ok"] for row in board["leaderboard"]} == {len(OBJECTS)}

    run = run_cli(capsys, sqlite_store_url, "runs", "--json").json()["runs"][0]
    assert run["config"]["split"] == "leave-one-group-out"
    assert (run["config"]["folds"], run["config"]["repeats"]) == (len(OBJECTS), 1)
    assert run["tasks"] == 2 * len(OBJECTS) and run["folds"] == board["folds"]
    table = run_cli(capsys, sqlite_store_url, "leaderboard", str(run["id"]))
    assert f"leave-one-group-out, {len(OBJECTS)} groups" in " ".join(table.out.split())
    markdown = run_cli(
        capsys, sqlite_store_url, "leaderboard", str(run["id"]), "--format", "markdown"
    )
    assert f"leave-one-group-out, {len(OBJECTS)} groups, ranked by" in markdown.out
    # every instance tested once, by the fold of its own group
    classes = run_cli(
        capsys, sqlite_store_url, "classes", str(run["id"]), "-c", "nb", "--json"
    ).json()
    assert np.sum(classes["classifiers"][0]["targets"][0]["confusion"]) == len(OBJECTS) * 10

    store = Store(sqlite_store_url)
    try:
        stored = get_run(store, run["id"])
        dataset = load_dataset(store, "grasps")
    finally:
        store.dispose()
    # the group column and the ignored one never reach the features
    assert dataset.schema.feature_names == FEATURES
    prepared = prepare_problem(dataset)
    assert prepared.problem.X.shape == (len(OBJECTS) * 10, len(FEATURES))
    plan = fold_plan(prepared, RunOptions.from_config(stored.config))
    groups = prepared.problem.groups
    assert groups is not None and len(plan.folds) == len(OBJECTS)
    tested = []
    for fold in plan.folds:
        assert not set(groups[fold.train]) & set(groups[fold.test])
        assert len(set(groups[fold.test])) == 1
        tested.append(groups[fold.test][0])
    assert sorted(tested) == sorted(OBJECTS)


def test_k_fold_views_name_k(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    path = grasp_csv(tmp_path / "grasps.csv")
    assert run_cli(capsys, sqlite_store_url, "import", str(path), "--ignore", "trial").code == 0
    bench = run_cli(capsys, sqlite_store_url, "bench", "grasps", "-c", "nb", "-k", "4", "--json")
    assert bench.code == 0, bench.err
    assert bench.json()["folds"] == "stratified 4-fold"


@pytest.mark.parametrize(
    ("grouped", "options", "expected"),
    [
        (False, ["--folds", "logo"], ["--folds: logo (leave-one-group-out) needs groups"]),
        (True, ["--folds", "logo", "--repeats", "3"], ["--repeats: must be 1 with --folds logo"]),
        (True, ["--folds", "lobo"], ["--folds: must be a number of folds or logo"]),
        (True, ["--folds", "1"], ["--folds: Input should be greater than or equal to 2 (or logo"]),
        (True, ["--folds", "101"], ["--folds: Input should be less than or equal to 100"]),
    ],
)
def test_leave_one_group_out_where_it_means_nothing_is_one_line_and_stores_no_run(
    capsys: pytest.CaptureFixture[str],
    sqlite_store_url: str,
    tmp_path: Path,
    grouped: bool,
    options: list[str],
    expected: list[str],
) -> None:
    path = grasp_csv(tmp_path / "grasps.csv")
    columns = ["--groups", "object", "--ignore", "trial"] if grouped else ["--ignore", "trial"]
    assert run_cli(capsys, sqlite_store_url, "import", str(path), *columns).code == 0
    one_error_line(
        run_cli(capsys, sqlite_store_url, "bench", "grasps", "-c", "nb", *options), *expected
    )
    assert run_cli(capsys, sqlite_store_url, "runs", "--json").json()["runs"] == []
