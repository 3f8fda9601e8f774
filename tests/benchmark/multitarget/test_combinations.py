"""LC, PS, NSR, RAkELd and SCC: classifiers over joint combinations of targets."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.multitarget import logistic, three_targets, tree
from touchbench.benchmark.multitarget import (
    EnsemblePrunedSets,
    LabelCombination,
    NearestSetReplacement,
    PrunedSets,
    RAkELd,
    SuperClassClassifier,
)


def counted(combinations: dict[tuple[int, ...], int]) -> np.ndarray:
    """A target matrix holding each combination the given number of times."""
    return np.array([list(c) for c, n in combinations.items() for _ in range(n)])


def test_lc_learns_one_class_per_seen_combination(tiny) -> None:
    X, Y = tiny
    model = LabelCombination(logistic()).fit(X, Y)
    seen = {tuple(row) for row in Y.tolist()}
    assert {tuple(row) for row in model.combinations_.tolist()} == seen
    assert {tuple(row) for row in model.predict(X).tolist()} <= seen


def test_lc_marginals_add_up_the_combination_probabilities(tiny) -> None:
    X, Y = tiny
    model = LabelCombination(logistic()).fit(X, Y)
    joint = model.estimator_.predict_proba(X[:5])
    marginals = model.predict_proba(X[:5])
    for target, k in enumerate((3, 2, 3)):
        for value in range(k):
            expected = joint[:, model.combinations_[:, target] == value].sum(axis=1)
            np.testing.assert_allclose(marginals[target][:, value], expected)


def test_nsr_replaces_a_rare_combination_by_its_nearest_frequent_ones() -> None:
    Y = counted({(0, 0): 5, (0, 1): 4, (1, 1): 3, (2, 2): 3, (1, 2): 1})
    model = NearestSetReplacement(tree(), pruning=1, n_replacements=2)
    model.fit(np.arange(len(Y), dtype=float)[:, None], Y)
    rows, targets, weights = model._training_set(Y)
    rare = len(Y) - 1
    # (1, 2) is one value away from (1, 1) [3 times] and (2, 2) [3 times], not (0, *).
    replaced = targets[rows == rare].tolist()
    assert sorted(replaced) == [[1, 1], [2, 2]]
    np.testing.assert_allclose(weights[rows == rare], [0.5, 0.5])
    assert [1, 2] not in model.combinations_.tolist()
    assert model.pruning_ == 1


def test_nsr_ranks_replacements_by_frequency() -> None:
    Y = counted({(0, 0): 5, (0, 1): 2, (1, 1): 4, (1, 0): 1})
    model = NearestSetReplacement(tree(), pruning=1, n_replacements=1).fit(np.zeros((12, 1)), Y)
    rows, targets, _ = model._training_set(Y)
    # (1, 0) is one value away from (0, 0) [5], (1, 1) [4]: the most frequent wins.
    assert targets[rows == 11].tolist() == [[0, 0]]


def test_ps_on_multi_class_targets_prefers_the_most_agreeing_combination() -> None:
    Y = counted({(0, 0, 0): 6, (0, 0, 1): 2, (2, 2, 0): 3, (1, 1, 1): 1})
    model = PrunedSets(tree(), pruning=1, n_replacements=3).fit(np.zeros((12, 1)), Y)
    rows, targets, weights = model._training_set(Y)
    # (1, 1, 1) agrees with (0, 0, 1) on one target; with the others on none.
    assert targets[rows == 11].tolist() == [[0, 0, 1]]
    np.testing.assert_allclose(weights[rows == 11], [1.0])


def test_ps_on_binary_targets_uses_labelset_subsets_largest_first() -> None:
    Y = counted({(1, 1, 0): 3, (1, 0, 0): 4, (0, 0, 0): 5, (0, 1, 1): 2, (1, 1, 1): 1})
    model = PrunedSets(tree(), pruning=1, n_replacements=2).fit(np.zeros((15, 1)), Y)
    rows, targets, weights = model._training_set(Y)
    # Subsets of {0, 1, 2} that are frequent: {0, 1}, {1, 2}, {0}, {} -> two largest,
    # equal size broken by frequency: {0, 1} (3 times) before {1, 2} (2 times).
    assert targets[rows == 14].tolist() == [[1, 1, 0], [0, 1, 1]]
    np.testing.assert_allclose(weights[rows == 14], [0.5, 0.5])


def test_pruning_backs_off_when_nothing_would_remain() -> None:
    Y = counted({(0, 0): 1, (1, 1): 1, (0, 1): 1})
    model = PrunedSets(tree(), pruning=2, n_replacements=1).fit(np.arange(3.0)[:, None], Y)
    assert model.pruning_ == 0
    assert len(model.combinations_) == 3


def test_sample_weights_of_replacements_reach_the_base() -> None:
    Y = counted({(0, 0): 5, (0, 1): 4, (1, 1): 3, (2, 2): 3, (1, 2): 1})
    X = np.arange(len(Y), dtype=float)[:, None]
    weighted = NearestSetReplacement(tree(), pruning=1, n_replacements=2).fit(X, Y)
    leaf_weights = weighted.estimator_.estimator_.tree_.weighted_n_node_samples[0]
    assert leaf_weights == pytest.approx(len(Y) - 1 + 0.5 + 0.5)


def test_rakeld_splits_the_targets_into_disjoint_subsets() -> None:
    rng = np.random.default_rng(0)
    X = rng.normal(size=(80, 3))
    Y = (X[:, [0, 0, 1, 1, 2]] + rng.normal(scale=0.5, size=(80, 5)) > 0).astype(int)
    model = RAkELd(logistic(), subset_size=2, random_state=0).fit(X, Y)
    assert sorted(len(part) for part in model.partition_) == [1, 2, 2]
    assert sorted(np.concatenate(model.partition_).tolist()) == [0, 1, 2, 3, 4]
    predicted = model.predict(X)
    for part, member in zip(model.partition_, model.estimators_, strict=True):
        seen = {tuple(row) for row in member.combinations_.tolist()}
        assert {tuple(row) for row in predicted[:, part].tolist()} <= seen


def test_rakeld_with_few_targets_is_lc(tiny) -> None:
    X, Y = tiny
    rakeld = RAkELd(logistic(), random_state=0).fit(X, Y)
    lc = LabelCombination(logistic()).fit(X, Y)
    assert [part.tolist() for part in rakeld.partition_] == [[0, 1, 2]]
    np.testing.assert_array_equal(rakeld.predict(X), lc.predict(X))


def coupled_targets(n_samples: int = 600, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Targets 0 and 1 are copies read from one noisy feature (their errors coincide);
    target 2 is read from a clean feature."""
    rng = np.random.default_rng(seed)
    shared = rng.integers(0, 2, n_samples)
    X = np.column_stack(
        [shared + rng.normal(scale=0.6, size=n_samples), rng.normal(size=n_samples)]
    )
    return X, np.column_stack([shared, shared, (X[:, 1] > 0).astype(int)])


