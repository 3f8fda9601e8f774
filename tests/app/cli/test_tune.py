"""`touchbench bench --tune/--budget/--stack` end to end on a tiny synthetic data set."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from types import MappingProxyType

import pytest

import touchbench.benchmark.catalogue
import touchbench.benchmark.estimators
from tests.support.cli_runner import run_cli
from tests.support.synthetic import touch_arff


@pytest.fixture
def db(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    url = f"sqlite:///{tmp_path / 't.db'}"
    path = touch_arff(tmp_path / "touch.arff", n=90)
    assert run_cli(capsys, url, "import", str(path), "--json").code == 0
    return url


def test_tuned_twins_sit_beside_their_defaults_with_a_test_and_their_choices(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    args = ["bench", "touch", "--target", "gesture", "-c", "logistic,nb", "-k", "3"]
    result = run_cli(capsys, db, *args, "--tune", "--budget", "0.01", "--json")
    assert result.code == 0, result.err
    report = result.json()
    rows = {row["classifier"]: row for row in report["leaderboard"]}
    assert set(rows) == {"logistic", "logistic+tuned", "nb"}
    assert rows["logistic+tuned"]["n_ok"] == 3
    (comparison,) = report["tuning"]
    assert (comparison["tuned"], comparison["default"]) == ("logistic+tuned", "logistic")
    assert comparison["n_folds"] == 3 and comparison["p"] is not None
    assert [c["fold"] for c in comparison["choices"]] == [0, 1, 2]
    assert all(set(c["params"]) == {"C"} for c in comparison["choices"])
    table = run_cli(capsys, db, "leaderboard", "1")
    assert table.code == 0
    assert "tuned against default" in table.out and "C=" in table.out


def test_a_multi_target_twin_records_each_targets_choice_per_fold(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    args = ["bench", "touch", "-c", "cr:logistic", "-k", "3", "--tune", "--budget", "0.01"]
    result = run_cli(capsys, db, *args, "--json")
    assert result.code == 0, result.err
    report = result.json()
    (comparison,) = report["tuning"]
    assert (comparison["tuned"], comparison["default"]) == ("cr:logistic+tuned", "cr:logistic")
    choices = comparison["choices"]
    assert choices == [c for c in report["choices"] if c["classifier"] == "cr:logistic+tuned"]
    assert [c["fold"] for c in choices] == [0, 1, 2]
    for choice in choices:
        assert set(choice["params"]) == {"gesture", "place"}
        assert all(set(chosen) == {"C"} for chosen in choice["params"].values())
    table = run_cli(capsys, db, "leaderboard", "1")
    assert table.code == 0, table.err
    lines = [line.replace("│", " ").split() for line in table.out.splitlines()]
    first = choices[0]["params"]
    for target in ("gesture", "place"):
        shown = ["cr:logistic+tuned", "1", "1", target, f"C={first[target]['C']:g}"]
        assert shown in lines, table.out


def test_a_stack_records_the_members_each_fold_chose(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    args = ["bench", "touch", "--target", "gesture", "-c", "logistic,nb,ibk", "-k", "3"]
    result = run_cli(capsys, db, *args, "--stack", "2", "--json")
    assert result.code == 0, result.err
    report = result.json()
    assert {row["classifier"] for row in report["leaderboard"]} >= {"stack-top2"}
    choices = [c for c in report["choices"] if c["classifier"] == "stack-top2"]
    assert len(choices) == 3
    for choice in choices:
        assert len(choice["params"]["members"]) == 2
        assert set(choice["params"]["members"]) <= {"logistic", "nb", "ibk"}


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--tune", "--budget", "0"], "--budget: Input should be greater than 0"),
        (["--tune", "--budget", "2000"], "--budget: Input should be less than or equal to 1440"),
        (["--budget", "1"], "--budget: is only meaningful with --tune"),
        (["--stack", "0"], "--stack: Input should be greater than or equal to 1"),
        (["--stack", "21"], "--stack: Input should be less than or equal to 20"),
        (["--stack", "3"], "--stack: needs at least 3 classifiers"),
    ],
)
def test_budgets_and_stacks_out_of_range_exit_2_in_one_line(
    capsys: pytest.CaptureFixture[str], db: str, extra: list[str], words: str
) -> None:
    args = ["bench", "touch", "--target", "gesture", "-c", "logistic,nb", *extra]
    result = run_cli(capsys, db, *args)
    assert result.code == 2
    assert words in result.err
    assert len(result.err.strip().splitlines()) == 1


def test_a_stack_on_several_targets_and_a_tune_without_space_exit_2(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    stack = run_cli(capsys, db, "bench", "touch", "-c", "cr:logistic,cr:nb", "--stack", "1")
    assert (
        stack.code == 2
        and "--stack: stacks multi-class classifiers: pick one --target" in stack.err
    )
    tune = run_cli(capsys, db, "bench", "touch", "--target", "gesture", "-c", "nb", "--tune")
    assert tune.code == 2
    assert "--tune: no classifier of this run declares a search space" in tune.err


def test_a_space_parameter_the_estimator_lacks_exits_2(
    capsys: pytest.CaptureFixture[str], db: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    catalogue = dict(touchbench.benchmark.catalogue.CATALOGUE)
    catalogue["logistic"] = replace(catalogue["logistic"], search_space={"penalty_c": (1.0,)})
    patched = MappingProxyType(catalogue)
    monkeypatch.setattr(touchbench.benchmark.catalogue, "CATALOGUE", patched)
    monkeypatch.setattr(touchbench.benchmark.estimators, "CATALOGUE", patched)
    result = run_cli(
        capsys, db, "bench", "touch", "--target", "gesture", "-c", "logistic", "--tune"
    )
    assert result.code == 2
    assert "search space of 'logistic' names 'penalty_c'" in result.err
    assert "LogisticRegression does not have" in result.err
    assert len(result.err.strip().splitlines()) == 1


def test_a_tuned_twin_trains_and_its_stored_model_predicts(
    capsys: pytest.CaptureFixture[str], db: str, tmp_path: Path
) -> None:
    args = ["train", "touch", "--classifier", "logistic+tuned", "--target", "gesture"]
    trained = run_cli(capsys, db, *args, "--name", "tuned", "--json")
    assert trained.code == 0, trained.err
    path = touch_arff(tmp_path / "again.arff", n=30, seed=3)
    predicted = run_cli(capsys, db, "predict", "tuned", str(path), "--json")
    assert predicted.code == 0, predicted.err  # a model the store trusts: no search object
