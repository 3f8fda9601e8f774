"""The catalogue's entries: one :class:`ClassifierSpec` per configuration.

Plain scikit-learn classes are their own factories; composite models (wrappers and
ensembles around a base estimator) are built by the module-level functions below, which
take the outer model's parameters so that ``params`` shows them.  Nested ``random_state``
parameters are set by :func:`benchmark.catalogue.build_pipeline`, not here.

An entry carries a WEKA command line only where it computes what that command computes
(:mod:`benchmark.weka` reimplements WEKA's J48, PART, NaiveBayes, IBk and ZeroR on
nominal codes); ``perf/weka_agreement.py`` measures each against WEKA itself.
"""

from __future__ import annotations

from typing import Any

from sklearn.base import BaseEstimator
from sklearn.calibration import CalibratedClassifierCV
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis, QuadraticDiscriminantAnalysis
from sklearn.ensemble import (
    AdaBoostClassifier,
    BaggingClassifier,
    ExtraTreesClassifier,
    GradientBoostingClassifier,
    HistGradientBoostingClassifier,
    RandomForestClassifier,
)
from sklearn.gaussian_process import GaussianProcessClassifier
from sklearn.gaussian_process.kernels import RBF, ConstantKernel
from sklearn.linear_model import (
    LogisticRegression,
    Perceptron,
    RidgeClassifier,
    RidgeClassifierCV,
    SGDClassifier,
)
from sklearn.multiclass import OneVsOneClassifier, OneVsRestClassifier, OutputCodeClassifier
from sklearn.naive_bayes import BernoulliNB, ComplementNB, GaussianNB, MultinomialNB
from sklearn.neighbors import KNeighborsClassifier, NearestCentroid
from sklearn.neural_network import MLPClassifier
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import KBinsDiscretizer
from sklearn.svm import SVC, LinearSVC, NuSVC
from sklearn.tree import DecisionTreeClassifier, ExtraTreeClassifier

from touchbench.benchmark.catalogue.boosters import CatBoostNominalClassifier, LightGBMClassifier
from touchbench.benchmark.catalogue.ensembles import describe_members, voting_classifier
from touchbench.benchmark.catalogue.estimators import LabelEncodedClassifier, OneRuleClassifier
from touchbench.benchmark.catalogue.model_trees import LogisticModelTree
from touchbench.benchmark.catalogue.neural import NeuralSequenceClassifier
from touchbench.benchmark.catalogue.rules import OrderedRuleClassifier
from touchbench.benchmark.catalogue.spec import ClassifierSpec, Combine, Ensemble, make_spec
from touchbench.benchmark.catalogue.stacking import stacked_spec
from touchbench.benchmark.catalogue.time_series import IntervalForestClassifier, RocketClassifier
from touchbench.benchmark.catalogue.weka_schemes import weka_command
from touchbench.benchmark.weka import (
    C45Classifier,
    PARTClassifier,
    WekaIBk,
    WekaNaiveBayes,
    WekaZeroR,
)

FAST = frozenset({"fast", "default"})
DEFAULT = frozenset({"default"})
ALL_ONLY: frozenset[str] = frozenset()

XGB_PARAMS: dict[str, Any] = {
    "n_estimators": 300,
    "max_depth": 6,
    "learning_rate": 0.1,
    "subsample": 0.9,
    "colsample_bytree": 0.8,
    "tree_method": "hist",
}
HGB_PARAMS: dict[str, Any] = {"max_iter": 300, "learning_rate": 0.1}


# Factories of composite models -------------------------------------------------------


def xgboost_classifier(**params: Any) -> BaseEstimator:
    """XGBoost behind a label encoder, so that folds missing a class still fit."""
    from xgboost import XGBClassifier  # imported on use: slow to import in every worker

    return LabelEncodedClassifier(XGBClassifier(**params))


def quantile_naive_bayes(n_bins: int = 10) -> BaseEstimator:
    """Equal-frequency discretisation followed by categorical naive Bayes."""
    from sklearn.naive_bayes import CategoricalNB

    return make_pipeline(
        KBinsDiscretizer(n_bins=n_bins, encode="ordinal", strategy="quantile"),
        CategoricalNB(min_categories=n_bins),
    )


def bagged_trees(n_estimators: int = 50, max_samples: float = 1.0) -> BaseEstimator:
    """Bagging of unpruned CART trees."""
    return BaggingClassifier(
        DecisionTreeClassifier(), n_estimators=n_estimators, max_samples=max_samples
    )


def bagged_c45(n_estimators: int = 10) -> BaseEstimator:
    """Bagging of C4.5 trees (WEKA J48's defaults) on bootstrap samples, probabilities averaged."""
    return BaggingClassifier(C45Classifier(), n_estimators=n_estimators)


def random_subspace_trees(n_estimators: int = 50, max_features: float = 0.5) -> BaseEstimator:
    """CART trees each on a random half of the features (random subspaces)."""
    return BaggingClassifier(
        DecisionTreeClassifier(),
        n_estimators=n_estimators,
        max_features=max_features,
        bootstrap=False,
    )


