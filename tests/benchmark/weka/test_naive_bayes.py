"""WEKA's NaiveBayes computed by hand on tiny data, and MDL discretisation."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.weka import WekaNaiveBayes
from touchbench.benchmark.weka.discretize import mdl_cut_points

NAN = np.nan


def test_nominal_attributes_are_laplace_frequencies_and_missing_values_are_skipped() -> None:
    # column 0 nominal with 2 labels; class 0 sees labels 0, 0, 1 (and one missing)
    X = np.array([[0.0], [0.0], [1.0], [NAN], [1.0]])
    y = np.array([0, 0, 0, 0, 1])
    model = WekaNaiveBayes(nominal_features={0: 2}).fit(X, y)
    prior = np.array([5.0, 2.0]) / 7.0  # counts 4 and 1, each plus 1
    np.testing.assert_allclose(np.exp(model.log_prior_), prior)
    # class 0: labels (2+1, 1+1) / 5; class 1: (0+1, 1+1) / 3
    np.testing.assert_allclose(np.exp(model.log_tables_[0]), [[3 / 5, 2 / 5], [1 / 3, 2 / 3]])
    proba = model.predict_proba(np.array([[0.0], [NAN]]))
    joint = prior * np.array([3 / 5, 1 / 3])
    np.testing.assert_allclose(proba[0], joint / joint.sum())
    np.testing.assert_allclose(proba[1], prior)  # a missing value leaves the prior


def test_numeric_attributes_use_wekas_precision_rounding_and_interval_probability() -> None:
    X = np.array([[1.0], [1.5], [3.0], [5.0]])
    y = np.array([0, 0, 0, 1])
    model = WekaNaiveBayes().fit(X, y)
    assert model.precision_[0] == pytest.approx(4.0 / 3.0)  # (5 - 1) / (4 distinct - 1)
    rounded = np.rint(np.array([1.0, 1.5, 3.0]) / (4 / 3)) * (4 / 3)
    assert model.mean_[0, 0] == pytest.approx(rounded.mean())
    assert model.std_[0, 0] == pytest.approx(rounded.std())  # population deviation
    # a single value per class: the deviation falls back to precision / 6
    assert model.std_[1, 0] == pytest.approx((4 / 3) / 6)


def test_constant_numeric_column_has_default_precision() -> None:
    model = WekaNaiveBayes().fit(np.array([[2.0], [2.0], [NAN]]), np.array([0, 1, 1]))
    assert model.precision_[0] == 0.01


def test_kernel_and_discretised_variants_fit_and_predict() -> None:
    rng = np.random.default_rng(0)
    y = np.repeat([0, 1], 40)
    X = np.column_stack([rng.normal(size=80) + 3 * y, rng.integers(0, 3, size=80)])
    for numeric in ("kernel", "discretize"):
        model = WekaNaiveBayes(numeric=numeric, nominal_features={1: 3}).fit(X, y)
        assert model.score(X, y) > 0.85
        np.testing.assert_allclose(model.predict_proba(X).sum(axis=1), 1.0)
    assert WekaNaiveBayes(numeric="discretize").fit(X, y).cut_points_[0].size >= 1


def test_mdl_cuts_separable_classes_once_and_noise_never() -> None:
    values = np.array([1.0, 2.0, 3.0, 10.0, 11.0, 12.0])
    np.testing.assert_array_equal(mdl_cut_points(values, np.array([0, 0, 0, 1, 1, 1]), 2), [6.5])
    rng = np.random.default_rng(3)
    noise = mdl_cut_points(rng.normal(size=60), rng.integers(0, 2, size=60), 2)
    assert noise.size == 0


def test_bad_parameters_and_codes_are_refused() -> None:
    with pytest.raises(ValueError, match="numeric must be"):
        WekaNaiveBayes(numeric="poisson").fit(np.zeros((2, 1)), [0, 1])
    with pytest.raises(ValueError, match=r"nominal feature column 0 holds 2.0; .* 0..1"):
        WekaNaiveBayes(nominal_features={0: 2}).fit(np.array([[0.0], [2.0]]), [0, 1])
    with pytest.raises(ValueError, match="outside the 1 columns"):
        WekaNaiveBayes(nominal_features={3: 2}).fit(np.zeros((2, 1)), [0, 1])
