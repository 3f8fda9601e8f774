"""A run's fold predictions in the store, and the ensembles computed from them: re-scored,
voted, shared, raced and resumed through the app (real SQLite and PostgreSQL stores)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from tests.support.cli_runner import run_cli
from tests.support.ensembles import prefit_vote
from tests.support.gate import Gate
from tests.support.rows import count_of, wait_for_count
from tests.support.synthetic import touch_arff
from touchbench.app.schemas.runs import BenchRequest
from touchbench.app.services.runs import Callbacks, create_run, execute_run
from touchbench.app.services.runs.problem import RunOptions, fold_plan, prepare_problem
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.app.store.predictions import load_predictions
from touchbench.app.store.runs import get_run, load_results
from touchbench.benchmark.catalogue import get_spec
from touchbench.benchmark.evaluation.fold_scores import score_fold
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.results import TaskKey, TaskResult
from touchbench.benchmark.run.folds import Fold

COSTS = {"fit_time", "predict_time", "fit_cpu_time", "predict_cpu_time", "model_size"}
COSTS |= {"inner_time", "inner_cpu_time"}  # seconds of the inner predictions
#: Runs each (command line, output file) of the JSON list in argv[1] with touchbench's main,
#: in order, each command's stdout to its file; exits with the first failing status.
BENCH_EACH = (
    "import contextlib, json, sys\n"
    "from touchbench.app.cli.main import main\n"
    "for command, output in json.loads(sys.argv[1]):\n"
    "    with open(output, 'w') as out, contextlib.redirect_stdout(out):\n"
    "        code = main(command)\n"
    "    if code:\n"
    "        sys.exit(code)\n"
)


def _imported(capsys: pytest.CaptureFixture[str], url: str, path: Path) -> None:
    result = run_cli(capsys, url, "import", str(path), "--json")
    assert result.code == 0, result.err


def _bench(capsys: pytest.CaptureFixture[str], url: str, *args: str) -> dict:
    result = run_cli(capsys, url, "bench", "touch", "--target", "gesture", *args, "--json")
    assert result.code == 0, result.err
    return result.json()


def _problem_and_folds(store: Store, run_id: int) -> tuple[Problem, list[Fold]]:
    """The problem and folds the run was carried out on, as a resume makes them."""
    run = get_run(store, run_id)
    prepared = prepare_problem(load_dataset(store, run.dataset_id), run.config.targets_given, ())
    return prepared.problem, list(fold_plan(prepared, RunOptions.from_config(run.config)).folds)


def _by_key(results: list[TaskResult]) -> dict[TaskKey, TaskResult]:
    return {result.key: result for result in results}


def _scores(result: TaskResult) -> dict[str, float]:
    """A result's scores, without its costs (seconds and bytes differ between runs)."""
    return {k: v for k, v in result.metrics.items() if k not in COSTS}


def _same(a: float, b: float) -> bool:
    return (a != a and b != b) or a == b


