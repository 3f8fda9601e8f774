"""The regression catalogue: what a classifier id means on numeric targets, as data.

A data set whose targets are numeric is a regression (:class:`benchmark.problem.Problem`
with ``task="regression"``).  On it, the ids of the classifier catalogue name the
regressor of the same family (``rf`` a random forest regressor, ``xgb`` XGBoost's
regressor, ``ibk`` 1-nearest neighbour...), and ``linear`` and ``ridge`` are least
squares without and with an L2 penalty.  An id with no regressor counterpart is refused.

Several numeric targets at once (multi-output regression):

- a plain id fits one model for all targets where the model is natively multi-output
  (linear models, trees, forests, k-NN, XGBoost, Gaussian process, MLP) and one model per
  target otherwise (SVR, gradient boosting);
- ``br:BASE`` always fits one independent model per target;
- ``rc:BASE`` is a regressor chain: each target's model also reads the predictions for the
  targets before it (scikit-learn's ``RegressorChain``, targets in data set order).

>>> regressor_spec("rf", n_targets=1).factory.__name__
'RandomForestRegressor'
>>> regressor_spec("rc:ridge", n_targets=2).id
'rc:ridge'
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from types import MappingProxyType
from typing import Any

from sklearn.base import BaseEstimator
from sklearn.compose import TransformedTargetRegressor
from sklearn.dummy import DummyRegressor
from sklearn.ensemble import (
    ExtraTreesRegressor,
    GradientBoostingRegressor,
    HistGradientBoostingRegressor,
    RandomForestRegressor,
)
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel
from sklearn.linear_model import LinearRegression, Ridge
from sklearn.multioutput import MultiOutputRegressor, RegressorChain
from sklearn.neighbors import KNeighborsRegressor
from sklearn.neural_network import MLPRegressor
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVR, LinearSVR
from sklearn.tree import DecisionTreeRegressor

from touchbench.benchmark.catalogue import CATALOGUE, SUITES, unknown_classifier_message
from touchbench.benchmark.catalogue.entries import NEURAL_ENTRIES, NEURAL_LIMITS
from touchbench.benchmark.catalogue.neural import NeuralSequenceRegressor
from touchbench.benchmark.catalogue.spec import ClassifierSpec, make_spec
from touchbench.benchmark.errors import ConfigurationError

__all__ = [
    "CHAIN_PREFIXES",
    "GP_MAX_INSTANCES",
    "NATIVE_MULTI_OUTPUT",
    "REGRESSORS",
    "regression_suite",
    "regressor_spec",
]

#: The Gaussian process is refused above this many instances: its fit costs the cube of
#: the training size per step of the kernel optimiser, and its memory the square.
GP_MAX_INSTANCES = 2000

#: Multi-output prefixes: one model per target, or a regressor chain.
CHAIN_PREFIXES: Mapping[str, str] = MappingProxyType(
    {"br": "one independent model per target", "rc": "regressor chain"}
)

#: Regression suites: ids in catalogue order (``all``: every entry).
_FAST = frozenset({"fast", "default"})
_DEFAULT = frozenset({"default"})
_ALL_ONLY: frozenset[str] = frozenset()

#: Chains run by the default suite on several targets.
_DEFAULT_CHAINS = ("rc:ridge", "rc:svm-rbf", "rc:xgb")


def xgboost_regressor(**params: Any) -> BaseEstimator:
    """XGBoost's regressor (natively multi-output), imported on use like the classifier."""
    from xgboost import XGBRegressor

    return XGBRegressor(**params)


def scaled_target(regressor: str, **params: Any) -> BaseEstimator:
    """A regressor fitted on standardised targets, its predictions mapped back.

    SVR's epsilon tube and an MLP's initialisation assume targets of unit scale; positions
    in centimetres or forces in newtons are not.
    """
    estimator = _SCALED[regressor](**params)
    return TransformedTargetRegressor(regressor=estimator, transformer=StandardScaler())


def optimised_gaussian_process(
    length_scale: float = 1.0, noise: float = 0.1, n_restarts: int = 0
) -> BaseEstimator:
    """GP regression with a constant x RBF + white-noise kernel whose hyperparameters
    (amplitude, length scale, noise level) maximise the marginal likelihood; targets are
    normalised."""
    kernel = ConstantKernel(1.0) * RBF(length_scale=length_scale) + WhiteKernel(noise)
    return GaussianProcessRegressor(
        kernel=kernel, normalize_y=True, n_restarts_optimizer=n_restarts
    )


def per_target(base: str) -> BaseEstimator:
    """One clone of the ``base`` regressor per target."""
    return MultiOutputRegressor(REGRESSORS[base].make_estimator())


def chain(base: str) -> BaseEstimator:
    """A regressor chain of ``base`` regressors, targets in data set order."""
    return RegressorChain(REGRESSORS[base].make_estimator())