def boosted_stumps(n_estimators: int = 100, learning_rate: float = 1.0) -> BaseEstimator:
    """AdaBoost (SAMME) over decision stumps."""
    return AdaBoostClassifier(
        DecisionTreeClassifier(max_depth=1),
        n_estimators=n_estimators,
        learning_rate=learning_rate,
    )


def boosted_trees(
    n_estimators: int = 100, max_depth: int = 3, learning_rate: float = 0.5
) -> BaseEstimator:
    """AdaBoost (SAMME) over small trees."""
    return AdaBoostClassifier(
        DecisionTreeClassifier(max_depth=max_depth),
        n_estimators=n_estimators,
        learning_rate=learning_rate,
    )


def calibrated(base: str, method: str = "sigmoid", cv: int = 3) -> BaseEstimator:
    """A base model with probabilities from cross-validated calibration."""
    return CalibratedClassifierCV(_BASES[base](), method=method, cv=cv, ensemble=False)


def one_vs_rest(base: str) -> BaseEstimator:
    """One binary model per class."""
    return OneVsRestClassifier(_BASES[base]())


def one_vs_one(base: str) -> BaseEstimator:
    """One binary model per pair of classes, majority vote."""
    return OneVsOneClassifier(_BASES[base]())


def output_codes(base: str, code_size: float = 2.0) -> BaseEstimator:
    """Error-correcting output codes: random binary problems, nearest code wins."""
    return OutputCodeClassifier(_BASES[base](), code_size=code_size)


def gaussian_process(length_scale: float = 10.0, optimize: bool = False) -> BaseEstimator:
    """Laplace-approximated GP classifier (one-vs-rest) with an RBF kernel.

    The kernel's hyperparameters stay fixed unless ``optimize``: fitting them multiplies
    the (already cubic) cost by the optimiser's iterations.
    """
    kernel = ConstantKernel(1.0) * RBF(length_scale=length_scale)
    return GaussianProcessClassifier(kernel=kernel, optimizer="fmin_l_bfgs_b" if optimize else None)


def _logistic() -> BaseEstimator:
    return LogisticRegression(C=10.0, max_iter=2000)


def _entropy_tree() -> BaseEstimator:
    return DecisionTreeClassifier(criterion="entropy", min_samples_leaf=2)


def _linear_svm() -> BaseEstimator:
    return LinearSVC(C=1.0, max_iter=5000)


def _rbf_svm() -> BaseEstimator:
    return SVC(C=10.0)


_BASES = {
    "logistic": _logistic,
    "svm-linear": _linear_svm,
    "svm-rbf": _rbf_svm,
    "nb": GaussianNB,
    "entropy-tree": _entropy_tree,
}


# The entries -------------------------------------------------------------------------


def _spec(id: str, factory: Any, params: dict[str, Any], **fields: Any) -> ClassifierSpec:
    """An entry; ``weka`` is the WEKA class whose command line it reproduces, if any."""
    weka = fields.pop("weka", None)
    command = weka_command(weka, params) if weka else None
    return make_spec(id, factory, params, weka_command=command, **fields)


W = "weka.classifiers."
WEKA_NATIVE = "computes what WEKA 3.6 computes (checked prediction by prediction)"


def _weka(
    id: str, factory: Any, params: dict[str, Any], weka: str, **fields: Any
) -> ClassifierSpec:
    """An entry of :mod:`benchmark.weka`: WEKA's command, nominal codes and NaN as they are."""
    return _spec(
        id, factory, params, weka=W + weka, missing=True, nominal=True, limits=WEKA_NATIVE, **fields
    )


#: The neural entries: id, parameters, description, shortest sequence (the regression
#: catalogue offers the same networks on numeric targets).
NEURAL_ENTRIES: tuple[tuple[str, dict[str, Any], str, int], ...] = (
    (
        "bilstm",
        {"network": "bilstm", "hidden": 64, "layers": 1, "n_networks": 3},
        "Bidirectional LSTM (64 units a direction) over the time steps, 3 seeds (PyTorch)",
        2,
    ),
    (
        "cnn1d",
        {"network": "cnn1d", "filters": 32, "kernel": 5, "hidden": 64},
        "Three 1-D convolution blocks over channels, global pooling, dense layer (PyTorch)",
        4,
    ),
    (
        "resnet1d",
        {"network": "resnet1d", "filters": 32},
        "Time-series ResNet: 3 residual blocks of 1-D convolutions, global pooling (PyTorch)",
        8,
    ),
    (
        "inception-time",
        {"network": "inception-time", "filters": 32, "kernel": 39, "layers": 6},
        "InceptionTime: 6 inception modules (kernels 39, 19, 9), shortcuts, pooling (PyTorch)",
        8,
    ),
)
NEURAL_LIMITS = (
    "sequence data sets only; missing values imputed by the training mean; early stopping "
    "on 15 % of the training fold, then a refit on all of it; CPU, one thread per worker"
)


