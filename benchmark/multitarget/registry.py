"""The ``META:BASE`` configuration registry: meta-classifiers over catalogue bases, as data.

A configuration id is ``META:BASE`` (``bcc:rf``, ``cc:svm-rbf``, ``lc:xgb``), META a key
of :data:`META_METHODS` and BASE a classifier id of :mod:`benchmark.catalogue`.  The
multi-label methods of scikit-multilearn that have no base classifier (``mlknn``,
``brknn``, ``mlaram``) are ids on their own.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from touchbench.benchmark.catalogue import ClassifierSpec, build_pipeline, get_spec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.multitarget._base import MultiTargetClassifier
from touchbench.benchmark.multitarget.bayesian_chain import BayesianClassifierChain
from touchbench.benchmark.multitarget.chains import ClassifierChain, ProbabilisticClassifierChain
from touchbench.benchmark.multitarget.combination import (
    LabelCombination,
    NearestSetReplacement,
    PrunedSets,
)
from touchbench.benchmark.multitarget.ensembles import EnsembleClassifierChains, EnsemblePrunedSets
from touchbench.benchmark.multitarget.multilabel import MultiLabelAdapter
from touchbench.benchmark.multitarget.rakeld import RAkELd
from touchbench.benchmark.multitarget.relevance import ClassRelevance
from touchbench.benchmark.multitarget.superclass import SuperClassClassifier
from touchbench.benchmark.sequence import SequenceLayout
from touchbench.benchmark.targets import all_binary

#: Factory signature: (base estimator or preprocessor, random_state, n_classes) -> estimator.
Factory = Callable[[Any, int | None, Sequence[int] | None], MultiTargetClassifier]

#: Catalogue ids combined with every meta-classifier by default.
DEFAULT_BASES: tuple[str, ...] = (
    "rf",
    "j48",
    "nb",
    "ibk",
    "logistic",
    "svm-rbf",
    "xgb",
    "extra-trees",
)
#: The catalogue classifier whose preprocessing steps feed the methods without a base.
PREPROCESSING_SOURCE = "knn5"  # imputation, one-hot and [0, 1] scaling


@dataclass(frozen=True)
class MetaSpec:
    """One meta-classifier of the registry.

    Parameters
    ----------
    id : str
        The META part of configuration ids.
    name : str
        Human-readable name.
    follows : str
        The MEKA (or scikit-multilearn) class it follows.
    factory : Factory
        Builds the estimator from a base (or, without a base, a preprocessor), a seed and
        the classes per target.
    needs_base : bool
        Whether ids take a ``:BASE`` part.
    binary_only : bool
        Only for binary targets (multi-label data).
    """

    id: str
    name: str
    follows: str
    factory: Factory
    needs_base: bool = True
    binary_only: bool = False


def _multilabel(method: str, *, needs_base: bool) -> Factory:
    def build(
        part: Any, random_state: int | None, n_classes: Sequence[int] | None
    ) -> MultiTargetClassifier:
        if needs_base:
            return MultiLabelAdapter(method, part, n_classes=n_classes, random_state=random_state)
        return MultiLabelAdapter(
            method, preprocessor=part, n_classes=n_classes, random_state=random_state
        )

    return build


_SPECS = (
    MetaSpec(
        "cr",
        "Class relevance",
        "meka.classifiers.multitarget.CR",
        lambda base, seed, n_classes: ClassRelevance(base, n_classes=n_classes),
    ),
    MetaSpec(
        "cc",
        "Classifier chain",
        "meka.classifiers.multitarget.CC",
        lambda base, seed, n_classes: ClassifierChain(base, n_classes=n_classes, random_state=seed),
    ),
    MetaSpec(
        "bcc",
        "Bayesian classifier chain",
        "meka.classifiers.multilabel.BCC",
        lambda base, seed, n_classes: BayesianClassifierChain(
            base, n_classes=n_classes, random_state=seed
        ),
    ),
    MetaSpec(
        "pcc",
        "Probabilistic classifier chain",
        "meka.classifiers.multilabel.PCC",
        lambda base, seed, n_classes: ProbabilisticClassifierChain(
            base, n_classes=n_classes, random_state=seed
        ),
    ),
    MetaSpec(
        "lc",
        "Label combination",
        "meka.classifiers.multilabel.LC",
        lambda base, seed, n_classes: LabelCombination(base, n_classes=n_classes),
    ),
    MetaSpec(
        "ps",
        "Pruned sets",
        "meka.classifiers.multilabel.PS",
        lambda base, seed, n_classes: PrunedSets(base, n_classes=n_classes),
    ),
    MetaSpec(
        "eps",
        "Ensemble of pruned sets",
        "meka.classifiers.multilabel.meta.EnsembleML",
        lambda base, seed, n_classes: EnsemblePrunedSets(
            base, n_classes=n_classes, random_state=seed
        ),
    ),
    MetaSpec(
        "ecc",
        "Ensemble of classifier chains",
        "meka.classifiers.multitarget.meta.BaggingMT",
        lambda base, seed, n_classes: EnsembleClassifierChains(
            base, n_classes=n_classes, random_state=seed
        ),
    ),
    MetaSpec(
        "rakeld",
        "Random disjoint k-labelsets",
        "meka.classifiers.multitarget.RAkELd",
        lambda base, seed, n_classes: RAkELd(base, n_classes=n_classes, random_state=seed),
    ),
    MetaSpec(
        "nsr",
        "Nearest set replacement",
        "meka.classifiers.multitarget.NSR",
        lambda base, seed, n_classes: NearestSetReplacement(base, n_classes=n_classes),
    ),
    MetaSpec(
        "scc",
        "Super-class classifier",
        "meka.classifiers.multitarget.SCC",
        lambda base, seed, n_classes: SuperClassClassifier(
            base, n_classes=n_classes, random_state=seed
        ),
    ),
    MetaSpec(
        "ml-br",
        "Binary relevance (scikit-multilearn)",
        "skmultilearn.problem_transform.BinaryRelevance",
        _multilabel("br", needs_base=True),
        binary_only=True,
    ),
    MetaSpec(
        "ml-cc",
        "Classifier chain (scikit-multilearn)",
        "skmultilearn.problem_transform.ClassifierChain",
        _multilabel("cc", needs_base=True),
        binary_only=True,
    ),
    MetaSpec(
        "ml-lp",
        "Label powerset (scikit-multilearn)",
        "skmultilearn.problem_transform.LabelPowerset",
        _multilabel("lp", needs_base=True),
        binary_only=True,
    ),
    MetaSpec(
        "ml-rakeld",
        "RAkEL disjoint (scikit-multilearn)",
        "skmultilearn.ensemble.LabelSpacePartitioningClassifier",
        _multilabel("rakeld", needs_base=True),
        binary_only=True,
    ),
    MetaSpec(
        "ml-rakelo",
        "RAkEL overlapping (scikit-multilearn)",
        "skmultilearn.ensemble.MajorityVotingClassifier",
        _multilabel("rakelo", needs_base=True),
        binary_only=True,
    ),
    MetaSpec(
        "mlknn",
        "ML-kNN (scikit-multilearn)",
        "skmultilearn.adapt.MLkNN",
        _multilabel("mlknn", needs_base=False),
        needs_base=False,
        binary_only=True,
    ),
    MetaSpec(
        "brknn",
        "BRkNN-a (scikit-multilearn)",
        "skmultilearn.adapt.BRkNNaClassifier",
        _multilabel("brknn", needs_base=False),
        needs_base=False,
        binary_only=True,
    ),
    MetaSpec(
        "mlaram",
        "ML-ARAM (scikit-multilearn)",
        "skmultilearn.adapt.MLARAM",
        _multilabel("mlaram", needs_base=False),
        needs_base=False,
        binary_only=True,
    ),
)

#: Every meta-classifier by id; ``binary_only`` flags the scikit-multilearn ones.
META_METHODS: Mapping[str, MetaSpec] = MappingProxyType({spec.id: spec for spec in _SPECS})


def multitarget_configurations(
    *, bases: Sequence[str] | None = None, include_multilabel: bool = False
) -> list[str]:
    """Configuration ids: every multi-target meta-classifier over every base.

    Parameters
    ----------
    bases : sequence of str, optional
        Catalogue ids; default :data:`DEFAULT_BASES`.
    include_multilabel : bool, default False
        Also list the binary-only (scikit-multilearn) methods.

    Returns
    -------
    list of str
        ``META:BASE`` ids, meta-classifiers in registry order, then bases in the given
        order; base-less ids alone.
    """
    chosen = DEFAULT_BASES if bases is None else tuple(bases)
    configurations: list[str] = []
    for spec in META_METHODS.values():
        if spec.binary_only and not include_multilabel:
            continue
        if spec.needs_base:
            configurations.extend(f"{spec.id}:{base}" for base in chosen)
        else:
            configurations.append(spec.id)
    return configurations


def parse_config(config_id: str) -> tuple[str, str]:
    """Split and check a configuration id.

    Parameters
    ----------
    config_id : str
        ``META:BASE`` or a base-less META.

    Returns
    -------
    (meta, base) : tuple of str
        ``base`` is ``""`` for methods without a base.

    Raises
    ------
    ConfigurationError
        Unknown META or BASE (with the closest known id), a missing or superfluous BASE.
    """
    meta, colon, base = config_id.strip().partition(":")
    meta, base = meta.strip().lower(), base.strip()
    if meta not in META_METHODS:
        raise ConfigurationError(
            f"unknown multi-target method '{meta}' in '{config_id}'"
            + _suggestion(meta, META_METHODS)
            + f" (known: {', '.join(META_METHODS)})"
        )
    spec = META_METHODS[meta]
    if not spec.needs_base:
        if colon:
            raise ConfigurationError(
                f"'{meta}' takes no base classifier; use '{meta}' instead of '{config_id}'"
            )
        return meta, ""
    if not base:
        raise ConfigurationError(
            f"'{config_id}' lacks a base classifier: write {meta}:BASE, e.g. {meta}:rf"
        )
    get_spec(base)
    return meta, base


def build_multitarget(
    config_id: str,
    *,
    nominal_features: Mapping[int, int] | None = None,
    n_features: int,
    random_state: int | None = 0,
    n_classes: Sequence[int] | None = None,
    sequence: SequenceLayout | None = None,
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
) -> MultiTargetClassifier:
    """A fresh, unfitted estimator for a configuration id.

    Parameters
    ----------
    config_id : str
        ``META:BASE`` (or a base-less META).
    nominal_features : mapping of int to int, optional
        Feature column -> number of labels, for the catalogue's one-hot encoding.
    n_features : int
        Number of feature columns of ``X`` (chains append target columns after them).
    random_state : int or None, default 0
        Seed of the base classifier and of the meta-classifier's own randomness.
    n_classes : sequence of int, optional
        Declared classes per target, so that probabilities cover classes a training
        fold lacks; default: inferred from each training ``Y``.
    sequence : SequenceLayout or None
        Where a sequence data set's windows lie among the feature columns, for a
        sequence classifier as the base.
    extra_specs : mapping of str to ClassifierSpec, optional
        Base specs outside the catalogue (a run's tuned twins at its budget), by id.

    Returns
    -------
    MultiTargetClassifier

    Raises
    ------
    ConfigurationError
        See :func:`parse_config`.
    """
    meta, base = parse_config(config_id)
    spec = META_METHODS[meta]
    nominal = {} if nominal_features is None else dict(nominal_features)
    pipeline = build_pipeline(
        (extra_specs or {}).get(base) or base or PREPROCESSING_SOURCE,
        nominal_features=nominal,
        n_features=n_features,
        random_state=random_state,
        sequence=sequence if base else None,
    )
    part = pipeline if spec.needs_base else pipeline[:-1]
    return spec.factory(part, random_state, None if n_classes is None else tuple(n_classes))


def check_targets(
    config_id: str, n_classes: Sequence[int], target_names: Sequence[str] | None = None
) -> None:
    """Check that a configuration can learn targets with these class counts.

    Parameters
    ----------
    config_id : str
    n_classes : sequence of int
        Declared classes per target.
    target_names : sequence of str, optional
        For the message.

    Raises
    ------
    ConfigurationError
        Fewer than two targets, or a binary-only method and a target with more than two
        classes.
    """
    meta, _ = parse_config(config_id)
    names = (
        list(target_names) if target_names is not None else [str(t) for t in range(len(n_classes))]
    )
    if len(n_classes) < 2:
        raise ConfigurationError(
            f"'{config_id}' is a multi-target method but the data set has "
            f"{len(n_classes)} target ({', '.join(names)}); choose a multi-class "
            "classifier or a data set with several targets (MEKA header -C N)"
        )
    if META_METHODS[meta].binary_only and not all_binary(n_classes):
        wide = [f"{name} ({k} classes)" for name, k in zip(names, n_classes, strict=True) if k > 2]
        raise ConfigurationError(
            f"'{config_id}' is a multi-label method for binary targets only, but "
            f"{', '.join(wide)} {'is' if len(wide) == 1 else 'are'} not binary"
        )


def _suggestion(name: str, known: Mapping[str, Any]) -> str:
    close = difflib.get_close_matches(name, list(known), n=1)
    return f"; did you mean '{close[0]}'?" if close else ""
