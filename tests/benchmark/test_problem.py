"""From a data set to the engine's problem: targets, usable features, missing targets."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.problems import make_problem
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.problem import problem_from_dataset

NAN = np.nan


def test_usable_features_nominal_columns_and_dropped_instances() -> None:
    data = make_problem(
        [[0, 0, 2, 1.5, 100], [1, 0, NAN, 2.5, 200], [NAN, 0, 1, 3.5, 300]],
        weights=np.array([1.0, 2.0, 1.0]),
    )
    data.groups = np.array([7, 8, 9])
    problem, notes = problem_from_dataset(data)
    np.testing.assert_array_equal(problem.X, [[2, 1.5, 100], [NAN, 2.5, 200]])
    np.testing.assert_array_equal(problem.Y, [[0], [1]])
    assert problem.nominal_features == {0: 3}
    assert problem.n_classes == (2,) and problem.target_names == ("gesture",)
    np.testing.assert_array_equal(problem.groups, [7, 8])
    assert problem.kind == "multiclass"
    assert notes == [
        "string attribute(s) not used as features: note",
        "1 instance(s) with a missing target value left out",
        "instance weights are not used: every instance counts once",
    ]


def test_several_targets_make_a_multitarget_problem() -> None:
    problem, _ = problem_from_dataset(make_problem([[0, 0, 2, 1.0, 0], [1, 0, 1, 2.0, 0]], (0, 2)))
    assert problem.kind == "multitarget" and problem.n_classes == (2, 3)
    assert problem.target_names == ("gesture", "colour")


def test_a_numeric_target_makes_a_regression_and_a_date_target_is_refused() -> None:
    problem, _ = problem_from_dataset(make_problem([[0, 0, 2, 1.5, 0], [1, 0, 1, NAN, 0]], (3,)))
    assert problem.kind == "regression" and problem.n_classes == ()
    np.testing.assert_array_equal(problem.Y, [[1.5]])
    with pytest.raises(ConfigurationError, match="target 'when' is a date attribute"):
        problem_from_dataset(make_problem([[0, 0, 2, 1.0, 0]], (4,)))
    with pytest.raises(ConfigurationError, match="targets mix nominal and numeric"):
        problem_from_dataset(make_problem([[0, 0, 2, 1.0, 0]], (0, 3)))
