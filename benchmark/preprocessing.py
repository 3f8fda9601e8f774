"""Per-fold preprocessing: imputation, one-hot encoding of nominal columns, scaling.

Every catalogue pipeline starts with the :class:`~sklearn.compose.ColumnTransformer` built
here, so that whatever it learns (means, modes, scales) comes from the training fold only.
Columns are addressed by index: the first ``n_features`` columns are the data set's
features (nominal ones hold label codes ``0..k-1``, NaN for missing); any further columns
(a multi-target meta-classifier's one-hot parent targets) pass through untouched.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Literal

import numpy as np
from sklearn.compose import ColumnTransformer
from sklearn.impute import SimpleImputer
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import MinMaxScaler, OneHotEncoder, StandardScaler

from touchbench.benchmark.errors import ConfigurationError

Scaling = Literal["standard", "minmax"]


def check_nominal_features(nominal_features: Mapping[int, int], n_features: int) -> None:
    """Raise :class:`ConfigurationError` unless every nominal column is a valid feature.

    Parameters
    ----------
    nominal_features : mapping of int to int
        Feature column index to its number of declared labels.
    n_features : int
        Number of feature columns.
    """
    if n_features < 1:
        raise ConfigurationError(f"n_features must be at least 1, got {n_features}")
    for column, n_labels in nominal_features.items():
        if not 0 <= column < n_features:
            raise ConfigurationError(
                f"nominal feature column {column} is outside the {n_features} feature columns"
            )
        if n_labels < 1:
            raise ConfigurationError(
                f"nominal feature column {column} declares {n_labels} labels; it needs at least 1"
            )


def make_preprocessor(
    *,
    n_features: int,
    nominal_features: Mapping[int, int],
    impute: bool,
    scaling: Scaling | None,
    native_nominal: bool = False,
) -> tuple[ColumnTransformer, list[int]]:
    """Build the column transformer that prepares one fold's features.

    Parameters
    ----------
    n_features : int
        Number of feature columns; columns from ``n_features`` on pass through.
    nominal_features : mapping of int to int
        Feature column index to its number of declared labels; other columns are numeric.
    impute : bool
        Replace missing numeric values by the training mean (WEKA's ReplaceMissingValues).
        ``False`` for models that handle NaN themselves.
    scaling : {"standard", "minmax"} or None
        Scale numeric columns to zero mean and unit variance, or to [0, 1] (clipped, as
        WEKA's normalised distances and non-negative count models need).
    native_nominal : bool
        Leave nominal codes as they are (for models with native categorical support)
        instead of one-hot encoding them.  Missing nominal values stay NaN.

    Returns
    -------
    transformer : ColumnTransformer
        Output columns: numeric features, then nominal features (one-hot blocks, or codes
        when ``native_nominal``), then the pass-through columns.  With ``native_nominal``
        and nothing to do to numeric columns, every column passes through in its own
        order (WEKA's learners scan attributes in file order, which breaks their ties).
    native_positions : list of int
        Output positions of the nominal code columns when ``native_nominal``, else empty.

    Notes
    -----
    One-hot encoding ignores unknown codes and encodes a missing nominal value as all
    zeros, so nominal columns never need imputation.
    """
    check_nominal_features(nominal_features, n_features)
    nominal = sorted(nominal_features)
    numeric = [c for c in range(n_features) if c not in nominal_features]
    transformers: list[tuple[str, object, np.ndarray]] = []
    if native_nominal and not impute and scaling is None:
        transformer = ColumnTransformer(
            [("features", "passthrough", _columns(range(n_features)))],
            remainder="passthrough",
            sparse_threshold=0.0,
            verbose_feature_names_out=False,
        )
        return transformer, nominal
    if numeric:
        transformers.append(("numeric", _numeric_steps(impute, scaling), _columns(numeric)))
    native_positions: list[int] = []
    if nominal:
        if native_nominal:
            transformers.append(("nominal", "passthrough", _columns(nominal)))
            native_positions = list(range(len(numeric), len(numeric) + len(nominal)))
        else:
            encoder = OneHotEncoder(
                categories=[np.arange(nominal_features[c], dtype=np.float64) for c in nominal],
                handle_unknown="ignore",
                sparse_output=False,
                dtype=np.float64,
            )
            transformers.append(("nominal", encoder, _columns(nominal)))
    transformer = ColumnTransformer(
        transformers, remainder="passthrough", sparse_threshold=0.0, verbose_feature_names_out=False
    )
    return transformer, native_positions


def _columns(indices: Iterable[int]) -> np.ndarray:
    """Column indices as an int64 array, shape (n_columns,).

    scikit-learn checks a list of indices item by item on every ``transform`` (its key
    type), an array by its dtype: on one row of a wide sequence data set the list costs
    more than a network's live prediction itself.
    """
    return np.fromiter(indices, dtype=np.int64)


def _numeric_steps(impute: bool, scaling: Scaling | None) -> Pipeline | str:
    steps: list[tuple[str, object]] = []
    if impute:
        steps.append(("impute", SimpleImputer(strategy="mean", keep_empty_features=True)))
    if scaling == "standard":
        steps.append(("scale", StandardScaler()))
    elif scaling == "minmax":
        steps.append(("scale", MinMaxScaler(clip=True)))
    return Pipeline(steps) if steps else "passthrough"