def test_scc_merges_targets_whose_errors_coincide() -> None:
    X, Y = coupled_targets()
    model = SuperClassClassifier(logistic(), random_state=0).fit(X, Y)
    assert model.dependence_[0, 1] > 0
    assert model.dependence_[0, 2] < 0 and model.dependence_[1, 2] < 0
    assert sorted(part.tolist() for part in model.partition_) == [[0, 1], [2]]
    assert model.score(X, Y) > 0.8


def test_eps_members_see_a_sample_without_replacement(tiny) -> None:
    X, Y = tiny
    model = EnsemblePrunedSets(tree(), n_estimators=4, random_state=0).fit(X, Y)
    assert len(model.estimators_) == 4
    for rows in model.samples_:
        assert rows.shape == (round(0.63 * 120),)
        assert np.unique(rows).shape == rows.shape


def test_ensembles_vote_per_target_and_average_probabilities() -> None:
    X, Y = three_targets(seed=5)
    model = EnsemblePrunedSets(tree(), n_estimators=5, random_state=1).fit(X, Y)
    votes = np.stack([member.predict(X) for member in model.estimators_])
    predicted = model.predict(X)
    for target in range(3):
        counts = np.stack([(votes[:, :, target] == v).sum(axis=0) for v in range(3)], axis=1)
        chosen = counts[np.arange(len(X)), predicted[:, target]]
        assert np.all(chosen == counts.max(axis=1))
    mean = np.mean([member.predict_proba(X)[0] for member in model.estimators_], axis=0)
    np.testing.assert_allclose(model.predict_proba(X)[0], mean)
