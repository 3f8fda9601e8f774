"""WEKA's IBk distance, ties, votes and range updates, by hand."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.weka import WekaIBk

NAN = np.nan


def test_numeric_range_normalisation_and_nominal_zero_one_differences() -> None:
    train = np.array([[0.0, 0.0], [10.0, 1.0]])
    model = WekaIBk(nominal_features={1: 2}).fit(train, [0, 1])
    squared = model._squared_distances(np.array([[5.0, 1.0]]), np.zeros(2), np.array([10.0, 1.0]))
    np.testing.assert_allclose(squared, [[0.25 + 1.0, 0.25 + 0.0]])
    assert model.predict(np.array([[5.0, 1.0]])).tolist() == [1]


def test_missing_values_differ_as_weka_says() -> None:
    train = np.array([[0.0, 0.0], [10.0, 1.0], [NAN, NAN]])
    model = WekaIBk(nominal_features={1: 2}).fit(train, [0, 1, 1])
    squared = model._squared_distances(
        np.array([[NAN, 0.0], [2.0, NAN]]), np.zeros(2), np.array([10.0, 1.0])
    )
    # row 0: numeric missing vs 0 (normalised 0) -> 1, vs 1 -> 1, both missing -> 1
    # row 1: 2 normalises to 0.2 -> vs missing max(0.2, 0.8) = 0.8; nominal missing -> 1
    np.testing.assert_allclose(
        squared, [[1.0 + 0.0, 1.0 + 1.0, 1.0 + 1.0], [0.04 + 1.0, 0.64 + 1.0, 0.64 + 1.0]]
    )


def test_every_instance_tied_with_the_kth_votes_and_each_class_starts_at_one_over_n() -> None:
    train = np.array([[0.0], [2.0], [2.0], [4.0]])
    model = WekaIBk(n_neighbors=1).fit(train, [0, 1, 1, 0])
    proba = model.predict_proba(np.array([[1.0]]))  # rows 0, 1 and 2 all at distance 0.25
    np.testing.assert_allclose(proba[0], np.array([1.25, 2.25]) / 3.5)


def test_inverse_and_similarity_weights_use_distance_over_root_of_attribute_count() -> None:
    train = np.array([[0.0, 0.0], [1.0, 1.0]])
    query = np.array([[0.25, 0.0]])
    near, far = np.sqrt(0.0625 / 2), np.sqrt((0.5625 + 1) / 2)
    for weighting, weight in (
        ("inverse", lambda d: 1 / (d + 0.001)),
        ("similarity", lambda d: 1 - d),
    ):
        proba = WekaIBk(2, weighting).fit(train, [0, 1]).predict_proba(query)[0]
        votes = np.array([0.5 + weight(near), 0.5 + weight(far)])
        np.testing.assert_allclose(proba, votes / votes.sum())


def test_ranges_widen_with_each_row_predicted_as_in_weka() -> None:
    train = np.array([[0.0, 1.0], [1.0, 0.2]])
    model = WekaIBk().fit(train, [0, 1])
    alone = np.array([[0.3, 0.5]])
    assert model.predict(alone).tolist() == [0]
    # a first row at 10 widens attribute 0 to [0, 10]: attribute 1 then decides
    assert model.predict(np.vstack([[10.0, 0.5], alone])).tolist()[1] == 1


def test_bad_parameters_are_refused() -> None:
    with pytest.raises(ValueError, match="n_neighbors must be a positive integer"):
        WekaIBk(n_neighbors=0).fit(np.zeros((2, 1)), [0, 1])
    with pytest.raises(ValueError, match="weighting must be"):
        WekaIBk(weighting="gauss").fit(np.zeros((2, 1)), [0, 1])


def test_blocks_of_rows_do_not_change_a_bit(monkeypatch: pytest.MonkeyPatch) -> None:
    """Rows predicted in blocks of one row, of a few, or all at once: the same votes."""
    from touchbench.benchmark.weka import ibk

    rng = np.random.default_rng(5)
    X = np.column_stack([rng.normal(size=300), rng.integers(0, 3, 300), rng.normal(size=300)])
    X[rng.random(X.shape) < 0.05] = NAN
    model = WekaIBk(7, "inverse", nominal_features={1: 3}).fit(X[:200], np.arange(200) % 3)
    test = X[200:].copy()
    test[:, [0, 2]] *= 1.5  # rows beyond the training ranges widen them as they come
    whole = model.predict_proba(test)
    for rows in (1, 3):
        monkeypatch.setattr(ibk, "BLOCK_BYTES", 8 * 200 * rows)
        np.testing.assert_array_equal(model.predict_proba(test), whole)