_SINGLE: tuple[ClassifierSpec, ...] = (
    # Baselines and rules
    _spec(
        "zeror",
        WekaZeroR,
        {},
        family="majority",
        description="Majority class; Laplace-corrected class frequencies as probabilities",
        weka=W + "rules.ZeroR",
        missing=True,
        suites=FAST,
        limits=WEKA_NATIVE,
    ),
    _spec(
        "oner",
        OneRuleClassifier,
        {"min_bucket": 6},
        family="rules",
        description="Best single-feature interval rule (OneR-like: intervals from a 1-D tree)",
        suites=FAST,
        limits="not WEKA's OneR: intervals from a 1-D tree, not OneR's bucket merging",
    ),
    _weka(
        "part",
        PARTClassifier,
        {"min_instances": 2, "confidence": 0.25},
        "rules.PART",
        family="rules",
        description="PART: decision list of rules from partial C4.5 trees",
        cost="slow",
        suites=ALL_ONLY,
    ),
    _spec(
        "ripper",
        OrderedRuleClassifier,
        {"algorithm": "ripper", "k": 2},
        family="rules",
        description="RIPPER rule sets per class in JRip's order (wittgenstein), 2 passes",
        probabilities=False,
        cost="slow",
        suites=ALL_ONLY,
        limits="not WEKA's JRip: numeric attributes binned into 10 quantiles first",
    ),
    _spec(
        "irep",
        OrderedRuleClassifier,
        {"algorithm": "irep"},
        family="rules",
        description="IREP rule sets per class in JRip's order (wittgenstein)",
        probabilities=False,
        cost="slow",
        suites=ALL_ONLY,
        limits="numeric attributes binned into 10 quantiles first",
    ),
    _spec(
        "stump",
        DecisionTreeClassifier,
        {"max_depth": 1},
        family="trees",
        description="Decision stump: one binary split",
        missing=True,
        limits="predicts at most two classes; not WEKA's DecisionStump (no missing branch)",
    ),
    # C4.5 (WEKA's J48)
    _weka(
        "j48",
        C45Classifier,
        {"confidence": 0.25, "min_instances": 2},
        "trees.J48",
        family="trees",
        description="C4.5 (J48): gain ratio, multiway nominal splits, pruned with confidence 0.25",
        suites=FAST,
    ),
    _weka(
        "j48-pruned",
        C45Classifier,
        {"confidence": 0.1, "min_instances": 2},
        "trees.J48",
        family="trees",
        description="C4.5 (J48) pruned harder: confidence 0.1",
    ),
    _weka(
        "j48-unpruned",
        C45Classifier,
        {"pruned": False, "min_instances": 2},
        "trees.J48",
        family="trees",
        description="C4.5 (J48) without pruning",
        suites=ALL_ONLY,
    ),
    _weka(
        "j48-no-raising",
        C45Classifier,
        {"confidence": 0.25, "subtree_raising": False, "min_instances": 2},
        "trees.J48",
        family="trees",
        description="C4.5 (J48) pruned without subtree raising",
        suites=ALL_ONLY,
    ),
    _weka(
        "j48-m5",
        C45Classifier,
        {"confidence": 0.25, "min_instances": 5},
        "trees.J48",
        family="trees",
        description="C4.5 (J48) with at least 5 instances per branch",
        suites=ALL_ONLY,
    ),
    # Other single trees
    _spec(
        "entropy-tree",
        DecisionTreeClassifier,
        {"criterion": "entropy", "min_samples_leaf": 2},
        family="trees",
        description="Binary information-gain tree (CART with entropy), 2 instances per leaf",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "cart",
        DecisionTreeClassifier,
        {"criterion": "gini", "min_samples_leaf": 2},
        family="trees",
        description="CART: Gini tree, unpruned",
        missing=True,
        limits="not WEKA's SimpleCart: no minimal cost-complexity pruning by cross-validation",
    ),
    _spec(
        "cart-pruned",
        DecisionTreeClassifier,
        {"criterion": "gini", "min_samples_leaf": 2, "ccp_alpha": 0.002},
        family="trees",
        description="CART with cost-complexity pruning (alpha 0.002)",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "lmt",
        LogisticModelTree,
        {"min_samples_leaf": 50, "C": 1.0},
        family="trees",
        description="Entropy tree, 50+ instances per leaf, an L2 logistic regression per leaf",
        cost="fast",
        suites=ALL_ONLY,
        limits="not WEKA's LMT: leaf models are plain logistic regressions, not LogitBoost "
        "refined from the parent's, and the tree is not pruned",
    ),
    _spec(
        "lmt-fine",
        LogisticModelTree,
        {"min_samples_leaf": 15, "C": 0.3},
        family="trees",
        description="Entropy tree, 15+ instances per leaf, a stronger-regularised logistic leaf",
        cost="fast",
        suites=ALL_ONLY,
        limits="not WEKA's LMT: leaf models are plain logistic regressions, not LogitBoost "
        "refined from the parent's, and the tree is not pruned",
    ),
    _spec(
        "random-tree",
        DecisionTreeClassifier,
        {"max_features": "log2", "criterion": "entropy"},
        family="trees",
        description="Unpruned tree over log2(d) random features per node",
        missing=True,
        limits="not WEKA's RandomTree: binary splits, log2(d) rather than log2(d)+1 features",
    ),
    _spec(
        "extra-tree",
        ExtraTreeClassifier,
        {},
        family="trees",
        description="One extremely randomised tree",
        missing=True,
        suites=ALL_ONLY,
    ),
    # Forests and bagging
    _spec(
        "rf",
        RandomForestClassifier,
        {"n_estimators": 100},
        family="forests",
        description="Random forest, 100 trees, sqrt(d) features per split",
        missing=True,
        suites=FAST,
    ),
    _spec(
        "rf-200",
        RandomForestClassifier,
        {"n_estimators": 200},
        family="forests",
        description="Random forest, 200 trees (a member of stacking)",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "rf-500",
        RandomForestClassifier,
        {"n_estimators": 500},
        family="forests",
        description="Random forest, 500 trees",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "rf-balanced",
        RandomForestClassifier,
        {"n_estimators": 100, "class_weight": "balanced"},
        family="forests",
        description="Random forest with class weights inversely proportional to frequency",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "rf-entropy",
        RandomForestClassifier,
        {"n_estimators": 100, "criterion": "entropy", "max_features": "log2"},
        family="forests",
        description="Random forest of information-gain trees, log2(d) features per split",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "extra-trees",
        ExtraTreesClassifier,
        {"n_estimators": 300},
        family="forests",
        description="Extremely randomised trees, 300 trees",
        missing=True,
    ),
    _spec(
        "extra-trees-200",
        ExtraTreesClassifier,
        {"n_estimators": 200},
        family="forests",
        description="Extremely randomised trees, 200 trees (a member of stacking)",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "extra-trees-entropy",
        ExtraTreesClassifier,
        {"n_estimators": 300, "criterion": "entropy"},
        family="forests",
        description="Extremely randomised information-gain trees, 300 trees",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "bagging",
        bagged_trees,
        {"n_estimators": 50, "max_samples": 1.0},
        family="bagging",
        description="Bagging of 50 unpruned CART trees",
    ),
    _spec(
        "bagging-j48",
        bagged_c45,
        {"n_estimators": 10},
        family="bagging",
        description="Bagging of 10 C4.5 (J48) trees, probabilities averaged",
        cost="slow",
        suites=ALL_ONLY,
        limits="nominal attributes reach the trees one-hot encoded; bags drawn by numpy",
    ),
    _spec(
        "random-subspace",
        random_subspace_trees,
        {"n_estimators": 50, "max_features": 0.5},
        family="bagging",
        description="50 CART trees, each on half of the features",
    ),
    # Boosting
    _spec(
        "adaboost",
        boosted_stumps,
        {"n_estimators": 100, "learning_rate": 1.0},
        family="boosting",
        description="AdaBoost (SAMME) over 100 decision stumps",
    ),
    _spec(
        "adaboost-tree",
        boosted_trees,
        {"n_estimators": 100, "max_depth": 3, "learning_rate": 0.5},
        family="boosting",
        description="AdaBoost (SAMME) over 100 depth-3 trees",
    ),
    _spec(
        "hgb",
        HistGradientBoostingClassifier,
        HGB_PARAMS,
        family="boosting",
        description="Histogram gradient boosting, native missing values and nominal features",
        missing=True,
        nominal=True,
        limits="nominal attributes with more than 255 labels are one-hot encoded instead",
    ),
    _spec(
        "hgb-balanced",
        HistGradientBoostingClassifier,
        {**HGB_PARAMS, "class_weight": "balanced"},
        family="boosting",
        description="Histogram gradient boosting with balanced class weights",
        missing=True,
        nominal=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "hgb-small",
        HistGradientBoostingClassifier,
        {"max_iter": 300, "learning_rate": 0.05, "max_leaf_nodes": 15, "l2_regularization": 1.0},
        family="boosting",
        description="Histogram gradient boosting, 15-leaf trees, slower learning, L2 1.0",
        missing=True,
        nominal=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "gbm",
        GradientBoostingClassifier,
        {"n_estimators": 100, "max_depth": 3},
        family="boosting",
        description="Gradient boosting of depth-3 trees, 100 stages",
        cost="slow",
        suites=ALL_ONLY,  # slower than xgb and hgb and scores below them: out of the default
    ),
    _spec(
        "xgb",
        xgboost_classifier,
        XGB_PARAMS,
        family="boosting",
        description="XGBoost, 300 rounds of depth-6 trees",
        missing=True,
    ),
    _spec(
        "xgb-shallow",
        xgboost_classifier,
        {**XGB_PARAMS, "max_depth": 3, "n_estimators": 500},
        family="boosting",
        description="XGBoost, 500 rounds of depth-3 trees",
        missing=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "lgbm",
        LightGBMClassifier,
        {"n_estimators": 300, "learning_rate": 0.05, "num_leaves": 31},
        family="boosting",
        description="LightGBM, 300 rounds of 31-leaf trees, native nominal features",
        missing=True,
        nominal=True,
        cost="slow",
        suites=ALL_ONLY,
    ),
    _spec(
        "lgbm-small",
        LightGBMClassifier,
        {"n_estimators": 300, "learning_rate": 0.05, "num_leaves": 15, "min_child_samples": 5},
        family="boosting",
        description="LightGBM, 300 rounds of 15-leaf trees",
        missing=True,
        nominal=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "lgbm-bagged",
        LightGBMClassifier,
        {
            "n_estimators": 300,
            "learning_rate": 0.05,
            "subsample": 0.8,
            "subsample_freq": 1,
            "colsample_bytree": 0.8,
        },
        family="boosting",
        description="LightGBM with 80% row and feature sampling per round",
        missing=True,
        nominal=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "lgbm-balanced",
        LightGBMClassifier,
        {"n_estimators": 300, "learning_rate": 0.05, "class_weight": "balanced"},
        family="boosting",
        description="LightGBM with balanced class weights",
        missing=True,
        nominal=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "lgbm-dart",
        LightGBMClassifier,
        {"n_estimators": 200, "learning_rate": 0.1, "boosting_type": "dart"},
        family="boosting",
        description="LightGBM DART (dropout boosting), 200 rounds",
        missing=True,
        nominal=True,
        cost="slow",
        suites=ALL_ONLY,
    ),
    _spec(
        "lgbm-rf",
        LightGBMClassifier,
        {
            "n_estimators": 200,
            "boosting_type": "rf",
            "subsample": 0.632,
            "subsample_freq": 1,
            "colsample_bytree": 0.5,
        },
        family="forests",
        description="LightGBM in random-forest mode, 200 trees",
        missing=True,
        nominal=True,
        suites=ALL_ONLY,
    ),
    _spec(
        "catboost",
        CatBoostNominalClassifier,
        {"iterations": 300, "depth": 6},
        family="boosting",
        description="CatBoost, 300 rounds of depth-6 oblivious trees, nominal features native",
        missing=True,
        nominal=True,
        cost="slow",
        suites=ALL_ONLY,
    ),
    _spec(
        "catboost-shallow",
        CatBoostNominalClassifier,
        {"iterations": 300, "depth": 4},
        family="boosting",
        description="CatBoost, 300 rounds of depth-4 trees",
        missing=True,
        nominal=True,
        cost="slow",
        suites=ALL_ONLY,
    ),
    _spec(
        "catboost-balanced",
        CatBoostNominalClassifier,
        {"iterations": 300, "depth": 6, "auto_class_weights": "Balanced"},
        family="boosting",
        description="CatBoost with balanced class weights",
        missing=True,
        nominal=True,
        cost="slow",
        suites=ALL_ONLY,
    ),
    # Nearest neighbours: WEKA's IBk exactly, then scikit-learn's
    _weka(
        "ibk",
        WekaIBk,
        {"n_neighbors": 1},
        "lazy.IBk",
        family="nearest-neighbours",
        description="1-nearest neighbour on WEKA's distance (range-normalised, nominal 0/1)",
        suites=FAST,
    ),
    _weka(
        "ibk3",
        WekaIBk,
        {"n_neighbors": 3},
        "lazy.IBk",
        family="nearest-neighbours",
        description="3-nearest neighbours (IBk)",
    ),
    _weka(
        "ibk5",
        WekaIBk,
        {"n_neighbors": 5},
        "lazy.IBk",
        family="nearest-neighbours",
        description="5-nearest neighbours (IBk)",
    ),
    _weka(
        "ibk10",
        WekaIBk,
        {"n_neighbors": 10},
        "lazy.IBk",
        family="nearest-neighbours",
        description="10-nearest neighbours (IBk)",
    ),
    _weka(
        "ibk-w",
        WekaIBk,
        {"n_neighbors": 10, "weighting": "inverse"},
        "lazy.IBk",
        family="nearest-neighbours",
        description="10-nearest neighbours weighted by 1/distance (IBk -I)",
    ),
    _weka(
        "ibk5-w",
        WekaIBk,
        {"n_neighbors": 5, "weighting": "inverse"},
        "lazy.IBk",
        family="nearest-neighbours",
        description="5-nearest neighbours weighted by 1/distance (IBk -I)",
        suites=ALL_ONLY,
    ),
    _weka(
        "ibk10-f",
        WekaIBk,
        {"n_neighbors": 10, "weighting": "similarity"},
        "lazy.IBk",
        family="nearest-neighbours",
        description="10-nearest neighbours weighted by 1 - distance (IBk -F)",
        suites=ALL_ONLY,
    ),
    _spec(
        "knn5",
        KNeighborsClassifier,
        {"n_neighbors": 5},
        family="nearest-neighbours",
        description="5-nearest neighbours (scikit-learn) on [0, 1]-scaled, one-hot features",
        scaling="minmax",
        suites=ALL_ONLY,
    ),
    _spec(
        "ibk5-std",
        KNeighborsClassifier,
        {"n_neighbors": 5},
        family="nearest-neighbours",
        description="5-nearest neighbours (scikit-learn) on standardised features",
        scaling="standard",
    ),
    _spec(
        "knn10-distance",
        KNeighborsClassifier,
        {"n_neighbors": 10, "weights": "distance"},
        family="nearest-neighbours",
        description="10-nearest neighbours (scikit-learn) weighted by 1/distance, standardised",
        scaling="standard",
        suites=ALL_ONLY,
    ),
    # Naive Bayes: WEKA's NaiveBayes exactly, then scikit-learn's
    _weka(
        "nb",
        WekaNaiveBayes,
        {"numeric": "normal"},
        "bayes.NaiveBayes",
        family="naive-bayes",
        description="Naive Bayes: Laplace frequencies for nominal, normal density for numeric",
        suites=FAST,
    ),
    _weka(
        "nb-kernel",
        WekaNaiveBayes,
        {"numeric": "kernel"},
        "bayes.NaiveBayes",
        family="naive-bayes",
        description="Naive Bayes with kernel density estimates for numeric attributes (-K)",
    ),
    _weka(
        "nb-discretized",
        WekaNaiveBayes,
        {"numeric": "discretize"},
        "bayes.NaiveBayes",
        family="naive-bayes",
        description="Naive Bayes on Fayyad-Irani MDL intervals of numeric attributes (-D)",
    ),
    _spec(
        "nb-gaussian",
        GaussianNB,
        {},
        family="naive-bayes",
        description="Gaussian naive Bayes (scikit-learn) on imputed, one-hot features",
        suites=ALL_ONLY,
    ),
    _spec(
        "nb-quantile",
        quantile_naive_bayes,
        {"n_bins": 10},
        family="naive-bayes",
        description="Categorical naive Bayes on 10 equal-frequency bins per feature",
        suites=ALL_ONLY,
    ),
    _spec(
        "nb-bernoulli",
        BernoulliNB,
        {"binarize": 0.0},
        family="naive-bayes",
        description="Bernoulli naive Bayes on features above their mean",
        scaling="standard",
    ),
    _spec(
        "nb-multinomial",
        MultinomialNB,
        {"alpha": 1.0},
        family="naive-bayes",
        description="Multinomial naive Bayes on [0, 1]-scaled features",
        scaling="minmax",
    ),
    _spec(
        "nb-complement",
        ComplementNB,
        {"alpha": 1.0},
        family="naive-bayes",
        description="Complement naive Bayes on [0, 1]-scaled features",
        scaling="minmax",
    ),
    # Discriminant analysis
    _spec(
        "lda",
        LinearDiscriminantAnalysis,
        {"solver": "svd"},
        family="discriminant-analysis",
        description="Linear discriminant analysis",
        suites=FAST,
    ),
    _spec(
        "lda-shrinkage",
        LinearDiscriminantAnalysis,
        {"solver": "lsqr", "shrinkage": "auto"},
        family="discriminant-analysis",
        description="LDA with Ledoit-Wolf shrinkage",
        scaling="standard",
    ),
    _spec(
        "qda",
        QuadraticDiscriminantAnalysis,
        {"reg_param": 0.1},
        family="discriminant-analysis",
        description="Quadratic discriminant analysis, covariance regularised by 0.1",
        scaling="standard",
    ),
    _spec(
        "qda-strong",
        QuadraticDiscriminantAnalysis,
        {"reg_param": 0.5},
        family="discriminant-analysis",
        description="Quadratic discriminant analysis, covariance regularised by 0.5",
        scaling="standard",
        suites=ALL_ONLY,
    ),
    # Logistic regression
    _spec(
        "logistic",
        LogisticRegression,
        {"C": 10.0, "max_iter": 2000},
        family="logistic",
        description="Multinomial logistic regression with a ridge (C=10) on standardised features",
        scaling="standard",
        suites=FAST,
    ),
    _spec(
        "logistic-weak",
        LogisticRegression,
        {"C": 1000.0, "max_iter": 5000},
        family="logistic",
        description="Nearly unregularised logistic regression (C=1000)",
        scaling="standard",
    ),
    _spec(
        "logistic-mle",
        LogisticRegression,
        {"C": 5e7, "max_iter": 10000},
        family="logistic",
        description="Multinomial logistic regression with a ridge of 1e-8 (maximum likelihood)",
        scaling="standard",
        suites=ALL_ONLY,
        limits="WEKA's Logistic has this ridge but replaces missing nominal values by the mode",
    ),
    _spec(
        "logistic-l1",
        LogisticRegression,
        {"C": 1.0, "l1_ratio": 1.0, "solver": "saga", "max_iter": 3000},
        family="logistic",
        description="Logistic regression with a lasso (L1) penalty",
        scaling="standard",
        cost="slow",
        suites=ALL_ONLY,
    ),
    _spec(
        "logistic-balanced",
        LogisticRegression,
        {"C": 10.0, "max_iter": 2000, "class_weight": "balanced"},
        family="logistic",
        description="Logistic regression with balanced class weights",
        scaling="standard",
        suites=ALL_ONLY,
    ),
    _spec(
        "logistic-strong",
        LogisticRegression,
        {"C": 0.1, "max_iter": 2000},
        family="logistic",
        description="Logistic regression with a strong ridge (C=0.1)",
        scaling="standard",
        suites=ALL_ONLY,
    ),
    # Support vector machines
    _spec(
        "svm-linear",
        LinearSVC,
        {"C": 1.0, "max_iter": 5000},
        family="svm",
        description="Linear SVM (liblinear, one-vs-rest)",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "svm-linear-smo",
        SVC,
        {"kernel": "linear", "C": 1.0},
        family="svm",
        description="Linear-kernel SVM (libsvm, one-vs-one) on [0, 1]-scaled features",
        probabilities=False,
        scaling="minmax",
    ),
    _spec(
        "svm-poly",
        SVC,
        {"kernel": "poly", "degree": 2, "C": 10.0, "coef0": 1.0},
        family="svm",
        description="Quadratic-kernel SVM",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "svm-poly3",
        SVC,
        {"kernel": "poly", "degree": 3, "C": 1.0, "coef0": 1.0},
        family="svm",
        description="Cubic-kernel SVM",
        probabilities=False,
        scaling="standard",
        suites=ALL_ONLY,
    ),
    _spec(
        "svm-rbf",
        SVC,
        {"kernel": "rbf", "C": 10.0, "gamma": "scale"},
        family="svm",
        description="RBF-kernel SVM on standardised features",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "svm-rbf-c1",
        SVC,
        {"kernel": "rbf", "C": 1.0, "gamma": "scale"},
        family="svm",
        description="RBF-kernel SVM, C=1",
        probabilities=False,
        scaling="standard",
        suites=ALL_ONLY,
    ),
    _spec(
        "svm-rbf-balanced",
        SVC,
        {"kernel": "rbf", "C": 10.0, "class_weight": "balanced"},
        family="svm",
        description="RBF-kernel SVM with balanced class weights",
        probabilities=False,
        scaling="standard",
        suites=ALL_ONLY,
    ),
    _spec(
        "nusvc",
        NuSVC,
        {"nu": 0.3, "kernel": "rbf"},
        family="svm",
        description="Nu-SVM with an RBF kernel (nu=0.3)",
        probabilities=False,
        scaling="standard",
        limits="fails ('specified nu is infeasible') when a class is much rarer than nu",
    ),
    # Neural networks
    _spec(
        "mlp",
        MLPClassifier,
        {"hidden_layer_sizes": (100,), "alpha": 1e-3, "max_iter": 500, "early_stopping": True},
        family="neural-network",
        description="Multilayer perceptron, one hidden layer of 100",
        scaling="standard",
    ),
    _spec(
        "mlp-small",
        MLPClassifier,
        {"hidden_layer_sizes": (30,), "alpha": 1e-2, "max_iter": 1000},
        family="neural-network",
        description="Multilayer perceptron, one hidden layer of 30, weight decay 0.01",
        scaling="standard",
        suites=ALL_ONLY,
    ),
    _spec(
        "mlp-deep",
        MLPClassifier,
        {"hidden_layer_sizes": (256, 128), "alpha": 1e-3, "max_iter": 500, "early_stopping": True},
        family="neural-network",
        description="Multilayer perceptron, hidden layers 256 and 128",
        scaling="standard",
        suites=ALL_ONLY,
    ),
    # Linear models trained by SGD and friends
    _spec(
        "sgd-hinge",
        SGDClassifier,
        {"loss": "hinge", "alpha": 1e-4},
        family="linear-sgd",
        description="Linear SVM trained by SGD",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "sgd-log",
        SGDClassifier,
        {"loss": "log_loss", "alpha": 1e-4},
        family="linear-sgd",
        description="Logistic regression trained by SGD",
        scaling="standard",
    ),
    _spec(
        "sgd-modified-huber",
        SGDClassifier,
        {"loss": "modified_huber", "alpha": 1e-4},
        family="linear-sgd",
        description="Modified-Huber loss linear model trained by SGD",
        scaling="standard",
    ),
    _spec(
        "perceptron",
        Perceptron,
        {},
        family="linear-sgd",
        description="Perceptron (one-vs-rest)",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "pa",
        SGDClassifier,
        {"loss": "hinge", "penalty": None, "learning_rate": "pa1", "eta0": 1.0},
        family="linear-sgd",
        description="Passive-aggressive (PA-I) linear classifier",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "ridge",
        RidgeClassifier,
        {"alpha": 1.0},
        family="linear",
        description="Ridge regression on one-vs-rest targets",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "ridge-cv",
        RidgeClassifierCV,
        {"alphas": (0.1, 1.0, 10.0, 100.0)},
        family="linear",
        description="Ridge classifier with the penalty chosen by leave-one-out",
        probabilities=False,
        scaling="standard",
    ),
    # Prototypes and Gaussian processes
    _spec(
        "nearest-centroid",
        NearestCentroid,
        {},
        family="prototype",
        description="Nearest class mean",
        scaling="standard",
    ),
    _spec(
        "nearest-centroid-shrunk",
        NearestCentroid,
        {"shrink_threshold": 0.5},
        family="prototype",
        description="Nearest shrunken centroid",
        scaling="standard",
    ),
    _spec(
        "gp",
        gaussian_process,
        {"length_scale": 10.0, "optimize": False},
        family="gaussian-process",
        description="Gaussian process classifier, fixed RBF kernel (length 10), one-vs-rest",
        scaling="standard",
        cost="slow",
        suites=ALL_ONLY,
        limits="memory and time grow with the cube of the training size",
    ),
    # Calibration and multi-class wrappers
    _spec(
        "calibrated-svm-linear",
        calibrated,
        {"base": "svm-linear", "method": "sigmoid"},
        family="calibration",
        description="Linear SVM with sigmoid-calibrated probabilities",
        scaling="standard",
    ),
    _spec(
        "calibrated-svm-rbf",
        calibrated,
        {"base": "svm-rbf", "method": "sigmoid"},
        family="calibration",
        description="RBF SVM with sigmoid-calibrated probabilities",
        scaling="standard",
    ),
    _spec(
        "calibrated-nb",
        calibrated,
        {"base": "nb", "method": "isotonic"},
        family="calibration",
        description="Gaussian naive Bayes, isotonic calibration",
    ),
    _spec(
        "ovr-logistic",
        one_vs_rest,
        {"base": "logistic"},
        family="multiclass-wrapper",
        description="One-vs-rest logistic regressions",
        scaling="standard",
    ),
    _spec(
        "ovr-svm-rbf",
        one_vs_rest,
        {"base": "svm-rbf"},
        family="multiclass-wrapper",
        description="One-vs-rest RBF SVMs",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "ovo-logistic",
        one_vs_one,
        {"base": "logistic"},
        family="multiclass-wrapper",
        description="One-vs-one logistic regressions, majority vote",
        probabilities=False,
        scaling="standard",
    ),
    _spec(
        "ovo-j48",
        one_vs_one,
        {"base": "entropy-tree"},
        family="multiclass-wrapper",
        description="One-vs-one information-gain trees, majority vote",
        probabilities=False,
    ),
    _spec(
        "ecoc",
        output_codes,
        {"base": "logistic", "code_size": 2.0},
        family="multiclass-wrapper",
        description="Error-correcting output codes over logistic regressions",
        probabilities=False,
        scaling="standard",
    ),
)

