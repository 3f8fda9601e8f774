"""Per-fold preprocessing: what is learnt comes from the training fold only."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.preprocessing import make_preprocessor

NAN = np.nan


def test_numeric_imputation_and_scaling_are_learnt_on_training_rows_only() -> None:
    train = np.array([[1.0], [3.0], [NAN], [5.0]])
    transformer, _ = make_preprocessor(
        n_features=1, nominal_features={}, impute=True, scaling="standard"
    )
    out = transformer.fit_transform(train)
    # the NaN becomes the mean 3; the scaler then sees 1, 3, 3, 5: std sqrt(2)
    np.testing.assert_allclose(out[:, 0], [-np.sqrt(2), 0.0, 0.0, np.sqrt(2)])
    test = transformer.transform(np.array([[NAN], [7.0]]))
    np.testing.assert_allclose(test[:, 0], [0.0, 4 / np.sqrt(2)])


def test_nominal_columns_are_one_hot_with_missing_and_unknown_as_zeros() -> None:
    train = np.array([[0.0, 10.0], [2.0, 20.0], [NAN, 30.0]])
    transformer, native = make_preprocessor(
        n_features=2, nominal_features={0: 3}, impute=True, scaling=None
    )
    transformer.fit(train)
    out = transformer.transform(np.array([[1.0, 5.0], [NAN, 6.0], [7.0, 8.0]]))
    # numeric column first, then the three indicator columns of labels 0, 1, 2
    np.testing.assert_array_equal(
        out, [[5.0, 0.0, 1.0, 0.0], [6.0, 0.0, 0.0, 0.0], [8.0, 0.0, 0.0, 0.0]]
    )
    assert native == []


def test_minmax_scaling_clips_to_the_training_range() -> None:
    transformer, _ = make_preprocessor(
        n_features=1, nominal_features={}, impute=True, scaling="minmax"
    )
    transformer.fit(np.array([[0.0], [10.0]]))
    np.testing.assert_allclose(
        transformer.transform(np.array([[5.0], [20.0], [-3.0]]))[:, 0], [0.5, 1.0, 0.0]
    )


def test_native_nominal_codes_pass_through_in_place_when_nothing_else_is_done() -> None:
    data = np.array([[0.5, 1.0, 2.0, 9.0], [NAN, NAN, 0.0, 8.0]])
    transformer, native = make_preprocessor(
        n_features=3, nominal_features={1: 2}, impute=False, scaling=None, native_nominal=True
    )
    out = transformer.fit_transform(data)
    assert native == [1]
    np.testing.assert_array_equal(out, data)


def test_native_nominal_codes_follow_scaled_numeric_columns() -> None:
    data = np.array([[0.0, 1.0, 2.0], [NAN, NAN, 4.0]])
    transformer, native = make_preprocessor(
        n_features=3, nominal_features={1: 2}, impute=True, scaling="minmax", native_nominal=True
    )
    out = transformer.fit_transform(data)
    assert native == [2]
    np.testing.assert_array_equal(out, [[0.0, 0.0, 1.0], [0.0, 1.0, NAN]])


def test_columns_after_the_features_pass_through_untouched() -> None:
    data = np.array([[1.0, 0.0, 1.0], [3.0, 1.0, 0.0]])
    transformer, _ = make_preprocessor(
        n_features=1, nominal_features={}, impute=True, scaling="standard"
    )
    out = transformer.fit_transform(data)
    np.testing.assert_array_equal(out[:, 1:], data[:, 1:])
    np.testing.assert_allclose(out[:, 0], [-1.0, 1.0])


@pytest.mark.parametrize(
    ("n_features", "nominal", "message"),
    [
        (0, {}, "n_features must be at least 1"),
        (2, {2: 3}, "nominal feature column 2 is outside the 2 feature columns"),
        (2, {1: 0}, "nominal feature column 1 declares 0 labels"),
    ],
)
def test_bad_column_descriptions_are_configuration_errors(
    n_features: int, nominal: dict[int, int], message: str
) -> None:
    with pytest.raises(ConfigurationError, match=message):
        make_preprocessor(
            n_features=n_features, nominal_features=nominal, impute=True, scaling=None
        )
