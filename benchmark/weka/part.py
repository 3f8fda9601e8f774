"""PART (``weka.classifiers.rules.PART``, 3.6): a decision list from partial C4.5 trees.

Each rule comes from a partial tree grown on the instances no earlier rule covers: the
node's split is chosen as in J48, its branches are expanded in order of increasing class
entropy, a branch whose subtree is all leaves is pruned back with C4.5's pessimistic
estimate, and expansion stops at the first branch that stays a subtree.  The leaf covering
the most weight becomes the rule; the instances it covers leave the data (those reaching
it through a missing value only in part), and the next rule is grown on the rest.  A row
is classified by the rules in order, each taking the share of the row it covers.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

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


class PARTClassifier(NanClassifier):
    """WEKA's PART rule learner with its defaults.

    Parameters
    ----------
    confidence : float
        Pruning confidence (``-C``), in (0, 0.5].
    min_instances : int
        Minimum number of instances per rule (``-M``).
    nominal_features : mapping of int to int, optional
        Nominal column index to its number of declared labels; other columns are numeric.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    nominal_ : dict of int to int
    rules_ : list of tuple
        In order: ``(conditions, counts)``, ``conditions`` a list of ``(feature, numeric,
        threshold, branch, share)`` tests (``share``: the fraction of a row with a missing
        value that goes down ``branch``), ``counts`` the class weights of the rule's leaf.
    """

    def __init__(
        self,
        confidence: float = 0.25,
        min_instances: int = 2,
        nominal_features: Mapping[int, int] | None = None,
    ) -> None:
        self.confidence = confidence
        self.min_instances = min_instances
        self.nominal_features = nominal_features

    def fit(self, X: Any, y: Any) -> PARTClassifier:
        """Learn the decision list from ``X`` (n_samples, n_features) and labels ``y``."""
        check_pruning(self.confidence, self.min_instances)
        X, codes, nominal = check_training_data(self, X, y)
        self.nominal_ = nominal
        builder = _RuleBuilder(
            X,
            codes,
            len(self.classes_),
            nominal,
            self.min_instances,
            float(np.float32(self.confidence)),
        )
        rows, weight = np.arange(X.shape[0]), np.ones(X.shape[0])
        self.rules_: list[tuple[list[tuple[int, bool, float, int, float]], np.ndarray]] = []
        while rows.size and len(self.rules_) <= X.shape[0]:
            root = builder.partial_tree(rows, weight, leaf=False)
            conditions, counts = _rule(root)
            self.rules_.append((conditions, counts))
            covered = _coverage(X[rows], conditions)
            keep = covered < 1 - SMALL
            rows, weight = rows[keep], weight[keep] * (1 - covered[keep])
        return self

    def predict_proba(self, X: Any) -> np.ndarray:
        """Class probabilities of shape (n_samples, n_classes), columns as ``classes_``."""
        check_is_fitted(self)
        X = check_test_data(self, X)
        out = np.zeros((X.shape[0], len(self.classes_)))
        remaining = np.ones(X.shape[0])
        for conditions, counts in self.rules_:
            covered = _coverage(X, conditions)
            total = counts.sum()
            leaf = counts / total if total > SMALL else np.zeros_like(counts)
            out += (remaining * covered)[:, None] * leaf
            remaining = np.where(covered > SMALL, remaining * (1 - covered), remaining)
        sums = out.sum(axis=1, keepdims=True)
        return np.asarray(np.where(sums > 0, out / np.where(sums > 0, sums, 1), 1 / out.shape[1]))


def _coverage(X: np.ndarray, conditions: list[tuple[int, bool, float, int, float]]) -> np.ndarray:
    """Share of each row a rule covers: 1 if it passes every test, the branch share for
    each test on a missing value, 0 if it fails one (``ClassifierDecList.weight``)."""
    covered = np.ones(X.shape[0])
    for feature, numeric, threshold, branch, share in conditions:
        values = X[:, feature]
        missing = np.isnan(values)
        if numeric:
            passes = (values <= threshold) if branch == 0 else (values > threshold)
        else:
            passes = values == branch
        covered *= np.where(missing, share, passes.astype(np.float64))
    return covered


@dataclass
class _PartialNode:
    counts: np.ndarray
    split: Split | None = None
    shares: np.ndarray | None = None
    children: list[_PartialNode | None] = field(default_factory=list)
    chosen: int = 0

    @property
    def is_leaf(self) -> bool:
        return self.split is None


def _rule(node: _PartialNode) -> tuple[list[tuple[int, bool, float, int, float]], np.ndarray]:
    """The conditions on the path to the chosen leaf, and that leaf's class weights."""
    conditions = []
    while not node.is_leaf:
        assert node.split is not None and node.shares is not None
        split, b = node.split, node.chosen
        conditions.append((split.feature, split.numeric, split.threshold, b, float(node.shares[b])))
        child = node.children[b]
        assert child is not None
        node = child
    return conditions, node.counts