_BY_ID = {spec.id: spec for spec in _SINGLE}


def _ensemble(id: str, combine: Combine, members: tuple[str, ...], **fields: Any) -> ClassifierSpec:
    """An ensemble of the entries ``members`` (ids above), its description naming them."""
    specs = tuple(_BY_ID[member] for member in members)
    return make_spec(
        id,
        voting_classifier,
        {"voting": combine},
        family="voting",
        description=describe_members(combine, specs),
        probabilities=combine == "soft",
        missing=True,
        nominal=True,
        ensemble=Ensemble(specs, combine),
        **fields,
    )


_STACKED = ("rf-200", "extra-trees-200", "svm-rbf", "logistic")

SPECS: tuple[ClassifierSpec, ...] = (
    *_SINGLE,
    # Ensembles of the entries above: a run computes them from their members' fold
    # predictions, fitting each member once per fold
    _ensemble("voting", "soft", ("xgb", "hgb", "calibrated-svm-rbf"), cost="slow"),
    _ensemble("voting-hard", "hard", ("logistic", "rf", "svm-rbf")),
    stacked_spec(
        [_BY_ID[member] for member in _STACKED],
        len(_STACKED),
        id="stacking",
        description=describe_members("stack", [_BY_ID[member] for member in _STACKED])
        + ", all kept, on their inner out-of-fold class scores",
        suites=ALL_ONLY,  # costlier than soft voting and scores below it: out of the default
    ),
    # Time series: the windows of a sequence data set (benchmark.sequence)
    _spec(
        "minirocket",
        RocketClassifier,
        {"variant": "minirocket", "n_kernels": 10_000},
        family="time-series",
        description="MiniRocket (aeon): 10,000 dilated-convolution features, ridge classifier",
        probabilities=False,
        min_sequence=9,
        limits="sequence data sets only; missing values imputed by the training mean",
    ),
    _spec(
        "multirocket",
        RocketClassifier,
        {"variant": "multirocket", "n_kernels": 6_250},
        family="time-series",
        description="MultiRocket (aeon): 4 poolings of series and differences, ridge classifier",
        probabilities=False,
        cost="slow",
        min_sequence=10,
        limits="sequence data sets only; missing values imputed by the training mean",
    ),
    _spec(
        "interval-forest",
        IntervalForestClassifier,
        {"n_intervals": None, "n_estimators": 300},
        family="time-series",
        description="7 statistics of random intervals of series, differences and spectra; "
        "extra trees",
        min_sequence=2,
        limits="sequence data sets only; one draw of intervals for the forest (aeon's "
        "RandomIntervalClassifier), not a draw per tree as DrCIF; no catch22 features",
    ),
    # Neural networks on the windows (PyTorch, imported only where one fits or predicts)
    *(
        _spec(
            id,
            NeuralSequenceClassifier,
            params,
            family="neural-network",
            description=description,
            cost="slow",
            suites=ALL_ONLY,  # minutes per fold on a few thousand windows
            min_sequence=minimum,
            limits=NEURAL_LIMITS,
        )
        for id, params, description, minimum in NEURAL_ENTRIES
    ),
)
