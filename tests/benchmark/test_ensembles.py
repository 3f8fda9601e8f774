"""Ensembles of entries computed from the run's fold predictions (benchmark/run/combine.py,
benchmark/run/members.py): the votes scikit-learn's VotingClassifier would give with the same
fitted members, members fitted once per fold and shared, a race that keeps a dropped member's
folds for a live ensemble, stacks and Caruana's selection on inner folds only, and a run
killed and resumed that gives the same ensembles."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.naive_bayes import GaussianNB
from threadpoolctl import threadpool_limits

from tests.support.ensembles import prefit_vote, resumable, small_problem, stand_in, vote
from touchbench.benchmark.catalogue import ClassifierSpec, get_spec
from touchbench.benchmark.catalogue.ensembles import selection_spec
from touchbench.benchmark.catalogue.stacking import stacked_spec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import build_estimator, classifier_spec
from touchbench.benchmark.evaluation.leaderboard import build_leaderboard
from touchbench.benchmark.evaluation.metrics import multiclass_scores
from touchbench.benchmark.predictions import FoldPredictions, decode
from touchbench.benchmark.results import Drop, Origin, TaskKey, TaskResult
from touchbench.benchmark.run.engine import Problem, plan_run, run_tasks
from touchbench.benchmark.run.folds import Fold, make_folds
from touchbench.benchmark.run.racing import RaceRule

TIMEOUT = 600.0
COSTS = {"fit_time", "predict_time", "fit_cpu_time", "predict_cpu_time", "model_size"}
COSTS |= {"inner_time", "inner_cpu_time"}


class CountingNB(GaussianNB):
    """Gaussian naive Bayes that appends its training rows' count to ``log`` at each fit
    (the engine's workers are other processes: a file counts across them)."""

    def __init__(self, log: str = "", priors: object = None, var_smoothing: float = 1e-9) -> None:
        super().__init__(priors=priors, var_smoothing=var_smoothing)
        self.log = log

    def fit(self, X: np.ndarray, y: np.ndarray, sample_weight: object = None) -> CountingNB:
        with open(self.log, "a") as out:
            out.write(f"{len(y)}\n")
        return super().fit(X, y)


class RowSpy(ClassifierMixin, BaseEstimator):
    """Writes the row ids (column 0) it is fitted on to a new file in ``folder``, then
    predicts by 1-nearest id: only memorising a row predicts its noise label."""

    def __init__(self, folder: str = "") -> None:
        self.folder = folder

    def fit(self, X: np.ndarray, y: np.ndarray) -> RowSpy:
        ids = X[:, 0].astype(int)
        name = f"{os.getpid()}-{time.monotonic_ns()}"
        (Path(self.folder) / name).write_text(" ".join(map(str, ids)))
        self.ids_, self.y_ = ids, np.asarray(y)
        self.classes_ = np.unique(y)
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        nearest = np.abs(X[:, [0]] - self.ids_[None, :]).argmin(axis=1)
        return self.y_[nearest]


@pytest.fixture(scope="module")
def problem() -> Problem:
    return small_problem()


@pytest.fixture(scope="module")
def folds(problem: Problem) -> list[Fold]:
    return make_folds(problem.Y, n_folds=3)[0]


def by_key(results: list[TaskResult]) -> dict[TaskKey, TaskResult]:
    return {r.key: r for r in results}


def scores(result: TaskResult) -> dict[str, float]:
    return {k: v for k, v in result.metrics.items() if k not in COSTS}


@pytest.mark.parametrize("entry", ["voting", "voting-hard"])
def test_a_vote_from_fold_predictions_is_the_voting_classifier_of_the_same_fitted_members(
    problem: Problem, folds: list[Fold], entry: str
) -> None:
    """Members fitted once, a VotingClassifier made of them without refitting: the same
    labels and probabilities to the last bit, and so the same scores; the ensemble that
    fits its own members (a model trained alone) gives them too."""
    results = by_key(run_tasks(problem, [entry], folds, timeout=TIMEOUT, jobs=2))
    spec = get_spec(entry)
    X, y = problem.X, problem.Y[:, 0]
    with threadpool_limits(limits=1):  # as in the engine's workers
        for fold in folds:
            combined = prefit_vote(spec, problem, fold)
            fitted = combined.estimators
            refitted = build_estimator(entry, problem).fit(X[fold.train], y[fold.train])
            ours = results[TaskKey(entry, 0, fold.fold)]
            assert ours.ok and ours.predictions is not None
            for model in (combined, refitted):
                labels = model.predict(X[fold.test])
                np.testing.assert_array_equal(ours.predictions.label, labels)
                proba = model.predict_proba(X[fold.test]) if spec.combine == "soft" else None
                if proba is not None:
                    np.testing.assert_array_equal(ours.predictions.probabilities, proba)
                else:
                    assert ours.predictions.probabilities is None
                expected, _ = multiclass_scores(y[fold.test], labels, proba, n_classes=3)
                assert {k: v for k, v in scores(ours).items() if k in expected} == pytest.approx(
                    expected, rel=0, abs=0, nan_ok=True
                )
            for member, _ in fitted:  # each member is an entry of the run, with its folds
                assert results[TaskKey(member, 0, fold.fold)].ok


def test_a_member_shared_by_two_ensembles_is_fitted_once_per_fold(
    problem: Problem, folds: list[Fold], tmp_path: Path
) -> None:
    log = tmp_path / "fits"
    counted = stand_in("counted", CountingNB, True, log=str(log))
    extra = {
        "vote-a": vote("vote-a", "soft", counted, get_spec("logistic")),
        "vote-b": vote("vote-b", "hard", get_spec("nb"), counted, get_spec("ibk")),
    }
    plan = plan_run(problem, ["vote-a", "vote-b", "nb"], extra_specs=extra)
    assert plan.helpers == ("counted", "logistic", "ibk")  # nb is asked for
    assert plan.entries == ("vote-a", "vote-b", "nb", "counted", "logistic", "ibk")
    reported: list[TaskResult] = []
    results = run_tasks(
        problem,
        ["vote-a", "vote-b", "nb"],
        folds,
        timeout=TIMEOUT,
        jobs=2,
        extra_specs=extra,
        on_result=reported.append,
    )
    fits = sorted(int(line) for line in log.read_text().split())
    assert fits == sorted(int(f.train.size) for f in folds)  # once per fold, no more
    assert [r.key for r in results] == [
        TaskKey(entry, 0, f.fold) for entry in plan.entries for f in folds
    ]
    assert sorted(r.key for r in reported) == sorted(r.key for r in results)
    assert all(r.ok for r in results)
    # a vote costs its members' fits: what it would cost alone
    for fold in folds:
        a = by_key(results)[TaskKey("vote-a", 0, fold.fold)]
        parts = [by_key(results)[TaskKey(m, 0, fold.fold)] for m in ("counted", "logistic")]
        assert a.metrics["model_size"] == sum(p.metrics["model_size"] for p in parts)
        assert a.metrics["fit_time"] >= sum(p.metrics["fit_time"] for p in parts)
    board = build_leaderboard(results, origins=plan.origins())
    assert board.row("vote-b").origin == Origin("from fold predictions", ("nb", "counted", "ibk"))
    assert board.row("counted").origin == Origin("helper", ("vote-a", "vote-b"))
    assert board.row("nb").origin is None
    row = board.row("vote-a").to_json()
    assert row["origin"]["note"] == "from fold predictions of counted, logistic"
    assert board.row("ibk").to_json()["origin"]["note"] == "helper of vote-b"


def test_the_catalogue_s_ensembles_are_defined_by_their_members() -> None:
    voting, hard, stacking = get_spec("voting"), get_spec("voting-hard"), get_spec("stacking")
    assert [m.id for m in voting.members] == ["xgb", "hgb", "calibrated-svm-rbf"]
    assert [m.id for m in hard.members] == ["logistic", "rf", "svm-rbf"]
    assert [m.id for m in stacking.members] == ["rf-200", "extra-trees-200", "svm-rbf", "logistic"]
    assert (voting.combine, hard.combine, stacking.combine) == ("soft", "hard", "stack")
    assert voting.description == "Soft vote of xgb, hgb and calibrated-svm-rbf"
    assert hard.description == "Majority vote of logistic, rf and svm-rbf"
    assert "rf-200, extra-trees-200, svm-rbf and logistic" in stacking.description
    for spec in (voting, hard, stacking):
        assert spec.to_json()["members"] == [m.id for m in spec.members]
        for member in spec.members:  # each member is the catalogue's own entry
            catalogued = get_spec(member.id)
            assert (member.factory, member.params) == (catalogued.factory, catalogued.params)
    assert get_spec("rf-200").params == {"n_estimators": 200}
    assert get_spec("extra-trees-200").params == {"n_estimators": 200}


def _racing_problem() -> Problem:
    rng = np.random.default_rng(4)
    y = np.arange(180) % 3
    X = rng.normal(size=(180, 3)) + 2.5 * y[:, None]
    return Problem(X=X, Y=y[:, None], n_classes=(3,), target_names=("gesture",))


def _race(
    classifiers: list[str], extra: dict[str, ClassifierSpec]
) -> tuple[Problem, list[Fold], list[TaskResult], list[Drop]]:
    """6 folds of :func:`_racing_problem` raced on accuracy: the results and the drops."""
    problem = _racing_problem()
    folds = make_folds(problem.Y, n_folds=6)[0]
    drops: list[Drop] = []
    raced = run_tasks(
        problem,
        classifiers,
        folds,
        timeout=TIMEOUT,
        jobs=2,
        extra_specs=extra,
        race=RaceRule("accuracy", alpha=0.01),
        on_drop=drops.append,
    )
    return problem, folds, raced, drops


def test_a_live_ensemble_keeps_the_folds_of_a_member_the_race_dropped() -> None:
    extra = {"vote": vote("vote", "soft", get_spec("logistic"), get_spec("zeror"))}
    problem, folds, raced, drops = _race(["logistic", "zeror", "vote"], extra)
    assert [(d.classifier, d.reason, d.after_fold) for d in drops] == [("zeror", "race", 3)]
    keys = {r.key for r in raced}
    assert {k.fold for k in keys if k.classifier == "zeror"} == {0, 1, 2}
    assert {k.fold for k in keys if k.classifier == "vote"} == set(range(6))
    # its later folds are those of the same vote with zeror a helper, unraced (in one worker)
    full = by_key(run_tasks(problem, ["vote"], folds, timeout=TIMEOUT, jobs=1, extra_specs=extra))
    for result in raced:
        if result.key.classifier == "vote":
            twin = full[result.key]
            assert result.predictions is not None and twin.predictions is not None
            assert result.predictions.same_as(twin.predictions)
            assert scores(result) == scores(twin)


def test_a_helper_of_a_dropped_ensemble_stops_with_it() -> None:
    weak = vote("weak", "hard", get_spec("zeror"), get_spec("stump"), get_spec("nb-gaussian"))
    _, _, raced, drops = _race(["logistic", "weak"], {"weak": weak})
    assert [(d.classifier, d.after_fold) for d in drops] == [("weak", 3)]
    for helper in ("zeror", "stump", "nb-gaussian"):
        assert {r.key.fold for r in raced if r.key.classifier == helper} == {0, 1, 2}


def _leaky_problem(n: int = 150) -> Problem:
    """Row ids in column 0, noise labels: only a model that saw a row predicts it."""
    rng = np.random.default_rng(0)
    X = np.column_stack([np.arange(n, dtype=np.float64), rng.normal(size=(n, 2))])
    return Problem(X=X, Y=rng.integers(0, 3, size=n)[:, None], n_classes=(3,), target_names=("y",))


def test_ensemble_selection_never_reads_an_outer_test_fold(tmp_path: Path) -> None:
    """Inner predictions are of the training fold's rows only, computed once per entry and
    outer fold for the stack and the selection together; nothing is fitted on test rows."""
    problem = _leaky_problem()
    folds = make_folds(problem.Y, n_folds=3)[0]
    spy = stand_in("spy", RowSpy, False, folder=str(tmp_path))
    inner: dict[TaskKey, FoldPredictions] = {}

    def keep(result: TaskResult) -> None:
        if result.inner_predictions is not None:
            inner[result.key] = result.inner_predictions

    stack = stacked_spec([spy, get_spec("nb"), get_spec("zeror")], 2)
    results = run_tasks(
        problem,
        ["spy", "nb", "zeror", stack.id],
        folds,
        timeout=TIMEOUT,
        jobs=2,
        extra_specs={"spy": spy, stack.id: stack},
        ensemble=4,
        on_result=keep,
    )
    assert {k.classifier for k in inner} == {"spy", "nb", "zeror"}
    for key, predictions in inner.items():
        fold = folds[key.fold]
        np.testing.assert_array_equal(predictions.indices, fold.train)
        assert not np.intersect1d(predictions.indices, fold.test).size
    # every fit of the spy, outer or inner, saw one training fold's rows only
    trains = [set(f.train.tolist()) for f in folds]
    fits = [set(map(int, p.read_text().split())) for p in tmp_path.iterdir()]
    # the outer fit and 3 inner ones per fold, for the stack and the selection alike
    assert len(fits) == 4 * len(folds)
    for rows in fits:
        owner = [k for k, train in enumerate(trains) if rows <= train]
        assert owner, "a fit saw rows of an outer test fold"
    assert all(r.ok for r in results if r.key.classifier == stack.id)
    selection = [r for r in results if r.key.classifier == "ensemble-4"]
    assert len(selection) == len(folds) and all(r.ok for r in selection)
    for result in selection:
        assert result.params is not None
        weights = result.params["weights"]
        assert set(weights) <= {"spy", "nb", "zeror"}
        assert sum(weights.values()) == pytest.approx(1.0)
        assert result.metrics["accuracy"] < 0.7  # memorising the test rows would give 1.0


def test_a_stack_and_a_selection_from_fold_predictions_equal_those_fitted_alone(
    problem: Problem, folds: list[Fold]
) -> None:
    """The inner folds are computed once per member and outer fold, in its own task, and
    serve the stack and the selection alike; the fold equals what the stack or the
    selection fitted alone (its own inner fits and refits) predicts."""
    members = ["logistic", "nb", "ibk", "lda"]
    stack = stacked_spec([classifier_spec(m) for m in members], 2)
    results = by_key(
        run_tasks(
            problem,
            [*members, stack.id],
            folds,
            timeout=TIMEOUT,
            jobs=2,
            extra_specs={stack.id: stack},
            ensemble=3,
        )
    )
    selection = selection_spec([classifier_spec(m) for m in members], 3)
    X, y = problem.X, problem.Y[:, 0]
    with threadpool_limits(limits=1):
        for fold in folds:
            for spec in (stack, selection):
                alone = build_estimator(spec.id, problem, extra_specs={spec.id: spec})
                alone.fit(X[fold.train], y[fold.train])
                ours = results[TaskKey(spec.id, 0, fold.fold)]
                assert ours.ok and ours.predictions is not None, ours.error
                np.testing.assert_array_equal(ours.predictions.label, alone.predict(X[fold.test]))
                np.testing.assert_array_equal(
                    ours.predictions.probabilities, alone.predict_proba(X[fold.test])
                )
                assert ours.params == alone[-1].best_params_


def test_ensemble_selection_is_refused_where_it_cannot_run(problem: Problem) -> None:
    with pytest.raises(ConfigurationError, match="`ensemble` must be between 1 and 100"):
        plan_run(problem, ["nb"], ensemble=0)
    two = Problem(
        X=problem.X,
        Y=np.column_stack([problem.Y[:, 0]] * 2),
        n_classes=(3, 3),
        target_names=("a", "b"),
    )
    with pytest.raises(ConfigurationError, match="combines multi-class classifiers"):
        plan_run(two, ["cr:nb"], ensemble=3)


# A run killed with SIGKILL, then resumed --------------------------------------------

RUNNER = """
import json, os, signal, sys
from pathlib import Path
from tests.support.ensembles import resumable
from tests.support.ensembles import small_problem
from touchbench.benchmark.predictions import encode
from touchbench.benchmark.run.engine import run_tasks
from touchbench.benchmark.run.folds import make_folds

out, last = Path(sys.argv[1]), int(sys.argv[2])
count = [0]

def store(result):
    count[0] += 1
    name = out / f"{count[0]:03d}"
    blobs = {"predictions": result.predictions, "inner": result.inner_predictions}
    for part, predictions in blobs.items():
        if predictions is not None:
            (out / f"tmp.{part}").write_bytes(encode(predictions))
            (out / f"tmp.{part}").rename(name.with_suffix(f".{part}"))
    (out / "tmp.json").write_text(json.dumps(result.to_json()))
    (out / "tmp.json").rename(name.with_suffix(".json"))
    if count[0] == last:
        os.kill(os.getpid(), signal.SIGKILL)

problem = small_problem()
folds = make_folds(problem.Y, n_folds=3)[0]
classifiers, extra = resumable(0.2)
run_tasks(problem, classifiers, folds, jobs=1, timeout=600, extra_specs=extra, ensemble=2,
          on_result=store)
"""

#: Results stored before the kill: the first fold's 4 members and 3 ensembles, then 2 of
#: the second fold's members (one task at a time, a fold's ensembles as soon as it is done).
KILLED_AFTER = 9


def _stored(folder: Path, with_predictions: bool) -> list[TaskResult]:
    results = []
    for path in sorted(folder.glob("[0-9]*.json")):
        result = TaskResult.from_json(json.loads(path.read_text()))
        if with_predictions:
            for part, attribute in (("predictions", "predictions"), ("inner", "inner_predictions")):
                blob = path.with_suffix(f".{part}")
                if blob.exists():
                    setattr(result, attribute, decode(blob.read_bytes()))
        results.append(result)
    return results


@pytest.fixture(scope="module")
def killed_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, int]:
    """The folder a run killed midway (SIGKILL of its own process) stored its results in,
    and that process's return code: one killed run, read (never written) by both legs of
    the resume test."""
    folder = tmp_path_factory.mktemp("killed")
    root = Path(__file__).resolve().parents[2]
    command = [sys.executable, "-c", RUNNER, str(folder), str(KILLED_AFTER)]
    runner = subprocess.run(command, cwd=root, timeout=300, check=False)
    return folder, runner.returncode


