"""Search spaces of the catalogue entries that ``bench --tune`` tunes.

Each space maps an estimator parameter, named as the entry's estimator names it in
``get_params(deep=True)`` (``estimator__max_depth`` for XGBoost behind its label encoder),
to the values to try. Spaces are discrete, so that the halving search and a full grid
search (``perf/tuning.py``) search the same thing; each holds the entry's own default
values, so tuning may always keep them.
"""

from __future__ import annotations

from types import MappingProxyType

from touchbench.benchmark.catalogue.spec import SearchSpace

# No setting costs much more than the entry's default (the plan counts every candidate at
# the default's cost; the tuned twin's goal is under 10x the default run): the forests keep
# their number of trees and try at most 0.2 of the features per split (about twice sqrt(d)
# on a hundred features), the boosters at most their default rounds and depth.
_FOREST: SearchSpace = {
    "max_features": ("sqrt", "log2", 0.2),
    "min_samples_leaf": (1, 2, 4),
    "criterion": ("gini", "entropy"),
    "class_weight": (None, "balanced"),
}

SEARCH_SPACES: MappingProxyType[str, SearchSpace] = MappingProxyType(
    {
        "rf": _FOREST,
        "extra-trees": _FOREST,
        "xgb": {
            "estimator__n_estimators": (150, 300),
            "estimator__max_depth": (3, 4, 6),
            "estimator__learning_rate": (0.05, 0.1, 0.2),
            "estimator__subsample": (0.7, 0.9),
            "estimator__colsample_bytree": (0.4, 0.6, 0.8),
            "estimator__min_child_weight": (1, 3),
        },
        "hgb": {
            "max_iter": (150, 300),
            "learning_rate": (0.05, 0.1, 0.2),
            "max_leaf_nodes": (15, 31),
            "min_samples_leaf": (5, 20, 40),
            "l2_regularization": (0.0, 0.1, 1.0),
        },
        "svm-rbf": {
            "C": (1.0, 3.0, 10.0, 30.0, 100.0, 300.0),
            "gamma": ("scale", 0.002, 0.005, 0.01, 0.02, 0.05),
        },
        "logistic": {"C": (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0)},
        "mlp": {
            "hidden_layer_sizes": ((50,), (100,), (100, 50)),
            "alpha": (1e-4, 1e-3, 1e-2, 1e-1, 1.0),
            "learning_rate_init": (1e-3, 3e-3),
        },
        "ibk5-std": {
            "n_neighbors": (1, 3, 5, 7, 11, 15, 25),
            "weights": ("uniform", "distance"),
            "p": (1, 2),
        },
    }
)
