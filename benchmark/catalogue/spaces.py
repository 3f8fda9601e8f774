"""Search spaces of the catalogue entries that ``bench --tune`` tunes.

Each space maps an estimator parameter, named as the entry's estimator names it in
``get_params(deep=True)`` (``estimator__max_depth`` for XGBoost behind its label encoder),
to the values to try. Spaces are discrete, so that the halving search and a full grid
search (``perf/tuning.py``) search the same thing; each holds the entry's own default
values, so tuning may always keep them.
"""

from __future__ import annotations

from types import MappingProxyType

from benchmark.catalogue.spec import SearchSpace

_FOREST: SearchSpace = {
    "max_features": ("sqrt", 0.2, 0.35, 0.5),
    "min_samples_leaf": (1, 2, 4),
    "criterion": ("gini", "entropy"),
    "class_weight": (None, "balanced"),
}

SEARCH_SPACES: MappingProxyType[str, SearchSpace] = MappingProxyType(
    {
        "rf": {**_FOREST, "n_estimators": (100, 300)},
        "extra-trees": {**_FOREST, "n_estimators": (300, 600)},
        "xgb": {
            "estimator__n_estimators": (150, 300, 600),
            "estimator__max_depth": (3, 4, 6, 8),
            "estimator__learning_rate": (0.03, 0.05, 0.1, 0.2),
            "estimator__subsample": (0.7, 0.9, 1.0),
            "estimator__colsample_bytree": (0.4, 0.6, 0.8),
            "estimator__min_child_weight": (1, 3),
        },
        "hgb": {
            "max_iter": (150, 300, 600),
            "learning_rate": (0.03, 0.05, 0.1, 0.2),
            "max_leaf_nodes": (15, 31, 63),
            "min_samples_leaf": (5, 20, 40),
            "l2_regularization": (0.0, 0.1, 1.0),
        },
        "svm-rbf": {
            "C": (1.0, 3.0, 10.0, 30.0, 100.0, 300.0),
            "gamma": ("scale", 0.002, 0.005, 0.01, 0.02, 0.05),
        },
        "logistic": {"C": (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0)},
        "mlp": {
            "hidden_layer_sizes": ((100,), (200,), (100, 50), (256, 128)),
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
