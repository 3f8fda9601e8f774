"""Ablation's problem without a group of columns, and the learning curve's training cuts:
inside each fold's training instances, stratified, group-aware and nested."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.run.ablation import without_columns
from touchbench.benchmark.run.folds import make_fold_plan
from touchbench.benchmark.run.learning import enough_fraction, learning_folds
from touchbench.benchmark.sequence import SequenceLayout

FRACTIONS = (0.1, 0.25, 0.5, 1.0)


def test_without_columns_keeps_nominal_labels_and_whole_channels() -> None:
    X = np.arange(40, dtype=np.float64).reshape(5, 8) % 3
    layout = SequenceLayout(start=2, channels=("ax", "ay", "az"), length=2)
    problem = Problem(X, np.arange(5) % 2, (2,), ("y",), {1: 3}, sequence=layout)
    reduced = without_columns(problem, [0, 4, 5])  # a column before the block, channel ay
    assert reduced.X.shape == (5, 5)
    np.testing.assert_array_equal(reduced.X, X[:, [1, 2, 3, 6, 7]])
    assert dict(reduced.nominal_features) == {0: 3}
    assert reduced.sequence == SequenceLayout(start=1, channels=("ax", "az"), length=2)
    assert without_columns(problem, [4]).sequence is None  # half a channel: no sequence
    with pytest.raises(ConfigurationError, match="no feature"):
        without_columns(problem, range(8))


@pytest.mark.parametrize("grouped", [False, True])
def test_fractions_never_let_a_test_instance_into_training(grouped: bool) -> None:
    rng = np.random.default_rng(3)
    n = 240
    y = rng.choice(3, size=n, p=[0.6, 0.3, 0.1])
    groups = np.repeat(np.arange(24), 10) if grouped else None
    if grouped:
        y = np.repeat(rng.choice(3, size=24, p=[0.5, 0.3, 0.2]), 10)
    folds = make_fold_plan(y, n_folds=4, seed=1, groups=groups).folds
    cut = learning_folds(folds, FRACTIONS, strata=y, groups=groups, seed=0)
    assert list(cut) == list(FRACTIONS)
    for k, fold in enumerate(folds):
        previous = np.array([], dtype=np.int64)
        for fraction in FRACTIONS:
            part = cut[fraction][k]
            np.testing.assert_array_equal(part.test, fold.test)  # scored on the same instances
            assert np.isin(part.train, fold.train).all()
            assert not np.isin(part.train, fold.test).any()
            assert np.unique(part.train).size == part.train.size
            assert np.isin(previous, part.train).all()  # nested: more data, not other data
            assert part.train.size >= fraction * fold.train.size
            previous = part.train
            if grouped:
                assert not np.isin(groups[part.train], groups[fold.test]).any()
                taken = np.unique(groups[part.train])
                assert np.isin(np.flatnonzero(np.isin(groups, taken)), part.train).all()
            else:
                assert part.train.size <= fraction * fold.train.size + 1
                # each class keeps about its share, and is there at all
                shares = np.bincount(y[part.train], minlength=3) / part.train.size
                full = np.bincount(y[fold.train], minlength=3) / fold.train.size
                assert (np.bincount(y[part.train], minlength=3) > 0).all()
                assert np.abs(shares - full).max() < 0.1
        np.testing.assert_array_equal(cut[1.0][k].train, fold.train)


def test_enough_is_the_smallest_fraction_within_a_point() -> None:
    means = {0.1: 0.70, 0.3: 0.885, 0.5: 0.905, 1.0: 0.90}
    assert enough_fraction(means) == 0.5  # 0.885 is 1.5 points off
    assert enough_fraction(means, tolerance=0.02) == 0.3
    assert enough_fraction({0.1: 0.2, 1.0: 0.1}, lower_is_better=True) == 1.0
    assert enough_fraction({0.1: 0.2, 1.0: float("nan")}) is None
    with pytest.raises(ConfigurationError, match="fraction"):
        learning_folds(make_fold_plan(np.arange(10) % 2, n_folds=2).folds, [1.5])
