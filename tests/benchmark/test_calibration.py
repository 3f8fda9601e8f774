"""Reliability bins and the expected calibration error."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.evaluation.calibration import Reliability, merge, reliability


def _calibrated(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Labels and probabilities of a classifier whose top-label confidence is exactly how
    often the top label is right: its top label is right with probability p."""
    rng = np.random.default_rng(seed)
    n_classes = 4
    confidence = rng.uniform(0.25, 1.0, size=n)
    top = rng.integers(0, n_classes, size=n)
    proba = np.empty((n, n_classes))
    proba[:] = ((1 - confidence) / (n_classes - 1))[:, None]
    proba[np.arange(n), top] = confidence
    right = rng.random(n) < confidence
    wrong = (top + rng.integers(1, n_classes, size=n)) % n_classes
    return np.where(right, top, wrong), proba


def test_a_perfectly_calibrated_classifier_has_an_ece_near_zero() -> None:
    y, proba = _calibrated(200_000, seed=1)
    bins = reliability(y, proba)
    assert bins.ece() < 0.005
    shown = bins.count > 0
    np.testing.assert_allclose(bins.accuracy()[shown], bins.mean_confidence()[shown], atol=0.01)


def test_an_overconfident_classifier_has_the_gap_as_its_ece() -> None:
    # always 90 % sure, right half the time: ECE 0.4
    y = np.array([0, 1] * 500)
    proba = np.tile([0.9, 0.1], (1000, 1))
    bins = reliability(y, proba)
    assert bins.ece() == pytest.approx(0.4)
    assert bins.count[9] == 1000 and bins.count.sum() == 1000  # bins hold their lower edge


def test_folds_add_up_to_the_whole() -> None:
    y, proba = _calibrated(3000, seed=2)
    whole = reliability(y, proba)
    parts = merge(reliability(y[i::3], proba[i::3]) for i in range(3))
    assert parts is not None
    np.testing.assert_allclose(parts.count, whole.count)
    np.testing.assert_allclose(parts.confidence, whole.confidence)
    assert parts.ece() == pytest.approx(whole.ece())
    assert Reliability.from_json(whole.to_json()).ece() == whole.ece()
    assert merge([]) is None


def test_certain_predictions_fall_in_the_last_bin_and_rows_are_normalised() -> None:
    y = np.array([0, 1, 2])
    proba = np.array([[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    bins = reliability(y, proba, n_bins=5)
    assert bins.count.tolist() == [1, 0, 0, 0, 2]
    # the zero row has confidence 0 and top label 0, which is wrong for its class 2
    assert bins.correct.tolist() == [0, 0, 0, 0, 2]
    np.testing.assert_allclose(bins.edges, [0.0, 0.2, 0.4, 0.6, 0.8, 1.0])
