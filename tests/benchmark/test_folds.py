"""Cross-validation folds: stratified, grouped, joint multi-target, fallbacks, reproducible."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.run.folds import make_fold_plan, make_folds


def check_partition(folds: list, n: int, n_repeats: int = 1) -> None:
    for repeat in range(n_repeats):
        tests = [f.test for f in folds if f.repeat == repeat]
        assert sorted(np.concatenate(tests).tolist()) == list(range(n))
        for f in folds:
            assert not set(f.train) & set(f.test)
            assert len(f.train) + len(f.test) == n


def test_single_target_folds_are_stratified_and_partition_the_data() -> None:
    y = np.repeat([0, 1, 2], [50, 30, 20])
    folds, notes = make_folds(y[:, None], n_folds=10)
    assert notes == []
    assert [(f.repeat, f.fold) for f in folds] == [(0, k) for k in range(10)]
    check_partition(folds, 100)
    for f in folds:
        assert np.bincount(y[f.test], minlength=3).tolist() == [5, 3, 2]


def test_repeats_use_different_shuffles_and_calls_repeat_exactly() -> None:
    y = np.repeat([0, 1], 40)
    folds, _ = make_folds(y, n_folds=4, n_repeats=2, seed=5)
    again, _ = make_folds(y, n_folds=4, n_repeats=2, seed=5)
    assert len(folds) == 8
    check_partition(folds, 80, n_repeats=2)
    for a, b in zip(folds, again, strict=True):
        np.testing.assert_array_equal(a.test, b.test)
    assert not np.array_equal(folds[0].test, folds[4].test)
    other, _ = make_folds(y, n_folds=4, n_repeats=2, seed=6)
    assert not np.array_equal(folds[0].test, other[0].test)


def test_too_few_instances_in_a_class_falls_back_with_a_warning() -> None:
    y = np.repeat([0, 1, 2], [20, 20, 3])
    folds, notes = make_folds(y, n_folds=10)
    assert len(folds) == 3
    assert notes == ["the smallest class has only 3 instance(s): using 3 folds instead of 10"]
    assert all(np.bincount(y[f.test], minlength=3)[2] == 1 for f in folds)


def test_a_singleton_class_still_gives_two_folds_and_says_why() -> None:
    folds, notes = make_folds(np.array([0] * 9 + [1]), n_folds=5)
    assert len(folds) == 2
    assert any("single instance" in note for note in notes)


@pytest.mark.parametrize(
    ("Y", "kwargs", "message"),
    [
        (np.zeros((0, 1), int), {}, "the data set is empty"),
        (np.zeros((5, 1), int), {}, "target 'target 1' has a single class"),
        (np.zeros((5, 1), int), {"target_names": ["gesture"]}, "target 'gesture' has a single"),
        (np.array([[0], [1]]), {"n_folds": 1}, "number of folds must be at least 2"),
        (np.array([[0], [1]]), {"n_repeats": 0}, "number of repeats must be at least 1"),
        (np.array([[0], [1], [0], [1]]), {"groups": np.zeros(4)}, "all instances belong to one"),
        (np.array([[0], [1], [0], [1]]), {"groups": np.zeros(3)}, "groups must have one entry"),
        (
            np.array([[0], [1], [0], [1]]),
            {"groups": np.array(["a", None, "b", "b"], dtype=object)},
            r"1 instance\(s\) have no group \(the first: instance 2\)",
        ),
        (
            np.array([[0], [1], [0], [1]]),
            {"split": "leave-one-group-out"},
            "leave-one-group-out needs groups, and the data set has none",
        ),
        (
            np.array([[0], [1], [0], [1]]),
            {"split": "leave-one-group-out", "groups": np.array(["mug"] * 4)},
            "leave-one-group-out needs at least 2 groups; every instance is in group 'mug'",
        ),
        (
            np.array([[0], [1], [0], [1]]),
            {"split": "leave-one-group-out", "groups": np.arange(4), "n_repeats": 3},
            "the number of repeats must be 1, got 3",
        ),
        (
            np.zeros((4, 1), int),
            {"split": "leave-one-group-out", "groups": np.arange(4)},
            "target 'target 1' has a single class",
        ),
    ],
)
def test_impossible_requests_are_configuration_errors(Y, kwargs, message) -> None:
    with pytest.raises(ConfigurationError, match=message):
        make_folds(Y, **kwargs)


def test_groups_never_straddle_training_and_test() -> None:
    rng = np.random.default_rng(0)
    groups = np.repeat(np.arange(12), 8)
    y = rng.integers(0, 3, size=96)
    folds, notes = make_folds(y, n_folds=4, groups=groups)
    assert notes == [] and len(folds) == 4
    check_partition(folds, 96)
    for f in folds:
        assert not set(groups[f.train]) & set(groups[f.test])


def test_fewer_groups_than_folds_falls_back() -> None:
    groups = np.repeat(np.arange(3), 10)
    folds, notes = make_folds(np.arange(30) % 2, n_folds=10, groups=groups)
    assert len(folds) == 3
    assert notes == ["only 3 groups: using 3 folds instead of 10"]
    for f in folds:
        assert len(set(groups[f.test])) == 1


def test_multi_target_folds_stratify_on_the_joint_combination_when_possible() -> None:
    Y = np.column_stack([np.arange(60) % 2, np.arange(60) % 3])  # 6 combinations of 10
    folds, notes = make_folds(Y, n_folds=5, target_names=["gesture", "place"])
    assert notes == ["folds stratified on the 6 combinations of gesture, place"]
    joint = Y[:, 0] * 3 + Y[:, 1]
    for f in folds:
        assert np.bincount(joint[f.test], minlength=6).tolist() == [2] * 6


def test_multi_target_folds_fall_back_to_plain_k_fold_for_rare_combinations() -> None:
    Y = np.column_stack([np.arange(60) % 2, np.arange(60) % 3])
    Y[0] = [1, 0]  # combination (0, 0) now has 9 members, fewer than 10 folds
    folds, notes = make_folds(Y, n_folds=10)
    assert len(folds) == 10
    assert notes == [
        "folds not stratified: 1 of the 6 combinations of target 1, target 2 have fewer "
        "than 10 instances (plain shuffled k-fold)"
    ]
    check_partition(folds, 60)


def test_leave_one_group_out_makes_one_fold_per_group_each_tested_once() -> None:
    rng = np.random.default_rng(1)
    groups = rng.permutation(np.repeat([f"subject{i:02d}" for i in range(12)], 7))
    y = rng.integers(0, 3, size=groups.size)
    plan = make_fold_plan(y, groups=groups, split="leave-one-group-out", n_folds=5, seed=9)
    assert plan.scheme == "leave-one-group-out over 12 groups" and plan.notes == []
    assert [(f.repeat, f.fold) for f in plan.folds] == [(0, k) for k in range(12)]
    assert plan.test_groups == tuple(f"subject{i:02d}" for i in range(12))
    check_partition(plan.folds, groups.size)
    for fold, held_out in zip(plan.folds, plan.test_groups, strict=True):
        assert set(groups[fold.test]) == {held_out}
        assert held_out not in set(groups[fold.train])
    again = make_fold_plan(y, groups=groups, split="leave-one-group-out", seed=1)
    for a, b in zip(plan.folds, again.folds, strict=True):  # the seed changes nothing
        np.testing.assert_array_equal(a.test, b.test)


def test_leave_one_group_out_also_splits_numeric_targets() -> None:
    values = np.linspace(0.0, 1.0, 20)
    plan = make_fold_plan(
        values, groups=np.arange(20) // 5, regression=True, split="leave-one-group-out"
    )
    assert plan.scheme == "leave-one-group-out over 4 groups" and len(plan.folds) == 4
    assert plan.test_groups == ("0", "1", "2", "3")
