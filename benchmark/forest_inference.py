"""Class probabilities of a fitted random or extra-trees forest, tree by tree in this thread.

scikit-learn's ``ForestClassifier.predict_proba`` hands every tree to joblib and adds the
trees' answers under a lock: right for thousands of rows, but on the one instance of a
live touch or a served request that machinery costs several times the trees themselves
(`perf/serve.py` measures it).  :func:`forest_proba` walks the trees directly,
computing what scikit-learn computes (each tree's leaf class fractions, normalised, then
averaged), and declines (``None``) whenever its shortcut would not be exactly that.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.sparse import issparse
from sklearn.ensemble._forest import ForestClassifier
from sklearn.pipeline import Pipeline


def forest_proba(estimator: Any, X: np.ndarray) -> np.ndarray | None:
    """What ``estimator.predict_proba(X)`` returns, for a forest or a pipeline ending in one.

    Parameters
    ----------
    estimator : fitted estimator
        A single-output :class:`~sklearn.ensemble.RandomForestClassifier` or
        :class:`~sklearn.ensemble.ExtraTreesClassifier` (not parallel), or a
        :class:`~sklearn.pipeline.Pipeline` whose last step is one.
    X : ndarray of shape (n_instances, n_features)

    Returns
    -------
    ndarray of shape (n_instances, n_classes) or None
        ``None`` for any other estimator, or input the shortcut does not take (sparse,
        the wrong width, missing values): call ``predict_proba`` then.
    """
    steps = estimator.steps if isinstance(estimator, Pipeline) else [("", estimator)]
    forest = steps[-1][1]
    if (
        not isinstance(forest, ForestClassifier)
        or forest.n_outputs_ != 1
        or forest.n_jobs not in (None, 1)
    ):
        return None
    transformed = X
    for _, step in steps[:-1]:
        if step is not None and step != "passthrough":
            transformed = step.transform(transformed)
    if issparse(transformed):
        return None
    rows = np.ascontiguousarray(transformed, dtype=np.float32)
    if rows.ndim != 2 or rows.shape[1] != forest.n_features_in_ or np.isnan(rows).any():
        return None  # scikit-learn's own checks say what is wrong, or route missing values
    n_classes = int(forest.n_classes_)
    total = np.zeros((rows.shape[0], n_classes))
    for tree in forest.estimators_:
        proba = tree.tree_.predict(rows)[:, :n_classes]
        normaliser = proba.sum(axis=1)[:, np.newaxis]
        normaliser[normaliser == 0.0] = 1.0
        total += proba / normaliser
    total /= len(forest.estimators_)
    return total
