"""The classifier catalogue: every benchmarkable configuration, as data.

>>> get_spec("j48").weka_command
'weka.classifiers.trees.J48 -C 0.25 -M 2'
>>> parse_weka_command("weka.classifiers.trees.J48 -U -M 2").id
'j48-unpruned'
>>> "zeror" in suite("fast")
True
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Mapping
from dataclasses import replace
from types import MappingProxyType

from sklearn.pipeline import Pipeline

from touchbench.benchmark.catalogue.entries import SPECS as _ENTRIES
from touchbench.benchmark.catalogue.pipeline import check_sequence_input, pipeline_for_spec
from touchbench.benchmark.catalogue.plugins import plugin_specs
from touchbench.benchmark.catalogue.spaces import SEARCH_SPACES
from touchbench.benchmark.catalogue.spec import ClassifierSpec
from touchbench.benchmark.catalogue.tuning import TUNED_SUFFIX, is_tuned_id, tuned_spec
from touchbench.benchmark.catalogue.weka_schemes import scheme_for, split_command
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.sequence import SequenceLayout

__all__ = [
    "CATALOGUE",
    "SEARCH_SPACES",
    "SUITES",
    "ClassifierSpec",
    "build_pipeline",
    "check_sequence_input",
    "get_spec",
    "parse_weka_command",
    "suite",
]

_OWN = tuple(
    replace(spec, search_space=SEARCH_SPACES[spec.id]) if spec.id in SEARCH_SPACES else spec
    for spec in _ENTRIES
)
SPECS: tuple[ClassifierSpec, ...] = _OWN + plugin_specs(spec.id for spec in _OWN)
CATALOGUE: Mapping[str, ClassifierSpec] = MappingProxyType({spec.id: spec for spec in SPECS})
SUITES: tuple[str, ...] = ("fast", "default", "all")


def get_spec(classifier_id: str) -> ClassifierSpec:
    """The catalogue entry called ``classifier_id``; ``ID+tuned`` is the tuned twin of ``ID``
    at the default budget.

    Raises
    ------
    ConfigurationError
        For an unknown id, naming the closest known one; a tuned twin of an entry without
        a search space.
    """
    if is_tuned_id(classifier_id):
        return tuned_spec(get_spec(classifier_id.removesuffix(TUNED_SUFFIX)))
    try:
        return CATALOGUE[classifier_id]
    except KeyError:
        raise ConfigurationError(unknown_classifier_message(classifier_id, CATALOGUE)) from None


def unknown_classifier_message(classifier_id: str, known: Mapping[str, object]) -> str:
    """``unknown classifier 'rff'; did you mean 'rf'?`` (or a pointer to the listing)."""
    close = difflib.get_close_matches(classifier_id.lower(), list(known), n=1, cutoff=0.5)
    hint = f"did you mean '{close[0]}'?" if close else "see the classifier listing"
    return f"unknown classifier '{classifier_id}'; {hint}"


def parse_weka_command(text: str) -> ClassifierSpec:
    """The catalogue configuration that runs a WEKA command line.

    Parameters
    ----------
    text : str
        A WEKA class and its options, as on WEKA's command line or in a results file's
        ``Key_Scheme`` and ``Key_Scheme_options`` (``"weka.classifiers.trees.J48 -C 0.1
        -M 5"``; the class may be given by its last part, ``"J48 -C 0.1"``).

    Returns
    -------
    ClassifierSpec
        The catalogue entry whose ``weka_command`` it is, or else a new spec on the same
        estimator with the options' parameters, its id derived from the entry's
        (``"j48-c0.1-m5"``), in no suite; pass it to the engine as an extra spec.

    Raises
    ------
    ConfigurationError
        A WEKA class touchbench does not reproduce, or an option it does not support
        (the message names it).
    """
    weka_class, tokens = split_command(text)
    scheme = scheme_for(weka_class)
    params = scheme.parse(tokens)
    base = CATALOGUE[scheme.base_id]
    merged = {**base.params, **params}
    command = scheme.command(merged)
    for spec in CATALOGUE.values():
        if spec.weka_command == command:
            return spec
    words = [t.lstrip("-").lower() for t in split_command(command)[1] if " " not in t]
    slug = "-".join(
        word + words[i + 1] if i + 1 < len(words) and not words[i + 1].isalpha() else word
        for i, word in enumerate(words)
        if not re.fullmatch(r"[0-9.e-]+", word) and word not in ("w", "a")
    )
    return replace(
        base,
        id=f"{base.id}-{slug}" if slug else base.id,
        weka_command=command,
        params=merged,
        suites=frozenset(),
        description=f"{base.description} ({scheme.weka_class} {command.split(' ', 1)[-1]})",
    )


def suite(name: str) -> list[str]:
    """The ids of a suite, in catalogue order; entries whose extra is not installed
    (:mod:`benchmark.extras`) are left out.

    Parameters
    ----------
    name : {"fast", "default", "all"}
        ``fast``: a handful of quick classifiers for smoke runs; ``default``: a broad set
        that runs a few thousand instances in minutes; ``all``: everything.
    """
    if name not in SUITES:
        raise ConfigurationError(f"unknown suite '{name}' (suites: {', '.join(SUITES)})")
    return [spec.id for spec in SPECS if (name == "all" or name in spec.suites) and spec.installed]


def build_pipeline(
    classifier_id: str | ClassifierSpec,
    *,
    nominal_features: Mapping[int, int] | None = None,
    n_features: int,
    random_state: int | None = 0,
    sequence: SequenceLayout | None = None,
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
    sequence : SequenceLayout or None
        Where a sequence data set's windows lie among the feature columns (sequence
        classifiers need it).

    Returns
    -------
    Pipeline
        Steps ``preprocess`` (imputation, one-hot encoding, scaling, learnt per fold) and
        ``classifier``; it accepts integer labels of which a fold may hold any subset.
    """
    spec = classifier_id if isinstance(classifier_id, ClassifierSpec) else get_spec(classifier_id)
    return pipeline_for_spec(
        spec,
        nominal_features=nominal_features,
        n_features=n_features,
        random_state=random_state,
        sequence=sequence,
    )