_SCALED = {"svr": SVR, "linear-svr": LinearSVR, "mlp": MLPRegressor}


def _spec(id: str, factory: Any, params: dict[str, Any], **fields: Any) -> ClassifierSpec:
    return make_spec(id, factory, params, probabilities=False, **fields)


_SPECS: tuple[ClassifierSpec, ...] = (
    _spec(
        "zeror",
        DummyRegressor,
        {"strategy": "mean"},
        family="baseline",
        description="The training mean of each target (WEKA's ZeroR on a numeric class)",
        suites=_FAST,
    ),
    _spec(
        "linear",
        LinearRegression,
        {},
        family="linear",
        description="Ordinary least squares",
        scaling="standard",
        suites=_FAST,
    ),
    _spec(
        "ridge",
        Ridge,
        {"alpha": 1.0},
        family="linear",
        description="Least squares with an L2 penalty (alpha 1) on standardised features",
        scaling="standard",
        suites=_FAST,
    ),
    _spec(
        "cart",
        DecisionTreeRegressor,
        {"min_samples_leaf": 2},
        family="trees",
        description="CART regression tree (squared error), 2 instances per leaf",
        missing=True,
    ),
    _spec(
        "ibk",
        KNeighborsRegressor,
        {"n_neighbors": 1},
        family="nearest-neighbours",
        description="1-nearest neighbour on [0, 1]-scaled features (WEKA IBk's normalisation)",
        scaling="minmax",
        suites=_FAST,
    ),
    _spec(
        "knn5",
        KNeighborsRegressor,
        {"n_neighbors": 5, "weights": "distance"},
        family="nearest-neighbours",
        description="5 nearest neighbours weighted by inverse distance, [0, 1]-scaled features",
        scaling="minmax",
    ),
    _spec(
        "svm-rbf",
        scaled_target,
        {"regressor": "svr", "kernel": "rbf", "C": 10.0, "gamma": "scale"},
        family="svm",
        description="Epsilon-SVR with an RBF kernel on standardised features and targets",
        scaling="standard",
    ),
    _spec(
        "svm-linear",
        scaled_target,
        {"regressor": "linear-svr", "C": 1.0, "max_iter": 5000},
        family="svm",
        description="Linear epsilon-SVR on standardised features and targets",
        scaling="standard",
        suites=_ALL_ONLY,
    ),
    _spec(
        "rf",
        RandomForestRegressor,
        {"n_estimators": 100, "max_features": 1.0},
        family="forests",
        description="Random forest regressor, 100 trees, all features per split (Breiman's)",
        missing=True,
        suites=_FAST,
    ),
    _spec(
        "extra-trees",
        ExtraTreesRegressor,
        {"n_estimators": 300},
        family="forests",
        description="Extremely randomised regression trees, 300 trees",
    ),
    _spec(
        "gbm",
        GradientBoostingRegressor,
        {"n_estimators": 100, "max_depth": 3},
        family="boosting",
        description="Gradient boosting of depth-3 trees, 100 stages (squared error)",
    ),
    _spec(
        "hgb",
        HistGradientBoostingRegressor,
        {"max_iter": 300, "learning_rate": 0.1},
        family="boosting",
        description="Histogram gradient boosting, native missing values and nominal features",
        missing=True,
        nominal=True,
        suites=_ALL_ONLY,
    ),
    _spec(
        "xgb",
        xgboost_regressor,
        {
            "n_estimators": 300,
            "max_depth": 6,
            "learning_rate": 0.1,
            "subsample": 0.9,
            "colsample_bytree": 0.8,
            "tree_method": "hist",
        },
        family="boosting",
        description="XGBoost regressor, 300 rounds of depth-6 trees",
        missing=True,
    ),
    _spec(
        "gp",
        optimised_gaussian_process,
        {"length_scale": 1.0, "noise": 0.1, "n_restarts": 0},
        family="gaussian-process",
        description="Gaussian process, constant x RBF + white kernel optimised by likelihood",
        scaling="standard",
        cost="slow",
        limits=f"refused above {GP_MAX_INSTANCES} instances (cubic time, quadratic memory)",
    ),
    _spec(
        "mlp",
        scaled_target,
        {
            "regressor": "mlp",
            "hidden_layer_sizes": (100,),
            "alpha": 1e-3,
            "max_iter": 500,
            "early_stopping": True,
        },
        family="neural-network",
        description="Multilayer perceptron, one hidden layer of 100, standardised targets",
        scaling="standard",
    ),
    # Networks on a sequence data set's windows, every target at once
    *(
        _spec(
            id,
            NeuralSequenceRegressor,
            params,
            family="neural-network",
            description=f"{description}, standardised targets",
            cost="slow",
            suites=_ALL_ONLY,
            min_sequence=minimum,
            limits=NEURAL_LIMITS,
        )
        for id, params, description, minimum in NEURAL_ENTRIES
        if id in ("bilstm", "cnn1d")
    ),
)

