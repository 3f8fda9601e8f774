"""Racing and the total budget in the engine: fold-major rounds, drops by the (moderated)
corrected resampled t-test against the leader, results that do not depend on timing, and a
budget that stops starting tasks (counted, not timed: the budget's clock is the test's)."""

from __future__ import annotations

import threading
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.gate import CLASSIFIERS, Gate
from touchbench.benchmark.catalogue.costs import Shape, cost_label, estimate_seconds
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import classifier_spec
from touchbench.benchmark.evaluation.leaderboard import build_leaderboard, mark_against
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.results import Drop, TaskKey, TaskResult
from touchbench.benchmark.run.engine import RaceRule, run_tasks
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.run.racing import race_round
from touchbench.benchmark.run.schedule import RoundSchedule

TIMEOUT = 120.0


def separable(n: int = 150, seed: int = 0) -> Problem:
    """Three classes a feature separates well: zero-rule is clearly worse than the rest."""
    rng = np.random.default_rng(seed)
    y = np.arange(n) % 3
    X = rng.normal(size=(n, 4))
    X[:, 0] += 4.0 * y
    return Problem(X=X, Y=y[:, None], n_classes=(3,), target_names=("gesture",))


@pytest.fixture(scope="module")
def problem() -> Problem:
    return separable()


@pytest.fixture(scope="module")
def folds(problem: Problem) -> list:
    return make_folds(problem.Y, n_folds=6)[0]


def race(problem: Problem, folds: list, classifiers: list[str], jobs: int = 2, **options: Any):
    drops: list[Drop] = []
    results = run_tasks(
        problem,
        classifiers,
        folds,
        jobs=jobs,
        timeout=TIMEOUT,
        on_drop=drops.append,
        **options,
    )
    return results, drops


#: The entries most tests race: zero-rule is clearly worse than the other two.
IDS = ["zeror", "nb", "j48"]


@pytest.fixture(scope="module")
def raced(problem: Problem, folds: list) -> tuple[list[TaskResult], list[Drop]]:
    """One local race of :data:`IDS`, shared by the tests that check it (a worker pool's
    start costs more than the race)."""
    return race(problem, folds, IDS, race=RaceRule("f1_weighted"))


def test_the_race_drops_zero_rule_after_the_third_fold_and_keeps_the_leader(raced) -> None:
    results, drops = raced
    assert [(d.classifier, d.reason, d.after_fold, d.leader) for d in drops] == [
        ("zeror", "race", 3, "nb")
    ]
    assert drops[0].p_value is not None and drops[0].p_value <= 0.01
    counts = Counter(r.key.classifier for r in results)
    assert counts == {"zeror": 3, "nb": 6, "j48": 6}
    # its results are folds 1-3 exactly, and its mean so far is theirs
    zeror = sorted(r.key.fold for r in results if r.key.classifier == "zeror")
    assert zeror == [0, 1, 2]
    mean = np.mean([r.metrics["f1_weighted"] for r in results if r.key.classifier == "zeror"])
    assert drops[0].mean == pytest.approx(mean)


def test_the_baseline_is_never_dropped(problem, folds) -> None:
    rule = RaceRule("f1_weighted", protected=frozenset({"zeror"}))
    results, drops = race(problem, folds, ["zeror", "nb", "j48"], jobs=1, race=rule)
    assert drops == []
    assert Counter(r.key.classifier for r in results) == {"zeror": 6, "nb": 6, "j48": 6}


def test_marks_and_p_values_equal_a_full_run_restricted_to_the_same_folds(
    problem, folds, raced
) -> None:
    results, drops = raced
    full, _ = race(problem, folds, IDS, jobs=1)  # no race: the reference, in one worker
    assert len(full) == len(IDS) * len(folds) > len(results)
    ran = {r.key for r in results}
    restricted = [r for r in full if r.key in ran]
    by_race = build_leaderboard(results, drops={d.classifier: d for d in drops})
    by_full = build_leaderboard(restricted)
    assert by_race.baseline == by_full.baseline
    for mine, theirs in zip(by_race.rows, by_full.rows, strict=True):
        assert (mine.classifier, mine.rank, mine.mark, mine.n_ok) == (
            theirs.classifier,
            theirs.rank,
            theirs.mark,
            theirs.n_ok,
        )
        assert mine.metrics["f1_weighted"] == theirs.metrics["f1_weighted"]
        np.testing.assert_equal(mine.p_value, theirs.p_value)
    assert by_race.row("zeror").dropped == drops[0]