class _RuleBuilder(SplitSelector):
    """Grows partial trees (``C45PruneableDecList.buildDecList``)."""

    def __init__(
        self,
        X: np.ndarray,
        codes: np.ndarray,
        n_classes: int,
        nominal: dict[int, int],
        min_instances: float,
        confidence: float,
    ) -> None:
        super().__init__(X, codes, n_classes, nominal, min_instances, True)
        self.confidence = confidence

    def partial_tree(self, rows: np.ndarray, weight: np.ndarray, *, leaf: bool) -> _PartialNode:
        counts = self.class_counts(rows, weight)
        node = _PartialNode(counts)
        split = None if leaf else self.select(rows, weight, counts)
        if split is None:
            return node
        parts = self.partition(split, rows, weight)
        bags = np.array([self.class_counts(r, w) for r, w in parts])
        totals = bags.sum(axis=1)
        node.split, node.shares = split, totals / totals.sum()
        node.children = [None] * len(parts)
        expanded = 0
        while True:
            expanded += 1
            index = self._lowest_entropy(node, bags)
            if index < 0:
                for b, (r, w) in enumerate(parts):
                    if node.children[b] is None:
                        node.children[b] = self.partial_tree(r, w, leaf=True)
                if expanded < 2:
                    return _PartialNode(counts)
                break
            child = self.partial_tree(*parts[index], leaf=False)
            node.children[index] = child
            if not (expanded < len(parts) and child.is_leaf):
                break
        all_leaves = all(c is not None and c.is_leaf for c in node.children)
        if all_leaves and self._leaf_errors(counts) - (self._tree_errors(node) + 0.1) < SMALL:
            return _PartialNode(counts)  # pruned back, as C4.5 would (``pruneEnd``)
        node.chosen = self._largest_leaf(node)
        return node

    def _lowest_entropy(self, node: _PartialNode, bags: np.ndarray) -> int:
        """The unexpanded branch of lowest class entropy (``chooseIndex``), -1 if none."""
        best, lowest = -1, np.inf
        for b, child in enumerate(node.children):
            if child is not None:
                continue
            total = bags[b].sum()
            if total < self.min_instances - SMALL:
                entropy = np.inf
            else:
                entropy = float((x_log(total) - sum(x_log(c) for c in bags[b])) / total)
            if entropy < SMALL:
                return b
            if entropy < lowest - SMALL:
                best, lowest = b, entropy
        return best

    def _leaf_errors(self, counts: np.ndarray) -> float:
        total = counts.sum()
        if abs(total) < SMALL:
            return 0.0
        errors = training_errors(counts)
        return errors + added_errors(total, errors, self.confidence)

    def _tree_errors(self, node: _PartialNode) -> float:
        return sum(self._leaf_errors(c.counts) for c in node.children if c is not None)

    @staticmethod
    def _largest_leaf(node: _PartialNode) -> int:
        """The branch whose rule covers the most weight (``chooseLastIndex``)."""
        best, largest = 0, -np.inf
        for b, child in enumerate(node.children):
            if child is None:
                continue
            covered = _covered_weight(child)
            if covered - largest > SMALL:
                best, largest = b, covered
        return best


def _covered_weight(node: _PartialNode) -> float:
    """Weight of the leaf a subtree's rule ends in (minus ``getSizeOfBranch``)."""
    while not node.is_leaf:
        child = node.children[node.chosen]
        assert child is not None
        node = child
    return float(node.counts.sum())


def x_log(x: float) -> float:
    """``x * log2(x)``, 0 below 1e-6."""
    return float(x * np.log2(x)) if x >= 1e-6 else 0.0
