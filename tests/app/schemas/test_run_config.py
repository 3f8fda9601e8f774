"""A run's stored configuration (app/schemas/run_config.py): what older versions wrote loads,
reads back as stored, and an old run is resumed and ranked as a new one is."""

from __future__ import annotations

from typing import Any

import pytest
from sqlalchemy import update

from tests.support.synthetic import small_dataset
from touchbench.app.schemas.run_config import RunConfig
from touchbench.app.schemas.status import Status
from touchbench.app.services.runs import RunOptions, execute_run, run_leaderboard
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset
from touchbench.app.store.runs import create_run, get_run
from touchbench.app.store.tables import RunRow

#: The config of a run as the first version that stored runs wrote it.
FIRST = {
    "folds": 2,
    "repeats": 1,
    "seed": 0,
    "timeout": 600.0,
    "targets_given": None,
    "n_tasks": 4,
    "n_instances": 7,
}
#: As the version before this one wrote a raced, budgeted, tuned run.
LAST = {
    **FIRST,
    "max_memory_mb": None,
    "folds": 2,
    "folds_requested": 3,
    "suite": None,
    "weka": {"J48-C0.1": "weka.classifiers.trees.J48 -C 0.1"},
    "tune": {"budget_minutes": None},
    "stack": None,
    "grouped": False,
    "fold_scheme": "stratified k-fold",
    "position": None,
    "metric": "accuracy",
    "baseline": "nb",
    "race": {"alpha": 0.01},
    "budget_total": 5.0,
    "aggregate": "window",
    "task_memory_mb": 1024,
    "task_memory_from": "asked",
}
#: As an imported WEKA results file's run was stored.
IMPORTED = {
    "origin": "imported",
    "name": "the paper",
    "source": "weka_results.arff",
    "key_dataset": "touch",
    "folds": 10,
    "repeats": 10,
    "fold_scheme": "WEKA Experimenter's 10-fold (imported)",
    "n_tasks": 200,
    "schemes": [
        {
            "classifier": "J48",
            "scheme": "weka.classifiers.trees.J48",
            "options": "-C 0.25",
            "version": "1",
        }
    ],
}


@pytest.mark.parametrize(
    "stored", [FIRST, LAST, IMPORTED, {}], ids=["first", "last", "imported", "empty"]
)
def test_what_any_version_stored_loads_and_reads_back_as_stored(stored: dict[str, Any]) -> None:
    config = RunConfig.load(stored)
    assert config.to_json() == stored
    assert RunConfig.load(config.to_json()) == config


def test_keys_an_older_version_did_not_write_take_the_default_it_meant() -> None:
    first = RunConfig.load(FIRST)
    assert (first.aggregate, first.by_recording, first.race, first.budget_total) == (
        "window",
        False,
        None,
        None,
    )
    assert (first.weka, first.tune, first.stack, first.grouped, first.fold_scheme) == (
        {},
        None,
        None,
        False,
        None,
    )
    assert first.asked_folds == 2  # before folds_requested, the folds asked were the folds made
    assert RunOptions.from_config(first) == RunOptions(
        folds=2, repeats=1, seed=0, timeout=600.0, max_memory_mb=None
    )
    last = RunConfig.load(LAST)
    assert (
        last.asked_folds,
        last.race and last.race.alpha,
        last.tune and last.tune.budget_minutes,
    ) == (3, 0.01, None)
    imported = RunConfig.load(IMPORTED)
    assert imported.imported and not first.imported and imported.seed == 0
    assert [s.classifier for s in imported.schemes] == ["J48"]


def test_a_key_this_version_does_not_know_is_kept() -> None:
    config = RunConfig.load({**FIRST, "written_by": "a later version"})
    assert config.to_json()["written_by"] == "a later version"
    assert config.updated(task_memory_mb=512).to_json() == {
        **FIRST,
        "written_by": "a later version",
        "task_memory_mb": 512,
    }


def test_a_run_stored_by_the_first_version_is_resumed_and_ranked(store: Store) -> None:
    info, _ = add_dataset(store, small_dataset(), sha256="2" * 64, name="old")
    run = create_run(
        store,
        dataset_id=info.id,
        kind="multiclass",
        targets=["gesture"],
        classifiers=["nb", "zeror"],
        config=RunConfig(),
    )
    with store.session() as session:  # the row exactly as the first version wrote it
        session.execute(
            update(RunRow)
            .where(RunRow.id == run.id)
            .values(config=FIRST, status=Status.INTERRUPTED)
        )
    assert get_run(store, run.id).schema().config == FIRST
    done = execute_run(store, run.id)
    assert (done.status, done.n_results, done.n_tasks) == (Status.DONE, 4, 4)
    config = done.schema().config
    assert {key: config[key] for key in FIRST} == FIRST  # what it was asked stays as it was
    assert config["task_memory_from"] and "aggregate" not in config
    ranked = run_leaderboard(store, run.id)
    assert {row.classifier for row in ranked.board.rows} == {"nb", "zeror"}
    assert (
        ranked.report().folds == "stratified k-fold"
        and ranked.race() is None
        and ranked.budget() is None
    )
