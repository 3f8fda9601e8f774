"""MEKA's measures against values computed by hand."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.multitarget import (
    MULTILABEL_METRICS,
    MULTITARGET_METRICS,
    multitarget_scores,
)

# Four instances, two targets (3 and 2 classes).
Y_TRUE = np.array([[0, 1], [1, 0], [2, 1], [2, 0]])
Y_PRED = np.array([[0, 1], [1, 1], [1, 1], [2, 0]])


def scores(probas: list[np.ndarray] | None = None) -> dict:
    return multitarget_scores(
        Y_TRUE, Y_PRED, probas, n_classes=(3, 2), target_names=("gesture", "place")
    )


def test_hamming_score_and_exact_match_by_hand() -> None:
    result = scores()
    # Correct values: row 0 both, row 1 first only, row 2 second only, row 3 both: 6 of 8.
    assert result["hamming_score"] == pytest.approx(6 / 8)
    assert result["hamming_loss"] == pytest.approx(2 / 8)
    # Rows 0 and 3 are entirely right.
    assert result["exact_match"] == pytest.approx(2 / 4)
    assert result["zero_one_loss"] == pytest.approx(2 / 4)


def test_per_target_accuracy_and_weighted_f1_by_hand() -> None:
    per_target = scores()["per_target"]
    assert per_target["gesture"]["accuracy"] == pytest.approx(3 / 4)
    assert per_target["place"]["accuracy"] == pytest.approx(3 / 4)
    # gesture: class 0 F1 1, class 1 (P 1/2, R 1) F1 2/3, class 2 (P 1, R 1/2) F1 2/3;
    # weights 1/4, 1/4, 2/4.
    assert per_target["gesture"]["f1_weighted"] == pytest.approx(
        0.25 * 1 + 0.25 * 2 / 3 + 0.5 * 2 / 3
    )
    # place: class 0 (P 1, R 1/2) F1 2/3, class 1 (P 2/3, R 1) F1 4/5; weights 1/2, 1/2.
    assert per_target["place"]["f1_weighted"] == pytest.approx(0.5 * 2 / 3 + 0.5 * 4 / 5)


def test_multi_class_targets_get_no_multi_label_measures() -> None:
    result = scores()
    assert not set(MULTILABEL_METRICS) & set(result)
    assert "log_loss" not in result


def test_log_loss_by_hand() -> None:
    gesture = np.array([[0.8, 0.1, 0.1], [0.2, 0.5, 0.3], [0.1, 0.6, 0.3], [0.0, 0.0, 1.0]])
    place = np.array([[0.3, 0.7], [0.5, 0.5], [0.4, 0.6], [0.9, 0.1]])
    result = scores([gesture, place])
    gesture_loss = -np.mean(np.log([0.8, 0.5, 0.3, 1.0]))
    place_loss = -np.mean(np.log([0.7, 0.5, 0.6, 0.9]))
    assert result["per_target"]["gesture"]["log_loss"] == pytest.approx(gesture_loss)
    assert result["per_target"]["place"]["log_loss"] == pytest.approx(place_loss)
    assert result["log_loss"] == pytest.approx((gesture_loss + place_loss) / 2)


def test_multi_label_measures_by_hand() -> None:
    truth = np.array([[1, 0, 1], [0, 0, 0], [1, 1, 0]])
    predicted = np.array([[1, 1, 1], [0, 0, 0], [0, 1, 0]])
    result = multitarget_scores(
        truth, predicted, None, n_classes=(2, 2, 2), target_names=("a", "b", "c")
    )
    # True positives 3, false positives 1, false negatives 1: micro F1 = 6 / 8.
    assert result["f1_micro"] == pytest.approx(6 / 8)
    # Per label: a (P 1, R 1/2) 2/3, b (P 1/2, R 1) 2/3, c 1.
    assert result["f1_macro"] == pytest.approx((2 / 3 + 2 / 3 + 1) / 3)
    # Jaccard per row: 2/3, both empty = 1, 1/2.
    assert result["jaccard"] == pytest.approx((2 / 3 + 1 + 1 / 2) / 3)
    assert result["hamming_score"] == pytest.approx(7 / 9)
    assert result["exact_match"] == pytest.approx(1 / 3)


def test_the_metric_names_cover_what_is_returned() -> None:
    gesture = np.full((4, 3), 1 / 3)
    place = np.full((4, 2), 1 / 2)
    result = scores([gesture, place])
    assert set(result) - {"per_target"} <= set(MULTITARGET_METRICS)
    for name in ("hamming_score", "exact_match", "hamming_loss", "zero_one_loss"):
        assert name in MULTITARGET_METRICS


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"Y_pred": Y_PRED[:3]}, "X has 4 rows but Y has 3"),
        ({"target_names": ("gesture",)}, "1 target names for 2 targets"),
        ({"n_classes": (2, 2)}, "class code 2 but n_classes"),
        ({"probas": [np.full((4, 3), 1 / 3)]}, "1 probability matrices for 2 targets"),
        (
            {"probas": [np.full((4, 2), 0.5), np.full((4, 2), 0.5)]},
            r"target 'gesture' have shape \(4, 2\), expected \(4, 3\)",
        ),
    ],
)
def test_inconsistent_inputs_are_refused(kwargs: dict, message: str) -> None:
    arguments: dict[str, Any] = {
        "Y_true": Y_TRUE,
        "Y_pred": Y_PRED,
        "probas": None,
        "n_classes": (3, 2),
        "target_names": ("gesture", "place"),
    }
    arguments.update(kwargs)
    with pytest.raises(ConfigurationError, match=message):
        multitarget_scores(
            arguments["Y_true"],
            arguments["Y_pred"],
            arguments["probas"],
            n_classes=arguments["n_classes"],
            target_names=arguments["target_names"],
        )
