"""Permutation importance on each outer test fold, per feature and per channel."""

from __future__ import annotations

import numpy as np

from touchbench.benchmark.problem import Problem
from touchbench.benchmark.run.folds import make_fold_plan
from touchbench.benchmark.run.importance import feature_groups, permutation_importance


def test_the_deciding_feature_ranks_first_and_noise_near_zero() -> None:
    rng = np.random.default_rng(0)
    n = 150
    y = np.arange(n) % 3
    decisive = y + rng.normal(scale=0.15, size=n)
    X = np.column_stack([rng.normal(size=n), decisive, rng.normal(size=n)])
    names = ["noise_2", "level_1", "other_2"]
    problem = Problem(X, y[:, None], (3,), ("class",))
    folds = make_fold_plan(problem.Y, n_folds=5, n_repeats=1, seed=0).folds
    found = permutation_importance(problem, "j48", folds, names, n_repeats=2)
    drops = {name: values.mean() for name, values in found.features.items()}
    assert max(drops, key=drops.__getitem__) == "level_1"
    assert drops["level_1"] > 0.4
    assert abs(drops["noise_2"]) < 0.03 and abs(drops["other_2"]) < 0.03
    channels = {name: values.mean() for name, values in found.groups["channel"].items()}
    assert channels["channel 1"] > 0.4 and abs(channels["channel 2"]) < 0.03
    assert found.baseline.shape == (5,) and found.baseline.min() > 0.9


def test_groups_follow_channel_suffixes_and_window_columns() -> None:
    groups = feature_groups(["pitch_1", "pitch_2", "snr_1", "snr_2", "label"])
    assert groups["channel"] == {"channel 1": [0, 2], "channel 2": [1, 3]}
    assert groups["family"] == {"pitch": [0, 1], "snr": [2, 3]}
    windows = feature_groups(["mic0[0]", "mic0[1]", "mic1[0]", "mic1[1]"])
    assert windows == {"channel": {"mic0": [0, 1], "mic1": [2, 3]}}
    assert feature_groups(["a", "b"]) == {}
