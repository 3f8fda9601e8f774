"""Tuned twins and stacks: nested cross-validation that never sees the outer test fold, the
search spaces' checks, and the per-fold record of what was chosen."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, ClassVar

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.neighbors import KNeighborsClassifier

from touchbench.benchmark.catalogue import CATALOGUE, SEARCH_SPACES, build_pipeline, get_spec
from touchbench.benchmark.catalogue.spec import ClassifierSpec
from touchbench.benchmark.catalogue.stacking import stacked_spec
from touchbench.benchmark.catalogue.tuning import TunedClassifier, check_search_space, tuned_spec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.tuned import compare_tuned
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.results import TaskKey, TaskResult
from touchbench.benchmark.run.folds import Fold
from touchbench.benchmark.run.task import TaskContext, execute_task


class RowSpy(ClassifierMixin, BaseEstimator):
    """1-nearest neighbour on all columns but the first, which holds each row's id: every
    id any copy is fitted on is recorded (clones share the class attribute)."""

    seen: ClassVar[set[int]] = set()

    def __init__(self, n_neighbors: int = 1, weights: str = "uniform") -> None:
        self.n_neighbors = n_neighbors
        self.weights = weights

    def fit(self, X: np.ndarray, y: np.ndarray) -> RowSpy:
        RowSpy.seen.update(int(v) for v in X[:, 0])
        self.model_ = KNeighborsClassifier(self.n_neighbors, weights=self.weights)
        self.model_.fit(X[:, 1:], y)
        self.classes_ = self.model_.classes_
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(self.model_.predict(X[:, 1:]))

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(self.model_.predict_proba(X[:, 1:]))


SPY = replace(
    get_spec("knn5"),
    id="spy",
    factory=RowSpy,
    params={},
    needs_scaling=False,
    handles_missing=True,
    search_space={"n_neighbors": (1, 3, 5, 9), "weights": ("uniform", "distance")},
)


def _leaky_problem(n: int = 150) -> tuple[Problem, Fold]:
    """Row ids in column 0; noise features and labels: only memorising a row predicts it, so
    a model that saw the test rows would score perfectly."""
    rng = np.random.default_rng(0)
    X = np.column_stack([np.arange(n, dtype=np.float64), rng.normal(size=(n, 3))])
    y = rng.integers(0, 3, size=n)
    problem = Problem(X=X, Y=y[:, None], n_classes=(3,), target_names=("y",))
    order = rng.permutation(n)
    return problem, Fold(0, 0, np.sort(order[:100]), np.sort(order[100:]))


@pytest.mark.parametrize("kind", ["tuned", "stack"])
def test_nested_search_never_fits_on_the_outer_test_fold(kind: str) -> None:
    problem, fold = _leaky_problem()
    spec = (
        tuned_spec(SPY, budget_minutes=0.05)
        if kind == "tuned"
        else stacked_spec([SPY, tuned_spec(SPY, 0.005), get_spec("nb-gaussian")], 2)
    )
    context = TaskContext(problem, {spec.id: spec, SPY.id: SPY}, [fold], random_state=0)
    RowSpy.seen.clear()
    result = execute_task(context, TaskKey(spec.id, 0, 0))
    assert result.ok, result.error
    test_ids = set(problem.X[fold.test, 0].astype(int))
    assert RowSpy.seen, "the spy was never fitted"
    assert RowSpy.seen <= set(problem.X[fold.train, 0].astype(int))
    assert not RowSpy.seen & test_ids
    assert result.metrics["accuracy"] < 0.7  # memorising the test rows would give 1.0
    assert result.params is not None
    if kind == "tuned":
        assert set(result.params) == {"n_neighbors", "weights"}
        assert result.params["n_neighbors"] in (1, 3, 5, 9)
    else:
        assert len(result.params["members"]) == 2


def test_every_catalogue_space_names_parameters_its_estimator_has() -> None:
    for classifier_id in SEARCH_SPACES:
        spec = CATALOGUE[classifier_id]
        assert spec.search_space == SEARCH_SPACES[classifier_id]
        check_search_space(spec)
        assert get_spec(classifier_id + "+tuned").tuning is not None


def test_a_space_parameter_the_estimator_lacks_is_refused_in_one_line() -> None:
    bad: ClassifierSpec = replace(get_spec("svm-rbf"), search_space={"C": (1.0,), "gama": (0.1,)})
    with pytest.raises(ConfigurationError) as caught:
        tuned_spec(bad)
    message = str(caught.value)
    assert "'svm-rbf'" in message and "'gama'" in message and "SVC" in message
    assert "gamma" in message and "\n" not in message


def test_entries_without_space_and_budgets_out_of_range_are_refused() -> None:
    with pytest.raises(ConfigurationError, match="no search space"):
        get_spec("nb+tuned")
    for budget in (0.0, -1.0, 5000.0, math.nan):
        with pytest.raises(ConfigurationError, match="`budget` must be more than 0"):
            tuned_spec(get_spec("logistic"), budget)
    with pytest.raises(ConfigurationError, match="a stack of the top 2 needs at least 2"):
        stacked_spec([get_spec("nb")], 2)
    with pytest.raises(ConfigurationError, match="`stack` must be between 1 and"):
        stacked_spec([get_spec("nb")], 0)


def test_a_budget_buys_candidates_in_powers_of_the_factor() -> None:
    rng = np.random.default_rng(1)
    X = rng.normal(size=(300, 4))
    y = (X[:, 0] > 0).astype(int)
    model = build_pipeline(tuned_spec(SPY, budget_minutes=10.0), n_features=4)
    RowSpy.seen.clear()
    X_ids = np.column_stack([np.arange(300.0), X[:, 1:]])
    model.fit(X_ids, y)
    tuner = model[-1]
    assert isinstance(tuner, TunedClassifier)
    assert tuner.n_candidates_ == 8  # the whole 8-setting grid: 10 minutes buy more
    assert set(tuner.best_params_) == {"n_neighbors", "weights"}


def _result(classifier: str, fold: int, f1: float, params: Any = None) -> TaskResult:
    return TaskResult(
        TaskKey(classifier, 0, fold),
        "ok",
        None,
        {"f1_weighted": f1},
        None,
        90,
        10,
        params=params,
    )


def test_tuned_twins_are_compared_with_their_defaults_fold_by_fold() -> None:
    results = [_result("rf", k, 0.80 + 0.001 * k) for k in range(10)]
    results += [_result("rf+tuned", k, 0.85 + 0.001 * (k % 3), {"C": k}) for k in range(10)]
    results += [_result("nb", k, 0.7) for k in range(10)]
    (comparison,) = compare_tuned(results)
    assert (comparison.tuned, comparison.default, comparison.n_folds) == ("rf+tuned", "rf", 10)
    assert comparison.mark == "v" and comparison.p < 0.05
    assert comparison.tuned_mean > comparison.default_mean
    assert [c.params for c in comparison.choices] == [{"C": k} for k in range(10)]


def test_chosen_parameters_round_trip_through_json_and_older_results_still_read() -> None:
    result = _result("rf+tuned", 0, 0.9, {"max_features": 0.35, "class_weight": None})
    assert TaskResult.from_json(result.to_json()) == result
    old = result.to_json()
    del old["params"]
    assert TaskResult.from_json(old).params is None


def test_a_multi_target_model_records_what_each_inner_search_chose() -> None:
    from touchbench.benchmark.multitarget import (
        ClassRelevance,
        EnsembleClassifierChains,
        LabelCombination,
        RAkELd,
    )
    from touchbench.benchmark.run.choices import chosen_params

    rng = np.random.default_rng(2)
    X = rng.normal(size=(120, 3))
    Y = np.column_stack([(X[:, 0] > 0) + (X[:, 0] > 1), X[:, 1] > 0, np.zeros(120)]).astype(int)
    names = ("gesture", "place", "constant")
    space = set(SEARCH_SPACES["ibk5-std"])

    def tuned() -> Any:
        return build_pipeline(tuned_spec(get_spec("ibk5-std"), 0.01), n_features=3)

    relevance = ClassRelevance(tuned()).fit(X, Y)
    chosen = chosen_params(relevance, names)
    assert chosen is not None and set(chosen) == {"gesture", "place"}  # constant: no search
    assert all(set(params) == space for params in chosen.values())
    assert chosen["gesture"] == relevance.estimators_[0].estimator_[-1].best_params_
    assert chosen_params(relevance) is None  # without target names: a single-target reading

    joint = chosen_params(LabelCombination(tuned()).fit(X, Y), names)
    assert joint is not None and set(joint) == {"joint"}
    rakel = RAkELd(tuned(), subset_size=2, random_state=0).fit(X, Y[:, :2])
    assert set(chosen_params(rakel, names) or {}) == {"gesture+place"}
    chains = EnsembleClassifierChains(tuned(), n_estimators=2, random_state=0).fit(X, Y[:, :2])
    assert set(chosen_params(chains, names) or {}) == {
        "member 1/gesture",
        "member 1/place",
        "member 2/gesture",
        "member 2/place",
    }
    plain = ClassRelevance(build_pipeline(get_spec("ibk5-std"), n_features=3)).fit(X, Y)
    assert chosen_params(plain, names) is None


@pytest.mark.parametrize("n_candidates", [3, 9, 27])
def test_the_planned_rounds_are_the_rounds_the_search_runs(n_candidates: int) -> None:
    from sklearn.dummy import DummyClassifier
    from sklearn.experimental import enable_halving_search_cv  # noqa: F401
    from sklearn.model_selection import HalvingGridSearchCV, StratifiedKFold

    from touchbench.benchmark.catalogue.tuning import _search_cost, schedule

    rng = np.random.default_rng(3)
    X = rng.normal(size=(540, 2))
    y = (X[:, 0] > 0).astype(int)
    first, last = schedule(n_candidates, 540, 12, 3)
    search = HalvingGridSearchCV(
        DummyClassifier(strategy="stratified"),
        {"random_state": list(range(n_candidates))},
        factor=3,
        cv=StratifiedKFold(3),
        min_resources=first,
        max_resources=last,
    ).fit(X, y)
    assert search.n_candidates_[-1] == 3  # no last round of one candidate, which chooses nothing
    assert search.n_resources_[-1] == 540 // 3
    # each candidate's fit and score on each inner fold, as the plan counts them
    evaluations = _search_cost(n_candidates, 540, 12, 3, 3, lambda rows: 0.0, overhead=1.0)
    assert evaluations == 3 * sum(search.n_candidates_)
    rows = _search_cost(n_candidates, 540, 12, 3, 3, lambda rows: rows)
    rounds = zip(search.n_candidates_, search.n_resources_, strict=True)
    assert rows == pytest.approx(sum(3 * k * r * 2 / 3 for k, r in rounds))