def test_a_finished_run_s_fold_predictions_rescore_and_vote_as_refitted(
    capsys: pytest.CaptureFixture[str], store_url: str, store: Store, tmp_path: Path
) -> None:
    """Every stored fold re-scores to its stored metrics exactly; the stored votes are what
    a VotingClassifier of the same fitted members predicts, to the last bit."""
    _imported(capsys, store_url, touch_arff(tmp_path / "touch.arff", n=150))
    board = _bench(
        capsys, store_url, "-c", "nb,logistic,voting-hard,voting", "--folds", "2", "--ensemble", "3"
    )
    origins = {row["classifier"]: row.get("origin") for row in board["leaderboard"]}
    for entry in ("voting", "voting-hard", "ensemble-3"):
        assert origins[entry]["kind"] == "from fold predictions"
        assert origins[entry]["note"].startswith("from fold predictions of ")
    assert origins["rf"] == {
        "kind": "helper",
        "entries": ["voting-hard"],
        "note": "helper of voting-hard",
    }
    assert origins["nb"] is None
    assert any(note.startswith("fitted only as members of ensembles: ") for note in board["notes"])

    run_id = board["run_id"]
    problem, folds = _problem_and_folds(store, run_id)
    results = _by_key(load_results(store, run_id))
    stored = load_predictions(store, run_id)
    inner = load_predictions(store, run_id, part="inner")
    run = get_run(store, run_id)
    entries = [*run.classifiers, *run.config.helpers]
    assert set(run.config.helpers) == {
        "rf", "svm-rbf", "xgb", "hgb", "calibrated-svm-rbf",
    }  # fmt: skip
    assert run.n_tasks == len(entries) * len(folds) == len(results) == len(stored)
    for key, result in results.items():
        assert result.ok, result.error
        found = score_fold(problem, stored[key])
        kept = _scores(result)
        assert set(kept) == set(found.metrics)
        assert all(_same(kept[k], found.metrics[k]) for k in kept), key
        assert result.confusion == found.confusion
        assert result.calibration == found.calibration

    assert inner == {}  # a finished run keeps only its test folds' predictions

    X = problem.X
    with threadpool_limits(limits=1):  # as in the engine's workers
        for entry in ("voting", "voting-hard"):
            spec = get_spec(entry)
            for fold in folds:
                vote = prefit_vote(spec, problem, fold)
                ours = stored[TaskKey(entry, 0, fold.fold)]
                np.testing.assert_array_equal(ours.indices, fold.test)
                np.testing.assert_array_equal(ours.label, vote.predict(X[fold.test]))
                if spec.combine == "soft":
                    np.testing.assert_array_equal(
                        ours.probabilities, vote.predict_proba(X[fold.test])
                    )
                else:
                    assert ours.probabilities is None


def test_a_member_shared_by_two_ensembles_is_fitted_once_per_fold(
    capsys: pytest.CaptureFixture[str], store_url: str, store: Store, tmp_path: Path
) -> None:
    _imported(capsys, store_url, touch_arff(tmp_path / "touch.arff", n=120))
    request = BenchRequest(
        dataset="touch", target="gesture", classifiers=["voting-hard", "stacking"], folds=2
    )
    run = create_run(store, request)
    # voting-hard: logistic, rf, svm-rbf; stacking: rf-200, extra-trees-200, svm-rbf,
    # logistic
    assert run.config.helpers == ["logistic", "rf", "svm-rbf", "rf-200", "extra-trees-200"]
    assert run.n_tasks == 7 * 2
    started: list[TaskKey] = []
    execute_run(store, run.id, callbacks=Callbacks(on_start=started.append))
    starts = Counter(started)
    assert set(starts.values()) == {1}  # no task ran twice
    assert {k.classifier for k in starts} == set(run.config.helpers)  # ensembles fit none
    assert Counter(k.classifier for k in starts) == dict.fromkeys(run.config.helpers, 2)
    results = load_results(store, run.id)
    assert len(results) == 14 and all(r.ok for r in results)
    origins = get_run(store, run.id).config.origins
    assert origins["rf-200"].entries == ["stacking"]
    shared = ["voting-hard", "stacking"]
    assert origins["svm-rbf"].entries == origins["logistic"].entries == shared


def test_an_ensemble_keeps_the_folds_of_a_member_the_race_dropped(
    capsys: pytest.CaptureFixture[str], store_url: str, store: Store, tmp_path: Path
) -> None:
    """zeror is dropped by the race; the selection over it stays live, and each of its
    folds is the unraced run's (zeror still a candidate on the later folds)."""
    _imported(capsys, store_url, touch_arff(tmp_path / "touch.arff", n=180))
    common = ["-c", "logistic,zeror", "--folds", "5", "--ensemble", "2"]
    raced = _bench(capsys, store_url, *common, "--race")
    full = _bench(capsys, store_url, *common)
    rows = {row["classifier"]: row for row in raced["leaderboard"]}
    assert rows["zeror"]["dropped"]["reason"] == "race"
    assert rows["ensemble-2"]["dropped"] is None and rows["ensemble-2"]["n_ok"] == 5
    ours = _by_key(load_results(store, raced["run_id"]))
    theirs = _by_key(load_results(store, full["run_id"]))
    after = rows["zeror"]["dropped"]["after_fold"]
    assert {k.fold for k in ours if k.classifier == "zeror"} == set(range(after))
    selection = [key for key in ours if key.classifier == "ensemble-2"]
    assert len(selection) == 5
    for key in selection:
        assert ours[key].params == theirs[key].params  # the same weights
        assert _scores(ours[key]) == _scores(theirs[key])
    stored = load_predictions(store, raced["run_id"])
    again = load_predictions(store, full["run_id"])
    assert all(stored[key].same_as(again[key]) for key in selection)


