"""C4.5 as WEKA's J48 (``weka.classifiers.trees.J48``, 3.6) grows and prunes it.

* splits: multiway on a nominal attribute (one branch per declared label), binary
  ``<= threshold`` on a numeric one; the threshold is the largest training value below
  the midpoint of the best cut, as in C4.5;
* choice: the highest gain ratio among attributes whose information gain is at least the
  average (minus 1e-3); numeric gains pay Quinlan's MDL correction log2(#cuts) / n;
  every branch of a numeric cut holds at least ``min(25, max(min_instances,
  0.1 * n / n_classes))`` instances and at least two branches of a nominal split hold
  ``min_instances``;
* missing values: an instance with a missing test value goes down every branch with a
  fractional weight proportional to the branch's known weight, in training and in
  prediction (C4.5's fractional instances; see :mod:`benchmark.weka._splits`);
* after growing, subtrees that do not reduce training errors are collapsed, then
  pessimistic error-based pruning with confidence ``confidence`` replaces subtrees by
  leaves or by their largest branch (subtree raising).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from sklearn.utils.validation import check_is_fitted

from touchbench.benchmark.weka._data import NanClassifier, check_test_data, check_training_data
from touchbench.benchmark.weka._splits import (
    SMALL,
    Split,
    SplitSelector,
    added_errors,
    check_pruning,
    training_errors,
)


class C45Classifier(NanClassifier):
    """C4.5 decision tree with WEKA J48's defaults and behaviour.

    Parameters
    ----------
    confidence : float
        Confidence factor of pessimistic pruning (``-C``), in (0, 0.5].
    min_instances : int
        Minimum number of instances per branch (``-M``).
    pruned : bool
        Prune after growing (``False`` is ``-U``).
    subtree_raising : bool
        Consider replacing a subtree by its largest branch while pruning (``False`` is
        ``-S``).
    collapse : bool
        Collapse subtrees that do not reduce training errors (``False`` is WEKA 3.7's
        ``-O``; WEKA 3.6 always collapses).
    mdl_correction : bool
        Penalise numeric cuts by log2(#candidate cuts) / n (``False`` is WEKA 3.7's
        ``-J``; WEKA 3.6 always does).
    laplace : bool
        Laplace-smoothed leaf probabilities (``-A``); predictions change only where a
        missing value mixes several leaves.
    nominal_features : mapping of int to int, optional
        Nominal column index to its number of declared labels; other columns are numeric.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    nominal_ : dict of int to int
    feature_ : ndarray of shape (n_nodes,), int
        Attribute tested at each node, -1 at a leaf.  Node 0 is the root.
    threshold_ : ndarray of shape (n_nodes,)
        ``<=`` threshold of numeric tests (NaN otherwise).
    children_ : ndarray of shape (n_nodes, max_branches), int
        Child node per branch, -1 past a node's last branch.
    counts_ : ndarray of shape (n_nodes, n_classes)
        Training class weights at each node.
    empty_ : ndarray of shape (n_nodes,), bool
        Leaves that received no training instance when grown.
    """

    def __init__(
        self,
        confidence: float = 0.25,
        min_instances: int = 2,
        pruned: bool = True,
        subtree_raising: bool = True,
        collapse: bool = True,
        mdl_correction: bool = True,
        laplace: bool = False,
        nominal_features: Mapping[int, int] | None = None,
    ) -> None:
        self.confidence = confidence
        self.min_instances = min_instances
        self.pruned = pruned
        self.subtree_raising = subtree_raising
        self.collapse = collapse
        self.mdl_correction = mdl_correction
        self.laplace = laplace
        self.nominal_features = nominal_features

    def fit(self, X: object, y: object) -> C45Classifier:
        """Grow and prune the tree on ``X`` (n_samples, n_features) and labels ``y``."""
        check_pruning(self.confidence, self.min_instances)
        X, codes, nominal = check_training_data(self, X, y)
        self.nominal_ = nominal
        grower = _Grower(
            X, codes, len(self.classes_), nominal, self.min_instances, self.mdl_correction
        )
        root = grower.grow(np.arange(X.shape[0]), np.ones(X.shape[0]))
        if self.collapse:
            _collapse(root)
        if self.pruned:
            _Pruner(grower, float(np.float32(self.confidence)), self.subtree_raising).prune(root)
        self._store(root)
        return self

    def _store(self, root: _Node) -> None:
        nodes: list[_Node] = []
        stack = [root]
        while stack:
            node = stack.pop()
            nodes.append(node)
            stack.extend(reversed(node.children))
        index = {id(node): i for i, node in enumerate(nodes)}
        width = max([len(n.children) for n in nodes] + [1])
        self.feature_ = np.array([n.split.feature if n.split else -1 for n in nodes])
        self.threshold_ = np.array(
            [n.split.threshold if n.split else np.nan for n in nodes], dtype=np.float64
        )
        self.children_ = np.full((len(nodes), width), -1, dtype=np.int64)
        for i, node in enumerate(nodes):
            self.children_[i, : len(node.children)] = [index[id(c)] for c in node.children]
        self.counts_ = np.array([n.counts for n in nodes], dtype=np.float64)
        self.empty_ = np.array([n.empty for n in nodes], dtype=bool)

    @property
    def n_leaves_(self) -> int:
        """Number of leaves."""
        check_is_fitted(self)
        return int(np.count_nonzero(self.feature_ < 0))

    def predict_proba(self, X: object) -> np.ndarray:
        """Class probabilities of shape (n_samples, n_classes), columns as ``classes_``.

        Rows whose branches all end in leaves emptied by subtree raising (WEKA leaves
        them unclassified) get the root's class distribution.
        """
        check_is_fitted(self)
        X = check_test_data(self, X)
        out = np.zeros((X.shape[0], len(self.classes_)))
        self._descend(X, 0, np.arange(X.shape[0]), np.ones(X.shape[0]), out)
        total = out.sum(axis=1)
        lost = total <= 0
        out[lost] = self._distribution(0)
        total[lost] = 1.0
        return np.asarray(out / total[:, None])

    def _distribution(self, node: int) -> np.ndarray:
        counts = self.counts_[node]
        total = counts.sum()
        if self.laplace:
            return np.asarray((counts + 1.0) / (total + counts.size))
        return counts / total if total > SMALL else np.zeros_like(counts)

    def _descend(
        self, X: np.ndarray, node: int, rows: np.ndarray, weight: np.ndarray, out: np.ndarray
    ) -> None:
        """Add ``weight`` times the class distribution reached by ``rows`` below ``node``."""
        feature = self.feature_[node]
        if feature < 0:
            out[rows] += weight[:, None] * self._distribution(node)
            return
        children = self.children_[node][self.children_[node] >= 0]
        values = X[rows, feature]
        missing = np.isnan(values)
        if feature in self.nominal_:
            branch = np.where(missing, -1, values).astype(np.int64)
        else:
            branch = np.where(values <= self.threshold_[node], 0, 1)
        totals = self.counts_[children].sum(axis=1)
        share = totals / totals.sum()
        for b, child in enumerate(children):
            chosen = ~missing & (branch == b)
            if self.empty_[child]:
                # WEKA: the parent's class distribution within that (empty) branch
                fallback = self._distribution(child) if totals[b] > SMALL else None
                if fallback is None:
                    fallback = self._distribution(node)
                out[rows[chosen]] += weight[chosen, None] * fallback
                continue
            self._descend(X, child, rows[chosen], weight[chosen], out)
            if missing.any():
                self._descend(X, child, rows[missing], weight[missing] * share[b], out)


# Growing ------------------------------------------------------------------------------


@dataclass
class _Node:
    """A node while the tree is built and pruned (WEKA's ``C45PruneableClassifierTree``)."""

    rows: np.ndarray
    weight: np.ndarray
    counts: np.ndarray
    split: Split | None = None
    children: list[_Node] = field(default_factory=list)
    empty: bool = False

    @property
    def is_leaf(self) -> bool:
        return self.split is None

    def make_leaf(self) -> None:
        self.split, self.children = None, []


class _Grower(SplitSelector):
    """Grows the unpruned tree (``C45PruneableClassifierTree.buildTree``)."""

    def grow(self, rows: np.ndarray, weight: np.ndarray) -> _Node:
        counts = self.class_counts(rows, weight)
        node = _Node(rows, weight, counts)
        split = self.select(rows, weight, counts)
        if split is None:
            node.empty = abs(counts.sum()) < SMALL
            return node
        node.split = split
        node.children = [self.grow(r, w) for r, w in self.partition(split, rows, weight)]
        return node


# Collapsing and pruning ---------------------------------------------------------------


def _subtree_training_errors(node: _Node) -> float:
    """Training errors of the leaves below ``node``."""
    if node.is_leaf:
        return training_errors(node.counts)
    return sum(_subtree_training_errors(child) for child in node.children)


def _collapse(node: _Node) -> None:
    """Turn a subtree into a leaf when it does not reduce training errors."""
    if node.is_leaf:
        return
    if _subtree_training_errors(node) >= training_errors(node.counts) - 1e-3:
        node.make_leaf()
        return
    for child in node.children:
        _collapse(child)


class _Pruner:
    """Error-based pruning with subtree raising (``C45PruneableClassifierTree.prune``)."""

    def __init__(self, grower: _Grower, confidence: float, raising: bool) -> None:
        self.grower, self.confidence, self.raising = grower, confidence, raising

    def estimated(self, counts: np.ndarray) -> float:
        total = counts.sum()
        if abs(total) < SMALL:
            return 0.0
        errors = training_errors(counts)
        return errors + added_errors(total, errors, self.confidence)

    def subtree_estimate(self, node: _Node) -> float:
        if node.is_leaf:
            return self.estimated(node.counts)
        return sum(self.subtree_estimate(child) for child in node.children)

    def branch_estimate(self, node: _Node, rows: np.ndarray, weight: np.ndarray) -> float:
        """Estimated errors of the subtree on other data (``getEstimatedErrorsForBranch``)."""
        if node.is_leaf:
            return self.estimated(self.grower.class_counts(rows, weight))
        assert node.split is not None
        parts = self.grower.partition(node.split, rows, weight)
        return sum(
            self.branch_estimate(child, r, w)
            for child, (r, w) in zip(node.children, parts, strict=True)
        )

    def redistribute(self, node: _Node, rows: np.ndarray, weight: np.ndarray) -> None:
        """Give ``node``'s subtree new training data (``newDistribution``)."""
        node.rows, node.weight = rows, weight
        node.counts = self.grower.class_counts(rows, weight)
        if node.is_leaf:
            if abs(weight.sum()) >= SMALL:
                node.empty = False
            return
        assert node.split is not None
        parts = self.grower.partition(node.split, rows, weight)
        for child, (r, w) in zip(node.children, parts, strict=True):
            self.redistribute(child, r, w)

    def prune(self, node: _Node) -> None:
        if node.is_leaf:
            return
        for child in node.children:
            self.prune(child)
        branch_weights = [child.counts.sum() for child in node.children]
        largest = 0
        for b, w in enumerate(branch_weights):  # WEKA's maxBag: the last of equal maxima
            if w - branch_weights[largest] > -SMALL:
                largest = b
        if self.raising:
            largest_errors = self.branch_estimate(node.children[largest], node.rows, node.weight)
        else:
            largest_errors = np.inf
        leaf_errors = self.estimated(node.counts)
        tree_errors = self.subtree_estimate(node)
        if (
            leaf_errors - (tree_errors + 0.1) < SMALL
            and leaf_errors - (largest_errors + 0.1) < SMALL
        ):
            node.make_leaf()
            return
        if largest_errors - (tree_errors + 0.1) < SMALL:
            raised = node.children[largest]
            node.split, node.children = raised.split, raised.children
            self.redistribute(node, node.rows, node.weight)
            self.prune(node)
