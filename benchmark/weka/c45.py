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
  prediction (C4.5's fractional instances);
* after growing, subtrees that do not reduce training errors are collapsed, then
  pessimistic error-based pruning with confidence ``confidence`` replaces subtrees by
  leaves or by their largest branch (subtree raising).

The numeric split search is vectorised: one sort per attribute and node, cumulative class
weights, every candidate cut scored at once.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy.special import ndtri
from sklearn.utils.validation import check_is_fitted

from benchmark.weka._data import NanClassifier, check_test_data, check_training_data

#: WEKA's tolerance in comparisons (``Utils.SMALL``).
SMALL = 1e-6


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
        Collapse subtrees that do not reduce training errors (``False`` is ``-O``).
    mdl_correction : bool
        Penalise numeric cuts by log2(#candidate cuts) / n (``False`` is ``-J``).
    laplace : bool
        Laplace-smoothed leaf probabilities (``-A``); predictions are unchanged.
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
        if not 0 < self.confidence <= 0.5:
            raise ValueError(f"confidence must lie in (0, 0.5], got {self.confidence!r}")
        if not isinstance(self.min_instances, int | np.integer) or self.min_instances < 1:
            raise ValueError(
                f"min_instances must be a positive integer, got {self.min_instances!r}"
            )
        X, codes, nominal = check_training_data(self, X, y)
        self.nominal_ = nominal
        grower = _Grower(X, codes, len(self.classes_), nominal, self)
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
class _Split:
    feature: int
    numeric: bool
    threshold: float
    n_branches: int


@dataclass
class _Node:
    """A node while the tree is built and pruned (WEKA's ``C45PruneableClassifierTree``)."""

    rows: np.ndarray
    weight: np.ndarray
    counts: np.ndarray
    split: _Split | None = None
    children: list[_Node] = field(default_factory=list)
    empty: bool = False

    @property
    def is_leaf(self) -> bool:
        return self.split is None

    def make_leaf(self) -> None:
        self.split, self.children = None, []


def _x_log2_x(x: np.ndarray) -> np.ndarray:
    """``x * log2(x)``, 0 below 1e-6 (WEKA's ``logFunc``)."""
    x = np.asarray(x, dtype=np.float64)
    logs = np.log2(x, out=np.zeros_like(x), where=x >= 1e-6)
    return np.asarray(x * logs)


class _Grower:
    """Grows the unpruned tree (WEKA's ``C45ModelSelection`` and ``C45Split``)."""

    def __init__(
        self,
        X: np.ndarray,
        codes: np.ndarray,
        n_classes: int,
        nominal: dict[int, int],
        params: C45Classifier,
    ) -> None:
        self.X, self.codes, self.n_classes, self.nominal = X, codes, n_classes, nominal
        self.min_instances = float(params.min_instances)
        self.mdl = params.mdl_correction
        self.numeric = np.array([c for c in range(X.shape[1]) if c not in nominal], dtype=np.intp)
        self.sorted_values = [np.unique(X[~np.isnan(X[:, c]), c]) for c in range(X.shape[1])]
        n = X.shape[0]
        self.multi_valued = self.numeric.size == 0 and all(k >= 0.3 * n for k in nominal.values())

    def class_counts(self, rows: np.ndarray, weight: np.ndarray) -> np.ndarray:
        return np.bincount(self.codes[rows], weights=weight, minlength=self.n_classes)

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

    def partition(
        self, split: _Split, rows: np.ndarray, weight: np.ndarray
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """Rows and weights of each branch; missing values go everywhere, fractionally."""
        values = self.X[rows, split.feature]
        missing = np.isnan(values)
        if split.numeric:
            branch = np.where(values <= split.threshold, 0, 1)
        else:
            branch = np.where(missing, 0, values).astype(np.intp)
        known = np.bincount(branch[~missing], weights=weight[~missing], minlength=split.n_branches)
        total = known.sum()
        share = known / total if total > SMALL else np.full(split.n_branches, 1 / split.n_branches)
        out = []
        for b in range(split.n_branches):
            chosen = ~missing & (branch == b)
            spread = missing if share[b] > SMALL else np.zeros_like(missing)
            take = chosen | spread
            out.append((rows[take], np.where(chosen, weight, weight * share[b])[take]))
        return out

    def select(self, rows: np.ndarray, weight: np.ndarray, counts: np.ndarray) -> _Split | None:
        """The best split of a node, or None for a leaf (``C45ModelSelection.selectModel``)."""
        total = counts.sum()
        if total < 2 * self.min_instances - SMALL or abs(total - counts.max()) < SMALL:
            return None
        found = self._numeric_splits(rows, weight, total)
        for feature in self.nominal:
            candidate = self._nominal_split(feature, rows, weight, total)
            if candidate is not None:
                found.append(candidate)
        if not found:
            return None
        found.sort(key=lambda item: item[2].feature)  # WEKA scans attributes in order
        counted = [
            gain
            for gain, _, split in found
            if split.numeric or self.multi_valued or split.n_branches < 0.3 * self.X.shape[0]
        ]
        if not counted:
            return None
        average = sum(counted) / len(counted)
        best, best_ratio = None, 0.0
        for gain, ratio, split in found:
            if gain >= average - 1e-3 and ratio - best_ratio > SMALL:
                best, best_ratio = split, ratio
        if best is None or abs(best_ratio) < SMALL:
            return None
        if best.numeric:
            values = self.sorted_values[best.feature]
            best.threshold = float(values[np.searchsorted(values, best.threshold, "right") - 1])
        return best

    def _nominal_split(
        self, feature: int, rows: np.ndarray, weight: np.ndarray, total: float
    ) -> tuple[float, float, _Split] | None:
        n_labels = self.nominal[feature]
        values = self.X[rows, feature]
        known = ~np.isnan(values)
        bags = np.zeros((n_labels, self.n_classes))
        np.add.at(bags, (values[known].astype(np.intp), self.codes[rows][known]), weight[known])
        if np.count_nonzero(bags.sum(axis=1) >= self.min_instances - SMALL) < 2:
            return None
        gain = _info_gain(bags[None], total)[0]
        ratio = _gain_ratio(bags[None], total, np.array([gain]))[0]
        return float(gain), float(ratio), _Split(feature, False, np.nan, n_labels)

    def _numeric_splits(
        self, rows: np.ndarray, weight: np.ndarray, total: float
    ) -> list[tuple[float, float, _Split]]:
        """The best cut of every numeric attribute at once (``C45Split`` on each).

        Each column is sorted (missing values last); cumulative class weights give the
        class distribution on each side of every candidate cut, of shape
        (n_rows - 1, n_numeric, n_classes).
        """
        columns = self.numeric
        if columns.size == 0 or rows.size < 2:
            return []
        values = self.X[np.ix_(rows, columns)]
        order = np.argsort(values, axis=0, kind="stable")
        v = np.take_along_axis(values, order, axis=0)
        missing = np.isnan(v)
        w = np.where(missing, 0.0, weight[order])
        codes = self.codes[rows][order]
        cumulative = np.stack(
            [np.cumsum(np.where(codes == c, w, 0.0), axis=0) for c in range(self.n_classes)],
            axis=2,
        )
        known_counts = cumulative[-1]  # (n_numeric, C)
        known_total = known_counts.sum(axis=1)
        n_known = np.count_nonzero(~missing, axis=0)
        min_split = 0.1 * known_total / self.n_classes
        min_split = np.where(min_split - 25 > SMALL, 25.0, min_split)
        min_split = np.where(min_split - self.min_instances < SMALL, self.min_instances, min_split)
        left = cumulative[:-1]
        left_total = left.sum(axis=2)
        right = known_counts[None] - left
        right_total = known_total[None] - left_total
        with np.errstate(invalid="ignore"):
            valid = (np.arange(v.shape[0] - 1)[:, None] < n_known - 1) & (v[:-1] + 1e-5 < v[1:])
        valid &= (left_total - min_split > -SMALL) & (right_total - min_split > -SMALL)
        valid &= ~(n_known < 2 * min_split - SMALL)
        n_candidates = np.count_nonzero(valid, axis=0)
        old = _x_log2_x(known_total) - _x_log2_x(known_counts).sum(axis=1)
        new = (
            _x_log2_x(left_total)
            + _x_log2_x(right_total)
            - _x_log2_x(left).sum(axis=2)
            - _x_log2_x(right).sum(axis=2)
        )
        numerator = (known_total / total) * (old - new)
        with np.errstate(divide="ignore", invalid="ignore"):
            gain = np.where(np.abs(numerator) < SMALL, 0.0, numerator / known_total)
        gain = np.where(valid & (gain > SMALL), gain, -np.inf)
        top = gain.max(axis=0)
        # WEKA keeps the first cut unless a later one gains more than 1e-6
        best = np.argmax(gain > (top - SMALL)[None, :], axis=0)
        chosen = np.flatnonzero(np.isfinite(top))
        i = best[chosen]
        corrected = gain[i, chosen]
        if self.mdl:
            corrected = corrected - np.log2(n_candidates[chosen]) / total
        keep = corrected >= SMALL
        chosen, i, corrected = chosen[keep], i[keep], corrected[keep]
        below, above = v[i, chosen], v[i + 1, chosen]
        thresholds = (below + above) / 2.0
        thresholds = np.where(thresholds == above, below, thresholds)
        bags = np.stack([left[i, chosen], right[i, chosen]], axis=1)
        ratios = _gain_ratio(bags, total, corrected)
        return [
            (float(g), float(r), _Split(int(columns[j]), True, float(t), 2))
            for j, g, r, t in zip(chosen, corrected, ratios, thresholds, strict=True)
        ]


def _info_gain(bags: np.ndarray, total: float) -> np.ndarray:
    """Information gain (bits per instance) of splits ``bags`` (n_splits, n_bags, C).

    ``total`` is the node's weight, unknown values included; gain is scaled by the known
    fraction as in C4.5.
    """
    per_class = bags.sum(axis=1)
    known = per_class.sum(axis=1)
    old = _x_log2_x(known) - _x_log2_x(per_class).sum(axis=1)
    new = _x_log2_x(bags.sum(axis=2)).sum(axis=1) - _x_log2_x(bags).sum(axis=(1, 2))
    numerator = (known / total) * (old - new)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = numerator / known
    return np.where(np.abs(numerator) < SMALL, 0.0, out)


def _gain_ratio(bags: np.ndarray, total: float, gains: np.ndarray) -> np.ndarray:
    """Gain ratio of splits ``bags`` (n_splits, n_bags, C) with information ``gains``."""
    per_bag = bags.sum(axis=2)
    unknown = total - per_bag.sum(axis=1)
    split_info = (
        -_x_log2_x(per_bag).sum(axis=1)
        - _x_log2_x(unknown)
        + _x_log2_x(np.full_like(unknown, total))
    )
    split_info = np.where(per_bag.sum(axis=1) > SMALL, split_info, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = gains / (split_info / total)
    return np.where(np.abs(split_info) < SMALL, 0.0, out)


# Collapsing and pruning ---------------------------------------------------------------


def _errors(counts: np.ndarray) -> float:
    """Training errors of a class distribution: its weight outside the majority class."""
    return float(counts.sum() - counts.max()) if counts.size else 0.0


def _training_errors(node: _Node) -> float:
    if node.is_leaf:
        return _errors(node.counts)
    return sum(_training_errors(child) for child in node.children)


def _collapse(node: _Node) -> None:
    """Turn a subtree into a leaf when it does not reduce training errors."""
    if node.is_leaf:
        return
    if _training_errors(node) >= _errors(node.counts) - 1e-3:
        node.make_leaf()
        return
    for child in node.children:
        _collapse(child)


def added_errors(n: float, errors: float, confidence: float) -> float:
    """Pessimistic extra errors of a leaf of weight ``n`` with ``errors`` (WEKA ``Stats.addErrs``).

    The upper limit of the binomial confidence interval at ``confidence``, with C4.5's
    interpolation below one error and its continuity correction near ``n``.
    """
    if errors < 1:
        base = n * (1 - confidence ** (1 / n))
        if errors == 0:
            return base
        return base + errors * (added_errors(n, 1, confidence) - base)
    if errors + 0.5 >= n:
        return max(n - errors, 0.0)
    z = float(ndtri(1 - confidence))
    f = (errors + 0.5) / n
    r = (f + z * z / (2 * n) + z * np.sqrt(f / n - f * f / n + z * z / (4 * n * n))) / (
        1 + z * z / n
    )
    return float(r * n - errors)


class _Pruner:
    """Error-based pruning with subtree raising (``C45PruneableClassifierTree.prune``)."""

    def __init__(self, grower: _Grower, confidence: float, raising: bool) -> None:
        self.grower, self.confidence, self.raising = grower, confidence, raising

    def estimated(self, counts: np.ndarray) -> float:
        total = counts.sum()
        if abs(total) < SMALL:
            return 0.0
        errors = _errors(counts)
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
