"""Regression: numeric targets as problems, the regressor catalogue, metrics against
scikit-learn, folds, and the direction of the marks for errors."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.metrics import mean_absolute_error, r2_score, root_mean_squared_error
from threadpoolctl import threadpool_limits

from touchbench.benchmark.catalogue.regressors import (
    GP_MAX_INSTANCES,
    NATIVE_MULTI_OUTPUT,
    REGRESSORS,
    regression_suite,
    regressor_spec,
)
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.evaluation.leaderboard import build_leaderboard
from touchbench.benchmark.evaluation.regression import regression_scores
from touchbench.benchmark.problem import Problem, problem_from_dataset
from touchbench.benchmark.results import TaskKey, TaskResult
from touchbench.benchmark.run.folds import make_fold_plan
from touchbench.benchmark.sequence import SequenceLayout


def numeric_dataset(n: int = 40, *, nominal_target: bool = False, seed: int = 0) -> Dataset:
    """Features f0..f2 and a nominal one; targets x and y (numeric), [c (nominal)] last."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 3))
    mic = (np.arange(n) % 2).astype(float)
    x = 2 * X[:, 0] - X[:, 1] + 0.05 * rng.normal(size=n)
    y = X[:, 2] ** 2 + mic
    columns = [X, mic[:, None], x[:, None], y[:, None]]
    attributes = [Attribute(f"f{i}", "numeric") for i in range(3)]
    attributes += [
        Attribute("mic", "nominal", values=("a", "b")),
        Attribute("x", "numeric"),
        Attribute("y", "numeric"),
    ]
    if nominal_target:
        columns.append((x > 0).astype(float)[:, None])
        attributes.append(Attribute("c", "nominal", values=("low", "high")))
    n_targets = 3 if nominal_target else 2
    schema = Schema(
        relation="numeric",
        attributes=tuple(attributes),
        target_indices=tuple(range(len(attributes) - n_targets, len(attributes))),
    )
    return Dataset(schema, np.hstack(columns), name="numeric")


def test_numeric_targets_make_a_regression_problem_with_float_targets() -> None:
    problem, notes = problem_from_dataset(numeric_dataset(), position=("y", "x"))
    assert problem.kind == "regression"
    assert problem.Y.dtype == np.float64 and problem.Y.shape == (40, 2)
    assert problem.n_classes == () and problem.coordinates == (1, 0)
    assert problem.nominal_features == {3: 2} and notes == []


def test_classification_problems_are_unchanged() -> None:
    problem = Problem(X=np.zeros((4, 1)), Y=[0, 1, 0, 1], n_classes=(2,), target_names=("c",))
    assert problem.kind == "multiclass" and problem.Y.dtype == np.int64


@pytest.mark.parametrize(
    ("position", "message"),
    [
        (("x", "f0"), "'f0' is not a target"),
        (("x", "c"), "'c' is a nominal target"),
        (("x",), "a position takes 2 or 3 distinct numeric targets"),
    ],
)
def test_a_position_must_be_two_or_three_numeric_targets(
    position: tuple[str, ...], message: str
) -> None:
    data = numeric_dataset(nominal_target=True)
    with pytest.raises(ConfigurationError, match=message):
        problem_from_dataset(data, position=position)


def test_nominal_and_numeric_targets_together_are_refused() -> None:
    with pytest.raises(ConfigurationError, match="targets mix nominal and numeric"):
        problem_from_dataset(numeric_dataset(nominal_target=True))


def test_scores_match_scikit_learn_for_one_and_several_targets() -> None:
    rng = np.random.default_rng(3)
    true = rng.normal(size=(50, 3)) * [1.0, 10.0, 0.1]
    pred = true + rng.normal(size=(50, 3))
    scores, per_target = regression_scores(true, pred, target_names=("a", "b", "c"))
    assert scores["mae"] == pytest.approx(mean_absolute_error(true, pred))
    assert scores["rmse"] == pytest.approx(root_mean_squared_error(true, pred))
    assert scores["r2"] == pytest.approx(r2_score(true, pred))
    assert per_target is not None
    assert per_target["b"]["rmse"] == pytest.approx(root_mean_squared_error(true[:, 1], pred[:, 1]))
    assert per_target["c"]["r2"] == pytest.approx(r2_score(true[:, 2], pred[:, 2]))
    one, none = regression_scores(true[:, 0], pred[:, 0], target_names=("a",))
    assert none is None
    assert one["r2"] == pytest.approx(r2_score(true[:, 0], pred[:, 0]))
    constant = np.full(5, 2.0)
    assert regression_scores(constant, constant + 1, target_names=("k",))[0]["r2"] == (
        r2_score(constant, constant + 1)
    )


def test_euclidean_error_is_the_mean_distance_between_positions() -> None:
    true = np.array([[0.0, 0.0, 5.0], [1.0, 1.0, 5.0]])
    pred = np.array([[3.0, 4.0, 0.0], [1.0, 1.0, 5.0]])
    scores, _ = regression_scores(true, pred, target_names=("x", "y", "z"), coordinates=(0, 1))
    assert scores["euclidean_error"] == pytest.approx(2.5)  # (5 + 0) / 2, z not a coordinate
    assert "euclidean_error" not in regression_scores(true, pred, target_names="xyz")[0]


def mae_results(classifier: str, mae: np.ndarray) -> list[TaskResult]:
    return [
        TaskResult(TaskKey(classifier, 0, k), "ok", None, {"mae": float(v)}, None, 90, 10)
        for k, v in enumerate(mae)
    ]