@pytest.mark.slow
def test_a_run_killed_and_resumed_gives_the_same_ensembles(
    capsys: pytest.CaptureFixture[str], store_url: str, store: Store, tmp_path: Path
) -> None:
    _imported(capsys, store_url, touch_arff(tmp_path / "touch.arff", n=120))
    gate = Gate(tmp_path / "gate")  # its fits wait for the test: killed while one waits
    environment = {**os.environ, **gate.environment()}
    bench = [sys.executable, "-m", "touchbench.app.cli.main", "--db", store_url, "bench"]
    args = ["touch", "--target", "gesture", "-c", "nb,gate,voting-hard", "--folds", "3"]
    args += ["--ensemble", "2"]
    child = subprocess.Popen(
        [*bench, *args], env=environment, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    # a fold of gate: its fit and 3 inner fits; the second fold's last fit waits
    gate.let_through(7)
    deadline = time.monotonic() + 300
    selections = "SELECT count(*) FROM fold_results WHERE classifier = 'ensemble-2'"
    wait_for_count(store_url, selections, 1, child, deadline)
    gate.wait_started(8)
    os.kill(child.pid, signal.SIGKILL)
    child.wait()
    before = count_of(store_url, "SELECT count(*) FROM fold_results")
    kept = count_of(store_url, selections)
    assert 1 <= kept < 3 and before < 7 * 3
    assert (
        count_of(store_url, "SELECT count(*) FROM fold_predictions WHERE part = 'test'") == before
    )

    # a selection reads its candidates' inner predictions (kept until the run ends): of
    # the training rows only, each once, never a row of the outer test fold
    _, folds = _problem_and_folds(store, 1)
    inner = load_predictions(store, 1, part="inner")
    assert {k.classifier for k in inner} == {"nb", "gate", "logistic", "rf", "svm-rbf"}
    for key, predictions in inner.items():
        fold = folds[key.fold]
        assert sorted(predictions.indices) == sorted(fold.train), key
        assert not set(predictions.indices) & set(fold.test)

    gate.open()
    # the resumed run, then an uninterrupted one, in one process (the gate is a plugin, read
    # when the catalogue is imported: not in this one)
    outputs = [tmp_path / "resumed.json", tmp_path / "again.json"]
    commands = [["--db", store_url, "bench", *c, "--json"] for c in (["--resume", "1"], args)]
    each = [[command, str(output)] for command, output in zip(commands, outputs, strict=True)]
    done = subprocess.run(
        [sys.executable, "-c", BENCH_EACH, json.dumps(each)],
        env=environment,
        capture_output=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr.decode()
    assert json.loads(outputs[0].read_text())["run_id"] == 1
    assert json.loads(outputs[1].read_text())["run_id"] == 2
    first, second = _by_key(load_results(store, 1)), _by_key(load_results(store, 2))
    assert set(first) == {TaskKey(k.classifier, k.repeat, k.fold) for k in second}
    assert len(first) == 7 * 3  # nb, gate, the votes, logistic, rf, svm-rbf
    for key in first:
        if key.classifier in ("ensemble-2", "voting-hard"):
            assert first[key].params == second[key].params
            assert _scores(first[key]) == _scores(second[key]), key
    assert load_predictions(store, 1, part="inner") == {}  # gone once the run ended
    one, two = load_predictions(store, 1), load_predictions(store, 2)
    assert set(one) == set(two) and all(one[key].same_as(two[key]) for key in one)
