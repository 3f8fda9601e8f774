"""BCC: the Bayesian chain classifier, a chain shaped by a Chow-Liu tree over the targets."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.utils import check_random_state

from touchbench.benchmark.multitarget._network import TargetNetwork
from touchbench.benchmark.multitarget.dependence import (
    maximum_spanning_tree,
    mutual_information_matrix,
    orient_tree,
)
from touchbench.benchmark.targets import TargetError


class BayesianClassifierChain(TargetNetwork):
    """Bayesian chain classifier (Zaragoza et al., IJCAI 2011), as MEKA builds it.

    1. The mutual information between every pair of targets, over all their value pairs
       (the marginal dependence of the training targets).
    2. A maximum spanning tree over those weights (Chow-Liu).
    3. A root (``root``, or drawn from ``random_state``), edges directed away from it.
    4. One classifier per target, fed the features plus the one-hot code of its parent
       target (true value at training time, predicted value at prediction time);
       targets are predicted in breadth-first tree order.

    Departures from MEKA's ``multilabel.BCC`` (which the paper ran on multi-target data):
    MEKA takes the seed itself as the root index and orders nodes depth-first, here the
    root is drawn from the seed (or given) and the order is breadth-first (both are
    topological, so predictions are the same for the same root); MEKA smooths counts
    with 1e-4 in the mutual information; the parent enters one-hot encoded.

    Parameters
    ----------
    estimator : classifier
        Base classifier; cloned once per target.
    root : int, optional
        Index of the root target; default: drawn from ``random_state``.
    n_classes : sequence of int, optional
        Classes per target; default ``max(code) + 1`` per target of the training data.
    random_state : int, RandomState or None
        Seed of the root choice.

    Attributes
    ----------
    mutual_information_ : ndarray of shape (n_targets, n_targets)
        Pairwise mutual information of the training targets (nats).
    edges_ : list of (int, int)
        The undirected spanning-tree edges.
    root_ : int
        The root target.
    tree_ : ndarray of shape (n_targets,)
        Parent of each target, -1 for the root.
    order_ : ndarray of shape (n_targets,)
        Prediction order (breadth-first from the root).
    parents_ : list of tuple
        ``(tree_[t],)`` or ``()`` for the root.
    estimators_ : list of TargetClassifier
        One fitted classifier per target.
    """

    def __init__(
        self,
        estimator: Any,
        *,
        root: int | None = None,
        n_classes: Sequence[int] | None = None,
        random_state: int | np.random.RandomState | None = None,
    ) -> None:
        self.estimator = estimator
        self.root = root
        self.n_classes = n_classes
        self.random_state = random_state

    def _structure(self, X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, list[tuple[int, ...]]]:
        n_targets = Y.shape[1]
        if self.root is None:
            root = int(check_random_state(self.random_state).randint(n_targets))
        elif 0 <= self.root < n_targets:
            root = int(self.root)
        else:
            raise TargetError(f"root must be a target index 0..{n_targets - 1}, got {self.root}")
        self.mutual_information_ = mutual_information_matrix(Y, self.n_classes_)
        self.edges_ = maximum_spanning_tree(self.mutual_information_)
        self.tree_, order = orient_tree(self.edges_, n_targets, root)
        self.root_ = root
        parents: list[tuple[int, ...]] = [() if p < 0 else (int(p),) for p in self.tree_]
        return order, parents
