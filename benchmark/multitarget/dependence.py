"""Dependence between target variables and the trees and partitions built on it.

- :func:`mutual_information_matrix`: marginal dependence, used by BCC (MEKA's
  ``StatUtils.margDepMatrix(D, "I")``, multi-target capable).
- :func:`maximum_spanning_tree` and :func:`orient_tree`: the Chow-Liu tree of BCC.
- :func:`error_dependence_matrix`: conditional dependence from the errors of independent
  classifiers (MEKA's LEAD-style chi-squared test, ``StatUtils.condDepMatrix``), used by SCC.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np

#: Chi-squared critical value at p = 0.10 with two degrees of freedom (three error kinds).
CHI2_CRITICAL_2DOF = 4.605


def mutual_information_matrix(Y: np.ndarray, n_classes: Sequence[int]) -> np.ndarray:
    """Mutual information between every pair of targets, over all value pairs.

    ``I(Y_j; Y_k) = sum_{a, b} p(a, b) log(p(a, b) / (p(a) p(b)))`` with empirical
    probabilities (natural log, terms with ``p(a, b) = 0`` contribute 0; MEKA adds 1e-4 to
    every count instead, which leaves the tree unchanged but for ties).

    Parameters
    ----------
    Y : ndarray of shape (n_samples, n_targets), int codes
    n_classes : sequence of int, length n_targets

    Returns
    -------
    ndarray of shape (n_targets, n_targets)
        Symmetric, zero diagonal, in nats.
    """
    n_samples, n_targets = Y.shape
    information = np.zeros((n_targets, n_targets))
    if n_samples == 0:
        return information
    for j in range(n_targets):
        for k in range(j + 1, n_targets):
            counts = np.bincount(
                Y[:, j] * n_classes[k] + Y[:, k], minlength=n_classes[j] * n_classes[k]
            ).reshape(n_classes[j], n_classes[k])
            joint = counts / n_samples
            independent = np.outer(joint.sum(axis=1), joint.sum(axis=0))
            seen = joint > 0
            value = float(np.sum(joint[seen] * np.log(joint[seen] / independent[seen])))
            information[j, k] = information[k, j] = max(value, 0.0)
    return information


def maximum_spanning_tree(weights: np.ndarray) -> list[tuple[int, int]]:
    """Edges of a maximum-weight spanning tree of a complete graph (Prim's algorithm).

    Parameters
    ----------
    weights : ndarray of shape (n_nodes, n_nodes)
        Symmetric edge weights; the diagonal is ignored.

    Returns
    -------
    list of (int, int)
        ``n_nodes - 1`` edges ``(already_in_tree, newly_added)``; ties go to the lowest
        node index, so the tree is deterministic.
    """
    n_nodes = weights.shape[0]
    if n_nodes == 0:
        return []
    in_tree = np.zeros(n_nodes, dtype=bool)
    in_tree[0] = True
    best_weight = np.where(in_tree, -np.inf, weights[0]).astype(np.float64)
    best_link = np.zeros(n_nodes, dtype=np.int64)
    edges: list[tuple[int, int]] = []
    for _ in range(n_nodes - 1):
        candidates = np.where(in_tree, -np.inf, best_weight)
        node = int(np.argmax(candidates))
        edges.append((int(best_link[node]), node))
        in_tree[node] = True
        closer = ~in_tree & (weights[node] > best_weight)
        best_weight[closer] = weights[node][closer]
        best_link[closer] = node
    return edges


def orient_tree(
    edges: Sequence[tuple[int, int]], n_nodes: int, root: int
) -> tuple[np.ndarray, np.ndarray]:
    """Direct an undirected tree's edges away from ``root``.

    Parameters
    ----------
    edges : sequence of (int, int)
        ``n_nodes - 1`` undirected edges forming a tree.
    n_nodes : int
    root : int

    Returns
    -------
    parents : ndarray of shape (n_nodes,), int64
        Parent of each node, -1 for the root.
    order : ndarray of shape (n_nodes,), int64
        Breadth-first order from the root: every node comes after its parent.
    """
    neighbours: list[list[int]] = [[] for _ in range(n_nodes)]
    for a, b in edges:
        neighbours[a].append(b)
        neighbours[b].append(a)
    parents = np.full(n_nodes, -1, dtype=np.int64)
    visited = np.zeros(n_nodes, dtype=bool)
    visited[root] = True
    order = [root]
    queue = deque([root])
    while queue:
        node = queue.popleft()
        for child in sorted(neighbours[node]):
            if not visited[child]:
                visited[child] = True
                parents[child] = node
                order.append(child)
                queue.append(child)
    return parents, np.asarray(order, dtype=np.int64)


def error_dependence_matrix(Y_true: np.ndarray, Y_pred: np.ndarray) -> np.ndarray:
    """Chi-squared test of whether two targets' errors co-occur, minus its critical value.

    For every pair of targets, the instances fall into three kinds: both predicted wrong,
    one wrong, both right.  Under independence of the two targets' errors the expected
    counts follow from each target's error rate; the statistic
    ``sum (observed - expected)^2 / expected`` minus :data:`CHI2_CRITICAL_2DOF` is positive
    when the errors are dependent at p = 0.10 (MEKA's ``StatUtils.condDepMatrix``).

    Parameters
    ----------
    Y_true, Y_pred : ndarray of shape (n_samples, n_targets), int codes

    Returns
    -------
    ndarray of shape (n_targets, n_targets)
        Symmetric, diagonal ``-CHI2_CRITICAL_2DOF``; higher means more dependent.
    """
    n_samples, n_targets = Y_true.shape
    wrong = Y_true != Y_pred
    error_rate = wrong.mean(axis=0) if n_samples else np.zeros(n_targets)
    statistic = np.zeros((n_targets, n_targets))
    for j in range(n_targets):
        for k in range(j + 1, n_targets):
            observed = np.array(
                [
                    np.sum(wrong[:, j] & wrong[:, k]),
                    np.sum(wrong[:, j] ^ wrong[:, k]),
                    np.sum(~wrong[:, j] & ~wrong[:, k]),
                ],
                dtype=np.float64,
            )
            e_j, e_k = error_rate[j], error_rate[k]
            expected = n_samples * np.array(
                [e_j * e_k, e_j * (1 - e_k) + (1 - e_j) * e_k, (1 - e_j) * (1 - e_k)]
            )
            defined = expected > 0
            value = np.sum((observed[defined] - expected[defined]) ** 2 / expected[defined])
            statistic[j, k] = statistic[k, j] = value
    return statistic - CHI2_CRITICAL_2DOF