#: Regressors by id (the ids classifiers of the same family have, plus linear and ridge).
REGRESSORS: Mapping[str, ClassifierSpec] = MappingProxyType({s.id: s for s in _SPECS})

#: Regressors that fit several targets with one model.
NATIVE_MULTI_OUTPUT: frozenset[str] = frozenset(
    {"zeror", "linear", "ridge", "cart", "ibk", "knn5", "rf", "extra-trees", "xgb", "gp", "mlp"}
    | {"bilstm", "cnn1d"}
)


def regressor_spec(
    regressor_id: str, *, n_targets: int, n_instances: int | None = None
) -> ClassifierSpec:
    """The configuration ``regressor_id`` means on ``n_targets`` numeric targets.

    Parameters
    ----------
    regressor_id : str
        A regressor id (``rf``, ``ridge``...), or ``br:ID`` / ``rc:ID`` for several targets.
    n_targets : int
        Number of numeric targets.
    n_instances : int, optional
        Training instances, checked against limits such as :data:`GP_MAX_INSTANCES`.

    Raises
    ------
    ConfigurationError
        An id with no regressor (a classifier-only id included), a chain on one target, a
        model beyond its instance limit.
    """
    prefix, _, base = regressor_id.rpartition(":")
    spec = _base_spec(base, regressor_id)
    if n_instances is not None and base == "gp" and n_instances > GP_MAX_INSTANCES:
        raise ConfigurationError(
            f"regressor 'gp' is limited to {GP_MAX_INSTANCES} instances (cubic cost); this "
            f"data set has {n_instances}"
        )
    if prefix:
        if spec.needs_sequence:
            raise ConfigurationError(
                f"'{regressor_id}': the sequence regressor '{base}' predicts every target "
                f"with one network; use '{base}'"
            )
        if prefix not in CHAIN_PREFIXES:
            raise ConfigurationError(
                f"unknown multi-output method '{prefix}' in '{regressor_id}'; numeric targets "
                f"take {', '.join(f'{p}:ID ({what})' for p, what in CHAIN_PREFIXES.items())}"
            )
        if n_targets < 2:
            raise ConfigurationError(
                f"'{regressor_id}' combines models over several targets; this regression has "
                f"one target: use '{base}'"
            )
        return _wrapped(spec, regressor_id, chain if prefix == "rc" else per_target)
    if n_targets > 1 and base not in NATIVE_MULTI_OUTPUT:
        return _wrapped(spec, regressor_id, per_target)
    return spec


def regression_suite(
    name: str, *, n_targets: int, n_instances: int, sequences: bool = False
) -> list[str]:
    """The regressor ids of a suite for a regression of this size.

    The Gaussian process is left out above :data:`GP_MAX_INSTANCES` instances; sequence
    regressors are in only for a sequence data set (``sequences``); several targets add
    the suite's regressor chains (``rc:ID``).
    """
    if name not in SUITES:
        raise ConfigurationError(f"unknown suite '{name}' (suites: {', '.join(SUITES)})")
    ids = [
        spec.id
        for spec in _SPECS
        if (name == "all" or name in spec.suites)
        and not (spec.id == "gp" and n_instances > GP_MAX_INSTANCES)
        and (sequences or not spec.needs_sequence)
        and spec.installed
    ]
    if n_targets > 1 and name != "fast":
        chains = [f"rc:{i}" for i in ids] if name == "all" else list(_DEFAULT_CHAINS)
        ids += [c for c in chains if c.split(":", 1)[1] in ids and not _reads_sequences(c)]
    return ids


def _reads_sequences(regressor_id: str) -> bool:
    return REGRESSORS[regressor_id.rpartition(":")[2]].needs_sequence


def _base_spec(base: str, regressor_id: str) -> ClassifierSpec:
    if base in REGRESSORS:
        return REGRESSORS[base]
    known = ", ".join(REGRESSORS)
    if base in CATALOGUE:
        raise ConfigurationError(
            f"classifier '{base}' has no regressor: the targets are numeric (regressors: {known})"
        )
    message = unknown_classifier_message(regressor_id, REGRESSORS)
    raise ConfigurationError(f"{message} (regressors on numeric targets: {known})")


def _wrapped(spec: ClassifierSpec, new_id: str, factory: Any) -> ClassifierSpec:
    what = "regressor chain of" if factory is chain else "one model per target:"
    return replace(
        spec,
        id=new_id,
        factory=factory,
        params={"base": spec.id},
        description=f"{what} {spec.description[0].lower()}{spec.description[1:]}",
        handles_missing=False,
        handles_nominal=False,
        suites=_ALL_ONLY,
    )