@pytest.fixture(scope="module")
def uninterrupted_run() -> dict[TaskKey, TaskResult]:
    """The results of the killed run's classifiers run without interruption (only read)."""
    problem = small_problem()
    folds = make_folds(problem.Y, n_folds=3)[0]
    classifiers, extra = resumable(0.0)
    return by_key(
        run_tasks(problem, classifiers, folds, timeout=TIMEOUT, extra_specs=extra, ensemble=2)
    )


@pytest.mark.parametrize("with_predictions", [True, False], ids=["stored", "not stored"])
@pytest.mark.slow
def test_a_run_killed_and_resumed_gives_the_same_ensembles(
    killed_run: tuple[Path, int],
    uninterrupted_run: dict[TaskKey, TaskResult],
    with_predictions: bool,
) -> None:
    """The run's process kills itself (SIGKILL) midway, right after storing a result;
    resumed from what it stored (with its fold predictions, or without them as a store
    that does not keep them): every ensemble fold is the uninterrupted run's."""
    problem = small_problem()
    folds = make_folds(problem.Y, n_folds=3)[0]
    folder, returncode = killed_run
    assert returncode == -signal.SIGKILL
    stored = _stored(folder, with_predictions)
    assert len(stored) == KILLED_AFTER
    classifiers, extra = resumable(0.0)
    expected = uninterrupted_run
    assert len(stored) < len(expected), "the run was not killed midway"
    plan = plan_run(problem, classifiers, extra_specs=extra, ensemble=2)
    again = plan.reruns([(0, f.fold) for f in folds], {r.key for r in stored}, by_key(stored))
    # without their predictions, the stored members an ensemble still needs run again
    assert bool(again) != with_predictions
    resumed = run_tasks(
        problem,
        classifiers,
        folds,
        timeout=TIMEOUT,
        jobs=2,
        extra_specs=extra,
        ensemble=2,
        previous=stored,
    )
    assert {r.key for r in resumed}.isdisjoint({r.key for r in stored})
    final = {r.key: r for r in [*stored, *resumed]}
    assert set(final) == set(expected)
    for key in ("vote", "stack-top2", "ensemble-2", "calibrated-nb"):
        for fold in folds:
            ours, theirs = final[TaskKey(key, 0, fold.fold)], expected[TaskKey(key, 0, fold.fold)]
            assert scores(ours) == scores(theirs), key
            assert ours.params == theirs.params
            if ours.predictions is not None:  # those of this execution (or stored)
                assert theirs.predictions is not None
                assert ours.predictions.same_as(theirs.predictions)
