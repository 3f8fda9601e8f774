"""Multi-target and multi-label classification: MEKA's meta-classifiers as scikit-learn
estimators, MEKA's measures, and the ``META:BASE`` configuration registry.

Every estimator takes ``X`` of shape (n_samples, n_features), float64 with NaN for
missing values, and ``Y`` of shape (n_samples, n_targets) of integer class codes;
``predict`` returns (n_samples, n_targets) int codes and ``predict_proba`` a list of
one (n_samples, n_classes[t]) matrix per target.
"""

from __future__ import annotations

from touchbench.benchmark.evaluation.multitarget import (
    LOSS_METRICS,
    MULTILABEL_METRICS,
    MULTITARGET_METRICS,
    multitarget_scores,
)
from touchbench.benchmark.multitarget._base import MultiTargetClassifier
from touchbench.benchmark.multitarget._target_classifier import TargetClassifier
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
from touchbench.benchmark.multitarget.registry import (
    DEFAULT_BASES,
    META_METHODS,
    MetaSpec,
    build_multitarget,
    check_targets,
    multitarget_configurations,
    parse_config,
)
from touchbench.benchmark.multitarget.relevance import ClassRelevance
from touchbench.benchmark.multitarget.superclass import SuperClassClassifier
from touchbench.benchmark.targets import TargetError

__all__ = [
    "DEFAULT_BASES",
    "LOSS_METRICS",
    "META_METHODS",
    "MULTILABEL_METRICS",
    "MULTITARGET_METRICS",
    "BayesianClassifierChain",
    "ClassRelevance",
    "ClassifierChain",
    "EnsembleClassifierChains",
    "EnsemblePrunedSets",
    "LabelCombination",
    "MetaSpec",
    "MultiLabelAdapter",
    "MultiTargetClassifier",
    "NearestSetReplacement",
    "ProbabilisticClassifierChain",
    "PrunedSets",
    "RAkELd",
    "SuperClassClassifier",
    "TargetClassifier",
    "TargetError",
    "build_multitarget",
    "check_targets",
    "multitarget_configurations",
    "multitarget_scores",
    "parse_config",
]