def test_regression_races_by_mae_where_lower_is_better() -> None:
    rng = np.random.default_rng(1)
    X = rng.normal(size=(120, 3))
    y = 5.0 * X[:, 0] + rng.normal(scale=0.1, size=120)
    problem = Problem(X=X, Y=y[:, None], n_classes=(), target_names=("force",), task="regression")
    folds = make_folds(problem.Y, n_folds=5, regression=True)[0]
    results, drops = race(problem, folds, ["zeror", "linear"], jobs=1, race=RaceRule("mae"))
    assert [(d.classifier, d.leader) for d in drops] == [("zeror", "linear")]
    counts = Counter(r.key.classifier for r in results)
    assert counts["zeror"] == drops[0].after_fold < 5 and counts["linear"] == 5


def test_multi_target_races_by_the_hamming_score() -> None:
    rng = np.random.default_rng(2)
    n = 120
    Y = np.stack([np.arange(n) % 3, (np.arange(n) // 3) % 2], axis=1)
    X = rng.normal(size=(n, 4)) + np.concatenate([4.0 * Y, 4.0 * Y], axis=1)
    problem = Problem(X=X, Y=Y, n_classes=(3, 2), target_names=("gesture", "place"))
    folds = make_folds(problem.Y, n_folds=5, target_names=problem.target_names)[0]
    results, drops = race(
        problem, folds, ["cr:zeror", "cr:nb"], jobs=1, race=RaceRule("hamming_score")
    )
    assert [(d.classifier, d.leader) for d in drops] == [("cr:zeror", "cr:nb")]
    counts = Counter(r.key.classifier for r in results)
    assert counts["cr:zeror"] == drops[0].after_fold < 5 and counts["cr:nb"] == 5


def test_a_race_on_dask_drops_what_it_drops_locally(problem, folds, raced, dask_scheduler) -> None:
    local, local_drops = raced
    remote, remote_drops = race(
        problem, folds, IDS, race=RaceRule("f1_weighted"), scheduler=dask_scheduler
    )
    assert remote_drops == local_drops and [d.classifier for d in local_drops] == ["zeror"]
    assert sorted(r.key for r in remote) == sorted(r.key for r in local)


@pytest.fixture(scope="module")
def dask_scheduler() -> Iterator[str]:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=True, dashboard_address=None
    ) as cluster:
        yield cluster.scheduler_address


def test_a_race_needs_three_folds(problem) -> None:
    two = make_folds(problem.Y, n_folds=2)[0]
    with pytest.raises(ConfigurationError, match="at least 3 folds"):
        run_tasks(problem, ["nb"], two, timeout=TIMEOUT, race=RaceRule("f1_weighted"))
    with pytest.raises(ConfigurationError, match="alpha"):
        RaceRule("f1_weighted", alpha=0.5)


# the schedule on its own: results handed in by the test, in any order ------------------


def result(entry: str, fold: int, score: float) -> TaskResult:
    return TaskResult(TaskKey(entry, 0, fold), "ok", None, {"accuracy": score}, None, 90, 10)


#: Per-fold accuracies: c is clearly worse than a; b is close to a.
SCORES = {
    "a": [0.90, 0.92, 0.91, 0.93, 0.90],
    "b": [0.89, 0.93, 0.90, 0.92, 0.91],
    "c": [0.30, 0.31, 0.29, 0.30, 0.32],
}


def drive(order: str) -> tuple[list[TaskKey], list[Drop]]:
    """Run the schedule with results arriving in ``order`` ("fifo" or "lifo" of the
    started tasks, at most three in flight); the delivered keys and the drops."""
    delivered: list[TaskKey] = []
    drops: list[Drop] = []
    schedule = RoundSchedule(
        ["a", "b", "c"],
        [(0, f) for f in range(5)],
        lambda r: delivered.append(r.key),
        hints={"a": 1.0, "b": 1.0, "c": 1.0},
        race=RaceRule("accuracy"),
        test_train_ratio=1 / 9,
        on_drop=drops.append,
    )
    running: list[TaskKey] = []
    while not schedule.exhausted or running:
        while len(running) < 3 and (key := schedule.next_task()) is not None:
            running.append(key)
        key = running.pop(0 if order == "fifo" else -1)
        schedule.arrived(result(key.classifier, key.fold, SCORES[key.classifier][key.fold]))
    return sorted(delivered), drops


def test_the_race_does_not_depend_on_the_order_results_arrive_in() -> None:
    fifo, fifo_drops = drive("fifo")
    lifo, lifo_drops = drive("lifo")
    assert fifo == lifo
    assert fifo_drops == lifo_drops and [d.classifier for d in fifo_drops] == ["c"]
    assert [k.fold for k in fifo if k.classifier == "c"] == [0, 1, 2]


def test_a_resumed_race_replays_its_decisions() -> None:
    previous = [result(e, f, SCORES[e][f]) for e in SCORES for f in range(3)]
    delivered: list[TaskKey] = []
    drops: list[Drop] = []
    schedule = RoundSchedule(
        ["a", "b", "c"],
        [(0, f) for f in range(5)],
        lambda r: delivered.append(r.key),
        hints={},
        previous=previous,
        race=RaceRule("accuracy"),
        test_train_ratio=1 / 9,
        on_drop=drops.append,
    )
    assert [d.classifier for d in drops] == ["c"]
    keys = []
    while (key := schedule.next_task()) is not None:
        keys.append(key)
    assert {k.classifier for k in keys} == {"a", "b"} and {k.fold for k in keys} == {3, 4}


def test_entries_far_from_a_drop_run_ahead_of_a_slow_entry_their_results_held() -> None:
    """d's fourth fold is slow: the survivors (p well above 0.05 against the leader) do not
    wait for it but run their later folds, whose results wait for the decisions they
    follow; the results handed on are those of a race that waited."""
    scores = {
        "a": [0.90, 0.92, 0.91, 0.93, 0.90, 0.92, 0.91, 0.90],
        "b": [0.89, 0.93, 0.90, 0.92, 0.91, 0.91, 0.92, 0.90],
        "c": [0.30, 0.31, 0.29, 0.30, 0.32, 0.30, 0.31, 0.30],
        "d": [0.88, 0.90, 0.93, 0.91, 0.90, 0.92, 0.90, 0.91],
    }
    delivered: list[TaskKey] = []
    drops: list[Drop] = []
    schedule = RoundSchedule(
        list(scores),
        [(0, f) for f in range(8)],
        lambda r: delivered.append(r.key),
        hints={"a": 1.0, "b": 1.0, "c": 1.0, "d": 5.0},
        race=RaceRule("accuracy"),
        test_train_ratio=1 / 9,
        on_drop=drops.append,
    )
    slow = TaskKey("d", 0, 3)
    started: list[TaskKey] = []
    while (key := schedule.next_task()) is not None:
        started.append(key)
        if key != slow:
            schedule.arrived(result(key.classifier, key.fold, scores[key.classifier][key.fold]))
    assert [d.classifier for d in drops] == ["c"]
    # the survivors started every fold while d's fourth runs; what follows the next
    # decision (after round 4, which waits for d) is held back
    assert {k.fold for k in started if k.classifier in "abd"} == set(range(8))
    assert max(k.fold for k in delivered) == 3
    schedule.arrived(result("d", 3, scores["d"][3]))
    while (key := schedule.next_task()) is not None:
        schedule.arrived(result(key.classifier, key.fold, scores[key.classifier][key.fold]))
    assert schedule.exhausted
    assert sorted(delivered) == sorted(
        TaskKey(e, 0, f) for e in scores for f in range(8) if e != "c" or f < 3
    )


@pytest.mark.parametrize("metric", ["accuracy", "mae"])
def test_a_round_keeps_a_close_entry_whose_first_folds_agree_by_chance(metric: str) -> None:
    """Mini gesture's first race dropped ``bagging`` after three folds (p 0.007 against
    ``voting``, its mean then above the final winner's): its three differences from the
    leader happened to agree.  With the variances moderated across the round's 40 entries
    it stays, while the clearly worse go; ``mae`` (lower is better) mirrors it."""
    rng = np.random.default_rng(0)
    leader = np.array([0.87, 0.88, 0.86])
    scores = {"leader": leader}
    for i in range(40):
        scores[f"worse{i}"] = leader + rng.normal(-rng.uniform(0.01, 0.3), 0.02, size=3)
    scores["close"] = leader + np.array([-0.0035, -0.0045, -0.0040])
    sign = -1.0 if metric == "mae" else 1.0
    table = {e: {r: sign * float(v) for r, v in enumerate(s)} for e, s in scores.items()}
    outcome = race_round(RaceRule(metric), table, list(table), 2, test_train_ratio=1 / 9)
    dropped = {d.classifier for d in outcome.drops}
    assert outcome.leader == "leader" and "close" not in dropped
    assert outcome.p_values["close"] > 0.01
    _, plain_p, mark = mark_against(
        np.array(list(table["close"].values())),
        np.array(list(table["leader"].values())),
        test_train_ratio=1 / 9,
        alpha=0.01,
        lower_is_better=metric == "mae",
    )
    assert mark == "*" and plain_p < 0.01  # what the plain test would have dropped
    clearly = {e for e, s in scores.items() if e.startswith("worse") and (s - leader).mean() < -0.1}
    assert clearly and clearly <= dropped
    # a constant deficit of 0.001 (zero variance: the plain test's p is 0) is no drop either
    table["better"] = {r: sign * float(v) for r, v in enumerate(leader + 0.001)}
    again = race_round(RaceRule(metric), table, list(table), 2, test_train_ratio=1 / 9)
    assert again.leader == "better" and "leader" not in {d.classifier for d in again.drops}


# the budget ------------------------------------------------------------------------


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_the_budget_stops_starting_a_slow_entrys_tasks(tmp_path: Path, monkeypatch) -> None:
    """The gate's first fold takes 40 s of the test's clock; with 50 s of budget its second
    cannot fit and is never started, while nb's cheap folds all run."""
    gate = Gate(tmp_path / "gate")
    for name, value in gate.environment().items():
        monkeypatch.setenv(name, value)  # the worker processes read them
    problem = separable(90)
    folds = make_folds(problem.Y, n_folds=5)[0]
    clock = FakeClock()
    started: list[TaskKey] = []
    drops: list[Drop] = []
    outcome: list[list[TaskResult]] = []

    def bench() -> None:
        outcome.append(
            run_tasks(
                problem,
                ["nb", "gate"],
                folds,
                jobs=1,
                timeout=TIMEOUT,
                budget=50.0,
                clock=clock,
                extra_specs={"gate": CLASSIFIERS[0]},
                on_start=started.append,
                on_drop=drops.append,
            )
        )

    thread = threading.Thread(target=bench)
    thread.start()
    gate.wait_started(1)
    clock.now = 40.0
    gate.let_through(1)
    thread.join(TIMEOUT)
    assert not thread.is_alive()
    counts = Counter(key.classifier for key in started)
    assert counts == {"nb": 5, "gate": 1}
    assert Counter(r.key.classifier for r in outcome[0]) == {"nb": 5, "gate": 1}
    assert drops == [Drop("gate", "budget", 1)]
    assert gate.started() == 1


def test_cost_hints_account_for_the_data_shape() -> None:
    xgb, nb = classifier_spec("xgb"), classifier_spec("nb")
    reference = Shape(2000, 100, 5)
    wide = Shape(800, 17_600, 20)
    assert cost_label(xgb, reference) == "fast"
    assert cost_label(xgb, wide) == "slow"
    assert estimate_seconds(xgb, wide) > 100 * estimate_seconds(xgb, reference)
    # naive Bayes grows too, but stays far cheaper than boosting on the same data
    assert estimate_seconds(nb, wide) < estimate_seconds(xgb, wide) / 5


def test_a_race_with_a_budget_ends_and_hands_on_every_result_it_keeps() -> None:
    """Each result takes 10 s of the test's clock; 75 s of budget cut the race mid-way (the
    rounds a decision waits for are never complete), and nothing stays held back."""
    clock = FakeClock()
    delivered: list[TaskKey] = []
    drops: list[Drop] = []
    schedule = RoundSchedule(
        ["a", "b", "c"],
        [(0, f) for f in range(5)],
        lambda r: delivered.append(r.key),
        hints={"a": 1.0, "b": 1.0, "c": 1.0},
        race=RaceRule("accuracy"),
        test_train_ratio=1 / 9,
        budget=75.0,
        on_drop=drops.append,
        clock=clock,
    )
    running: list[TaskKey] = []
    arrived = 0
    while not schedule.exhausted or running:
        while len(running) < 3 and (key := schedule.next_task()) is not None:
            running.append(key)
        if not running:
            break
        key = running.pop(0)
        clock.now += 10.0
        arrived += 1
        schedule.arrived(result(key.classifier, key.fold, SCORES[key.classifier][key.fold]))
    schedule.finish()
    # c's speculative fourth fold may be discarded with it; nothing else is lost
    raced_out = sum(1 for d in drops if d.reason == "race")
    assert schedule.exhausted and arrived - raced_out <= len(delivered) <= arrived
    cut = {d.classifier for d in drops if d.reason == "budget"}
    assert cut and schedule.cut_tasks() > 0
    ran = Counter(k.classifier for k in delivered)
    assert all(d.after_fold == ran[d.classifier] for d in drops if d.reason == "budget")
