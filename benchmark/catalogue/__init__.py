"""The classifier catalogue: every benchmarkable configuration, as data.

>>> get_spec("rf").weka_name
'weka.classifiers.trees.RandomForest'
>>> "zeror" in suite("fast")
True
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from types import MappingProxyType

from sklearn.pipeline import Pipeline

from benchmark.catalogue.entries import SPECS
from benchmark.catalogue.pipeline import pipeline_for_spec
from benchmark.catalogue.spec import ClassifierSpec
from benchmark.errors import ConfigurationError

__all__ = ["CATALOGUE", "SUITES", "ClassifierSpec", "build_pipeline", "get_spec", "suite"]

CATALOGUE: Mapping[str, ClassifierSpec] = MappingProxyType({spec.id: spec for spec in SPECS})
SUITES: tuple[str, ...] = ("fast", "default", "all")


def get_spec(classifier_id: str) -> ClassifierSpec:
    """The catalogue entry called ``classifier_id``.

    Raises
    ------
    ConfigurationError
        For an unknown id, naming the closest known one.
    """
    try:
        return CATALOGUE[classifier_id]
    except KeyError:
        raise ConfigurationError(unknown_classifier_message(classifier_id, CATALOGUE)) from None


def unknown_classifier_message(classifier_id: str, known: Mapping[str, object]) -> str:
    """``unknown classifier 'rff'; did you mean 'rf'?`` (or a pointer to the listing)."""
    close = difflib.get_close_matches(classifier_id.lower(), list(known), n=1, cutoff=0.5)
    hint = f"did you mean '{close[0]}'?" if close else "see `touchbench classifiers`"
    return f"unknown classifier '{classifier_id}'; {hint}"


def suite(name: str) -> list[str]:
    """The ids of a suite, in catalogue order.

    Parameters
    ----------
    name : {"fast", "default", "all"}
        ``fast``: a handful of quick classifiers for smoke runs; ``default``: a broad set
        that runs a few thousand instances in minutes; ``all``: everything.
    """
    if name not in SUITES:
        raise ConfigurationError(f"unknown suite '{name}' (suites: {', '.join(SUITES)})")
    return [spec.id for spec in SPECS if name == "all" or name in spec.suites]


def build_pipeline(
    classifier_id: str | ClassifierSpec,
    *,
    nominal_features: Mapping[int, int] | None = None,
    n_features: int,
    random_state: int | None = 0,
) -> Pipeline:
    """The preprocessing-plus-classifier pipeline of a catalogue entry.

    Parameters
    ----------
    classifier_id : str or ClassifierSpec
        A catalogue id, or a spec not in the catalogue.
    nominal_features : mapping of int to int, optional
        Feature column index to its number of declared labels (codes ``0..k-1``, NaN
        missing); all other columns are numeric, NaN for missing.
    n_features : int
        Number of feature columns; any columns after them (a meta-classifier's extra
        inputs) pass through unchanged.
    random_state : int or None
        Seed for every ``random_state`` of the estimator.

    Returns
    -------
    Pipeline
        Steps ``preprocess`` (imputation, one-hot encoding, scaling, learnt per fold) and
        ``classifier``; it accepts integer labels of which a fold may hold any subset.
    """
    spec = classifier_id if isinstance(classifier_id, ClassifierSpec) else get_spec(classifier_id)
    return pipeline_for_spec(
        spec, nominal_features=nominal_features, n_features=n_features, random_state=random_state
    )
