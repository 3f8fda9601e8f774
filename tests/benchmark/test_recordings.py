"""Per-recording scores (benchmark/evaluation/recordings.py): pooling a fold's windows by
recording, and a task scored so, in-process, for each kind of problem."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.catalogue import CATALOGUE
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.recordings import Recordings, check_one_label
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.run.task import TaskContext, TaskKey, execute_task

#: 12 recordings of 10 windows each, classes alternating by recording.
GROUPS = np.repeat([f"take{i:02d}.wav" for i in range(12)], 10).astype(object)
CLASS = np.repeat(np.arange(12) % 2, 10)


def test_windows_pool_by_recording_in_order_of_appearance() -> None:
    recordings = Recordings.of(np.array(["b", "a", "b", "c", "a"], dtype=object))
    assert recordings.index.tolist() == [0, 1, 0, 2, 1] and recordings.n_recordings == 3
    assert recordings.truth(np.array([10, 20, 11, 30, 21])).tolist() == [10, 20, 30]
    assert recordings.mean(np.array([1.0, 2.0, 3.0, 4.0, 6.0])).tolist() == [2.0, 4.0, 4.0]
    # a tie goes to the lowest class code; probabilities are averaged, then the argmax
    assert recordings.vote(np.array([1, 0, 0, 2, 1]), 3).tolist() == [0, 0, 2]
    proba = np.array([[0.9, 0.1], [0.4, 0.6], [0.0, 1.0], [0.3, 0.7], [0.4, 0.6]])
    labels, mean = recordings.classes(np.array([0, 1, 1, 1, 1]), proba, 2)
    assert labels.tolist() == [1, 1, 1] and mean is not None
    assert mean[0].tolist() == pytest.approx([0.45, 0.55])


def test_one_label_per_recording_is_checked() -> None:
    Y = CLASS[:, None]
    check_one_label(Y, GROUPS, ["gesture"], "takes")
    with pytest.raises(ConfigurationError, match="data set 'file' has no recording groups"):
        check_one_label(Y, None, ["gesture"], "file")
    mixed = Y.copy()
    mixed[[3, 25]] = 1 - mixed[[3, 25]]
    with pytest.raises(ConfigurationError, match=r"^2 recording.s. hold windows of .*take00"):
        check_one_label(mixed, GROUPS, ["gesture"], "takes")


def _scores(problem: Problem, classifier: str, metric: str) -> tuple[float, float]:
    """Mean of ``metric`` over 4 group folds, per window and per recording."""
    folds, _ = make_folds(
        problem.Y, n_folds=4, groups=problem.groups, regression=problem.kind == "regression"
    )
    means = []
    for by_recording in (False, True):
        context = TaskContext(problem, CATALOGUE, folds, 0, by_recording)
        results = [execute_task(context, TaskKey(classifier, 0, f.fold)) for f in folds]
        assert all(r.ok for r in results), [r.error for r in results]
        assert {r.n_test for r in results} == {30}  # windows: the t-test's ratio is unchanged
        means.append(float(np.mean([r.metrics[metric] for r in results])))
    return means[0], means[1]


def test_recordings_scored_whole_beat_their_noisy_windows() -> None:
    # one feature: the recording's class plus noise of the gap's size
    rng = np.random.default_rng(5)
    X = np.column_stack([CLASS + rng.normal(scale=0.8, size=CLASS.size), rng.normal(size=120)])
    problem = Problem(
        X=X, Y=CLASS[:, None], n_classes=(2,), target_names=("gesture",), groups=GROUPS
    )
    # nb pools its probabilities, ridge (no probabilities) votes
    for classifier in ("nb", "ridge"):
        by_window, by_recording = _scores(problem, classifier, "f1_weighted")
        assert by_window < 0.8 and by_recording > 0.85, (classifier, by_window, by_recording)


def test_a_regression_per_recording_scores_the_mean_prediction() -> None:
    rng = np.random.default_rng(2)
    position = np.repeat(rng.uniform(0, 10, 12), 10)
    X = np.column_stack([position + rng.normal(scale=1.0, size=position.size)])
    problem = Problem(
        X=X, Y=position[:, None], n_classes=(), target_names=("x",), groups=GROUPS,
        task="regression",
    )  # fmt: skip
    by_window, by_recording = _scores(problem, "linear", "mae")
    # a window's error is its noise; 10 windows' mean has a third of it
    assert by_recording < 0.6 * by_window, (by_window, by_recording)


def test_each_target_of_a_multi_target_problem_pools_its_windows() -> None:
    rng = np.random.default_rng(4)
    place = np.repeat(np.arange(12) // 2 % 2, 10)
    X = np.column_stack([CLASS, place]) + rng.normal(scale=0.6, size=(CLASS.size, 2))
    problem = Problem(
        X=X, Y=np.column_stack([CLASS, place]), n_classes=(2, 2),
        target_names=("gesture", "place"), groups=GROUPS,
    )  # fmt: skip
    by_window, by_recording = _scores(problem, "cr:nb", "hamming_score")
    assert by_window < 0.8 and by_recording > 0.9, (by_window, by_recording)