def test_a_lower_error_ranks_first_and_is_marked_better() -> None:
    noise = np.linspace(-0.01, 0.01, 10)
    results = mae_results("good", 0.5 + noise) + mae_results("bad", 2.0 - noise)
    board = build_leaderboard(results, metric="mae", baseline="bad")
    assert [row.classifier for row in board.rows] == ["good", "bad"]
    assert board.row("good").mark == "v" and board.summary == (1, 0, 0)
    against_best = build_leaderboard(results, metric="mae")
    assert against_best.baseline == "good" and against_best.row("bad").mark == "*"


def tiny_problem(n_targets: int, n: int = 30, *, windows: bool = False) -> Problem:
    """``windows``: 2-channel windows of 8 steps follow the features (a sequence data set)."""
    problem, _ = problem_from_dataset(numeric_dataset(n))
    X, sequence = problem.X, None
    if windows:
        noise = np.random.default_rng(0).normal(size=(n, 16))
        X = np.column_stack([X, noise + problem.Y[:, :1]])
        sequence = SequenceLayout(start=problem.X.shape[1], channels=("a", "b"), length=8)
    return Problem(
        X=X,
        Y=problem.Y[:, :n_targets],
        n_classes=(),
        target_names=problem.target_names[:n_targets],
        nominal_features=problem.nominal_features,
        sequence=sequence,
        task="regression",
    )


@pytest.mark.parametrize("regressor_id", list(REGRESSORS))
def test_every_regressor_fits_one_and_several_targets(regressor_id: str) -> None:
    for n_targets in (1, 2):
        problem = tiny_problem(n_targets, windows=REGRESSORS[regressor_id].needs_sequence)
        model = build_estimator(regressor_id, problem, random_state=0)
        if "classifier__max_epochs" in model.get_params():  # networks: a few quick epochs
            model.set_params(classifier__max_epochs=3)
        Y = problem.Y if n_targets > 1 else problem.Y[:, 0]
        with threadpool_limits(limits=1):  # boosting's OpenMP threads spin on a shared machine
            predicted = np.asarray(model.fit(problem.X, Y).predict(problem.X[:5]))
        assert predicted.reshape(5, -1).shape == (5, n_targets)
        assert np.all(np.isfinite(predicted))


def test_chains_and_per_target_models_on_several_targets() -> None:
    problem = tiny_problem(2)
    chain = build_estimator("rc:ridge", problem)[-1]
    assert type(chain).__name__ == "RegressorChain"
    assert type(build_estimator("br:rf", problem)[-1]).__name__ == "MultiOutputRegressor"
    assert "svm-rbf" not in NATIVE_MULTI_OUTPUT
    assert type(build_estimator("svm-rbf", problem)[-1]).__name__ == "MultiOutputRegressor"
    assert type(build_estimator("rf", problem)[-1]).__name__ == "RandomForestRegressor"
    assert regression_suite("default", n_targets=2, n_instances=50)[-3:] == [
        "rc:ridge",
        "rc:svm-rbf",
        "rc:xgb",
    ]


@pytest.mark.parametrize(
    ("regressor_id", "n_targets", "message"),
    [
        ("j48", 1, "classifier 'j48' has no regressor: the targets are numeric"),
        ("bcc:rf", 2, "unknown multi-output method 'bcc'"),
        ("rc:ridge", 1, "this regression has one target: use 'ridge'"),
        ("rff", 1, "did you mean 'rf'"),
    ],
)
def test_ids_without_a_regressor_are_refused(
    regressor_id: str, n_targets: int, message: str
) -> None:
    with pytest.raises(ConfigurationError, match=message):
        regressor_spec(regressor_id, n_targets=n_targets)


def test_the_gaussian_process_is_limited_by_the_number_of_instances() -> None:
    with pytest.raises(ConfigurationError, match=f"limited to {GP_MAX_INSTANCES} instances"):
        regressor_spec("gp", n_targets=1, n_instances=GP_MAX_INSTANCES + 1)
    assert "gp" in regression_suite("default", n_targets=1, n_instances=GP_MAX_INSTANCES)
    assert "gp" not in regression_suite("default", n_targets=1, n_instances=GP_MAX_INSTANCES + 1)


def test_regression_folds_are_shuffled_k_fold_or_group_k_fold() -> None:
    values = np.linspace(0.0, 1.0, 40)[:, None]
    plan = make_fold_plan(values, n_folds=4, regression=True)
    assert plan.scheme == "k-fold" and len(plan.folds) == 4
    assert not np.array_equal(plan.folds[0].test, np.arange(10))  # shuffled
    groups = np.repeat(np.arange(8), 5)
    grouped = make_fold_plan(values, n_folds=4, regression=True, groups=groups)
    assert grouped.scheme == "group k-fold"
    for fold in grouped.folds:
        assert not set(groups[fold.train]) & set(groups[fold.test])
    few = make_fold_plan(
        values, n_folds=10, regression=True, groups=np.repeat(np.arange(3), 14)[:40]
    )
    assert len(few.folds) == 3 and few.scheme == "group k-fold"


def test_classification_folds_name_their_scheme() -> None:
    labels = np.tile([0, 1], 20)
    assert make_fold_plan(labels, n_folds=4).scheme == "stratified k-fold"
    groups = np.repeat(np.arange(8), 5)
    assert make_fold_plan(labels, n_folds=4, groups=groups).scheme == "stratified group k-fold"
