"""A tree with a logistic regression in every leaf: the nearest we defend to WEKA's LMT.

WEKA's ``LMT`` (Landwehr, Hall and Frank 2005) grows a C4.5-style tree and fits a
LogitBoost logistic model in every node, each refining its parent's, then prunes with
CART's cost-complexity rule.  :class:`LogisticModelTree` keeps the idea that matters for
touch data (axis-aligned splits first, then a linear model where the split has separated
the regimes) with parts scikit-learn already has: an entropy tree with large leaves
decides the regions, and an L2 logistic regression on standardised features is fitted in
each region.  A leaf that saw a single class, or too few instances for a model, answers
the Laplace-corrected class frequencies of its instances.  It carries no WEKA name: the
node models are not boosted and are not refined from the parent's.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.linear_model import LogisticRegression
from sklearn.preprocessing import StandardScaler
from sklearn.tree import DecisionTreeClassifier
from sklearn.utils.validation import check_is_fitted, validate_data


class LogisticModelTree(ClassifierMixin, BaseEstimator):
    """An entropy tree whose leaves hold logistic regressions.

    Parameters
    ----------
    min_samples_leaf : int, default=50
        The fewest training instances in a leaf, so that every leaf can fit a model.
    max_depth : int or None, default=None
        Depth limit of the tree (``None``: grown until ``min_samples_leaf`` stops it).
    C : float, default=1.0
        Inverse L2 regularisation strength of the leaf models.
    max_iter : int, default=300
        Iterations of the leaf models' solver.
    random_state : int or None, default=None
        Seed of the tree's tie-breaking among equally good splits.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
        The labels seen in training, sorted.
    tree_model_ : DecisionTreeClassifier
        The fitted tree that routes an instance to its leaf.
    scaler_ : StandardScaler
        Standardisation fitted on the whole training set, applied before the leaf models.
    leaf_ids_ : ndarray of shape (n_leaves,)
        The tree's node ids of its leaves, sorted.
    leaf_models_ : list of LogisticRegression or None, length n_leaves
        The model of each leaf, ``None`` where the leaf answers its class frequencies.
    leaf_priors_ : ndarray of shape (n_leaves, n_classes)
        Laplace-corrected class frequencies of each leaf's training instances.
    """

    def __init__(
        self,
        min_samples_leaf: int = 50,
        max_depth: int | None = None,
        C: float = 1.0,
        max_iter: int = 300,
        random_state: int | None = None,
    ) -> None:
        self.min_samples_leaf = min_samples_leaf
        self.max_depth = max_depth
        self.C = C
        self.max_iter = max_iter
        self.random_state = random_state

    def fit(self, X: np.ndarray, y: np.ndarray) -> LogisticModelTree:
        """Fit on ``X`` of shape (n_samples, n_features) and labels ``y`` (n_samples,)."""
        X, y = validate_data(self, X, y, dtype=np.float64)
        self.classes_, codes = np.unique(y, return_inverse=True)
        n_classes = len(self.classes_)
        self.tree_model_ = DecisionTreeClassifier(
            criterion="entropy",
            min_samples_leaf=self.min_samples_leaf,
            max_depth=self.max_depth,
            random_state=self.random_state,
        ).fit(X, codes)
        self.scaler_ = StandardScaler().fit(X)
        standardised = self.scaler_.transform(X)
        leaves = self.tree_model_.apply(X)
        self.leaf_ids_ = np.unique(leaves)
        self.leaf_models_: list[LogisticRegression | None] = []
        self.leaf_priors_ = np.empty((len(self.leaf_ids_), n_classes))
        for index, leaf in enumerate(self.leaf_ids_):
            in_leaf = leaves == leaf
            counts = np.bincount(codes[in_leaf], minlength=n_classes)
            self.leaf_priors_[index] = (counts + 1.0) / (counts.sum() + n_classes)
            model = None
            if np.count_nonzero(counts) > 1:
                model = LogisticRegression(C=self.C, max_iter=self.max_iter)
                model.fit(standardised[in_leaf], codes[in_leaf])
            self.leaf_models_.append(model)
        return self

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Probabilities of shape (n_samples, n_classes), columns as ``classes_``."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, dtype=np.float64)
        leaf_index = np.searchsorted(self.leaf_ids_, self.tree_model_.apply(X))
        standardised = self.scaler_.transform(X)
        probabilities = self.leaf_priors_[leaf_index]
        for index, model in enumerate(self.leaf_models_):
            rows = np.flatnonzero(leaf_index == index)
            if model is None or rows.size == 0:
                continue
            leaf_probabilities = np.zeros((rows.size, len(self.classes_)))
            leaf_probabilities[:, model.classes_] = model.predict_proba(standardised[rows])
            probabilities[rows] = leaf_probabilities
        return probabilities

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Labels of shape (n_samples,)."""
        return self.classes_[np.argmax(self.predict_proba(X), axis=1)]
