"""Per-fold metrics against hand-computed values and scikit-learn's definitions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from sklearn import metrics as skm

from touchbench.benchmark.evaluation.metrics import (
    LOWER_IS_BETTER,
    MULTICLASS_METRICS,
    confusion_matrix,
    expand_proba,
    multiclass_scores,
)

# 10 instances, 3 classes.  Confusion (rows true, columns predicted):
#   [[3, 1, 0],
#    [1, 2, 1],
#    [0, 0, 2]]
Y_TRUE = np.array([0, 0, 0, 0, 1, 1, 1, 1, 2, 2])
Y_PRED = np.array([0, 0, 0, 1, 0, 1, 1, 2, 2, 2])


def test_confusion_matrix_counts_true_rows_and_predicted_columns() -> None:
    expected = [[3, 1, 0], [1, 2, 1], [0, 0, 2]]
    assert confusion_matrix(Y_TRUE, Y_PRED, n_classes=3).tolist() == expected
    assert confusion_matrix(Y_TRUE, Y_PRED, n_classes=4).tolist() == [
        [3, 1, 0, 0],
        [1, 2, 1, 0],
        [0, 0, 2, 0],
        [0, 0, 0, 0],
    ]


def test_scores_match_hand_computed_values() -> None:
    scores, confusion = multiclass_scores(Y_TRUE, Y_PRED, None, n_classes=3)
    assert confusion == [[3, 1, 0], [1, 2, 1], [0, 0, 2]]
    # precision 3/4, 2/3, 2/3; recall 3/4, 2/4, 2/2; support 4, 4, 2
    precision = np.array([3 / 4, 2 / 3, 2 / 3])
    recall = np.array([3 / 4, 1 / 2, 1.0])
    f1 = 2 * precision * recall / (precision + recall)
    weights = np.array([0.4, 0.4, 0.2])
    assert scores["accuracy"] == pytest.approx(0.7)
    assert scores["balanced_accuracy"] == pytest.approx((0.75 + 0.5 + 1.0) / 3)
    assert scores["precision_weighted"] == pytest.approx(weights @ precision)
    assert scores["recall_weighted"] == pytest.approx(0.7)
    assert scores["f1_weighted"] == pytest.approx(weights @ f1)
    assert scores["f1_macro"] == pytest.approx(f1.mean())
    # kappa: p_o = 0.7, p_e = (4*4 + 4*3 + 2*3) / 100 = 0.34
    assert scores["kappa"] == pytest.approx((0.7 - 0.34) / (1 - 0.34))
    # mcc: (c*s - t.p) / sqrt((s^2 - p.p)(s^2 - t.t)) with c=7, s=10, t=(4,4,2), p=(4,3,3)
    assert scores["mcc"] == pytest.approx((70 - 34) / math.sqrt((100 - 34) * (100 - 36)))
    assert math.isnan(scores["roc_auc"]) and math.isnan(scores["log_loss"])
    # WEKA's errors on one-hot predictions: 3 wrong instances, each |diff| sums to 2
    assert scores["mean_absolute_error"] == pytest.approx(6 / 30)
    assert scores["root_mean_squared_error"] == pytest.approx(math.sqrt(6 / 30))
    assert set(MULTICLASS_METRICS) <= set(scores)


def test_probability_scores_match_scikit_learn() -> None:
    rng = np.random.default_rng(3)
    proba = rng.dirichlet(np.ones(3), size=10)
    scores, _ = multiclass_scores(Y_TRUE, Y_PRED, proba, n_classes=3)
    assert scores["roc_auc"] == pytest.approx(
        skm.roc_auc_score(Y_TRUE, proba, average="weighted", multi_class="ovr")
    )
    assert scores["log_loss"] == pytest.approx(skm.log_loss(Y_TRUE, proba, labels=[0, 1, 2]))


def test_roc_auc_by_hand_with_ties() -> None:
    y = np.array([0, 0, 1, 1])
    proba = np.array([[0.9, 0.1], [0.5, 0.5], [0.5, 0.5], [0.2, 0.8]])
    scores, _ = multiclass_scores(y, proba.argmax(axis=1), proba, n_classes=2)
    # class 1 scores: positives 0.5, 0.8 vs negatives 0.1, 0.5 -> pairs won 1 + 0.5 + 1 + 1
    assert scores["roc_auc"] == pytest.approx(3.5 / 4)


def test_a_class_absent_from_the_test_fold_breaks_nothing() -> None:
    y_true = np.array([0, 0, 2, 2])
    y_pred = np.array([0, 1, 2, 2])
    proba = np.array([[0.8, 0.2, 0.0], [0.3, 0.6, 0.1], [0.1, 0.1, 0.8], [0.0, 0.3, 0.7]])
    scores, confusion = multiclass_scores(y_true, y_pred, proba, n_classes=3)
    assert confusion == [[1, 1, 0], [0, 0, 0], [0, 0, 2]]
    for name in ("accuracy", "f1_weighted", "f1_macro", "balanced_accuracy", "kappa", "mcc"):
        expected = {
            "accuracy": skm.accuracy_score(y_true, y_pred),
            "f1_weighted": skm.f1_score(y_true, y_pred, average="weighted", zero_division=0),
            "f1_macro": skm.f1_score(y_true, y_pred, average="macro", zero_division=0),
            "balanced_accuracy": 0.75,
            "kappa": skm.cohen_kappa_score(y_true, y_pred),
            "mcc": skm.matthews_corrcoef(y_true, y_pred),
        }[name]
        assert scores[name] == pytest.approx(expected), name
    assert scores["log_loss"] == pytest.approx(
        -(np.log(0.8) + np.log(0.3) + np.log(0.8) + np.log(0.7)) / 4
    )
    assert scores["roc_auc"] == pytest.approx(1.0)


def test_roc_auc_is_nan_with_a_single_class_present() -> None:
    scores, _ = multiclass_scores(
        np.zeros(3, int), np.zeros(3, int), np.eye(2)[[0, 0, 0]], n_classes=2
    )
    assert math.isnan(scores["roc_auc"])
    assert math.isnan(scores["kappa"]) and scores["mcc"] == 0.0
    assert scores["accuracy"] == 1.0


def test_expand_proba_places_columns_of_the_classes_seen() -> None:
    proba = np.array([[0.25, 0.75], [1.0, 0.0]])
    full = expand_proba(proba, np.array([0, 3]), n_classes=4)
    np.testing.assert_array_equal(full, [[0.25, 0, 0, 0.75], [1.0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"shape \(2, 2\) for 3 classes"):
        expand_proba(proba, np.array([0, 1, 2]), n_classes=4)


def test_labels_outside_the_declared_range_are_rejected() -> None:
    with pytest.raises(ValueError, match=r"labels must lie in 0\.\.2"):
        confusion_matrix(np.array([0, 3]), np.array([0, 1]), n_classes=3)


def test_lower_is_better_covers_losses_and_costs() -> None:
    assert {"log_loss", "fit_time", "predict_time", "model_size", "hamming_loss"} <= LOWER_IS_BETTER
    assert not {"accuracy", "f1_weighted", "roc_auc", "kappa"} & LOWER_IS_BETTER
