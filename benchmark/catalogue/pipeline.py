"""From a catalogue entry to a scikit-learn pipeline that preprocesses each fold itself."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from sklearn.base import BaseEstimator
from sklearn.pipeline import Pipeline

from touchbench.benchmark.catalogue.spec import ClassifierSpec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.preprocessing import make_preprocessor
from touchbench.benchmark.sequence import SequenceLayout

#: HistGradientBoosting's limit on the labels of a native categorical feature (estimators
#: that take ``nominal_features`` have none).
MAX_NATIVE_LABELS = 255


def pipeline_for_spec(
    spec: ClassifierSpec,
    *,
    nominal_features: Mapping[int, int] | None = None,
    n_features: int,
    random_state: int | None = 0,
    sequence: SequenceLayout | None = None,
) -> Pipeline:
    """The pipeline ``[("preprocess", ColumnTransformer), ("classifier", estimator)]``.

    Parameters
    ----------
    spec : ClassifierSpec
        The configuration to build.
    nominal_features : mapping of int to int, optional
        Feature column index to its number of declared labels (codes ``0..k-1``, NaN
        missing); every other column is numeric with NaN for missing.
    n_features : int
        Number of data-set feature columns; columns after them pass through unchanged.
    random_state : int or None
        Seed given to every ``random_state`` parameter of the estimator, nested ones
        included.
    sequence : SequenceLayout or None
        Where a sequence data set's windows lie among the feature columns; a sequence
        classifier gets their place after preprocessing as its ``sequence`` parameter.

    Returns
    -------
    Pipeline
        Unfitted; ``fit(X, y)`` takes X of shape (n_samples, n_features + n_extra) and
        integer labels y of shape (n_samples,).
    """
    check_sequence_input(spec, sequence)
    options = {
        "nominal_features": nominal_features,
        "n_features": n_features,
        "random_state": random_state,
        "sequence": sequence,
    }
    if spec.tuning is not None or spec.stacking is not None or spec.ensemble is not None:
        # the preprocessing lives inside each candidate (each member), learnt on its own
        return Pipeline([("preprocess", "passthrough"), ("classifier", _composite(spec, options))])
    nominal = dict(nominal_features or {})
    estimator = spec.make_estimator()
    takes_labels = "nominal_features" in estimator.get_params(deep=False)
    native = spec.handles_nominal and (
        takes_labels or all(k <= MAX_NATIVE_LABELS for k in nominal.values())
    )
    preprocessor, native_positions = make_preprocessor(
        n_features=n_features,
        nominal_features=nominal,
        impute=not spec.handles_missing,
        scaling=spec.scaling if spec.needs_scaling else None,
        native_nominal=native,
    )
    if native_positions and takes_labels:
        labels = [nominal[column] for column in sorted(nominal)]
        estimator.set_params(nominal_features=dict(zip(native_positions, labels, strict=True)))
    elif native_positions:
        estimator.set_params(categorical_features=native_positions)
    seeds = {
        name: random_state
        for name in estimator.get_params(deep=True)
        if name == "random_state" or name.endswith("__random_state")
    }
    estimator.set_params(**seeds)
    if spec.needs_sequence:
        assert sequence is not None
        # Numeric columns leave the preprocessor first, in their order (one-hot blocks
        # follow them): the block moves left by the nominal columns before it.
        moved = sum(1 for column in nominal if column < sequence.start)
        estimator.set_params(
            sequence=(sequence.start - moved, sequence.n_channels, sequence.length)
        )
    return Pipeline([("preprocess", preprocessor), ("classifier", estimator)])


def _composite(spec: ClassifierSpec, options: dict[str, Any]) -> BaseEstimator:
    """The tuned twin's search, the stack or the ensemble, over whole member pipelines."""
    from touchbench.benchmark.catalogue.stacking import SelectedStack
    from touchbench.benchmark.catalogue.tuning import CLASSIFIER_STEP, TunedClassifier, as_grid

    if spec.tuning is not None:
        base = spec.tuning.base
        assert base.search_space is not None
        budget = spec.tuning.budget_minutes
        return TunedClassifier(
            pipeline_for_spec(base, **options),
            space=as_grid(base.search_space, f"{CLASSIFIER_STEP}__"),
            budget=None if budget is None else budget * 60.0,
            random_state=options["random_state"],
        )
    members = [(m.id, pipeline_for_spec(m, **options)) for m in spec.members]
    if spec.ensemble is not None:
        ensemble = spec.factory(members=members, **spec.params)
        if "random_state" in ensemble.get_params(deep=False):  # a selection's inner folds
            ensemble.set_params(random_state=options["random_state"])
        return ensemble
    assert spec.stacking is not None
    return SelectedStack(members, spec.stacking.top_n, random_state=options["random_state"])


def check_sequence_input(spec: ClassifierSpec, sequence: SequenceLayout | None) -> None:
    """Refuse a sequence classifier on flat features, or on sequences too short for it.

    Raises
    ------
    ConfigurationError
        One line naming the classifier and what it needs.
    """
    if spec.min_sequence is None:
        return
    if sequence is None:
        raise ConfigurationError(
            f"classifier '{spec.id}' needs a sequence data set (attributes named "
            "CHANNEL[T], as the extractor `sequence`, or `mfcc` with its option frames=N, "
            "makes them); this data set has flat features"
        )
    if sequence.length < spec.min_sequence:
        raise ConfigurationError(
            f"classifier '{spec.id}' needs sequences of at least {spec.min_sequence} steps; "
            f"this data set's are {sequence.describe()}"
        )
