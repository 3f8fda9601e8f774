"""Fayyad and Irani's MDL discretisation, as WEKA's supervised ``Discretize`` filter does it.

Cut points are chosen recursively: the boundary between two distinct sorted values that
minimises the class entropy of the two halves is kept when its information gain passes
the minimum description length test; each half is then cut again.  WEKA's defaults are
followed: Fayyad and Irani's criterion (not Kononenko's) and the "worse" encoding, which
counts every position as a candidate cut point.
"""

from __future__ import annotations

import numpy as np


def entropy_bits(counts: np.ndarray) -> np.ndarray:
    """Entropy in bits of class counts along the last axis; shape ``counts.shape[:-1]``."""
    total = counts.sum(axis=-1)
    terms = _x_log2_x(counts).sum(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = (_x_log2_x(total) - terms) / total
    return np.where(total > 0, out, 0.0)


def _x_log2_x(x: np.ndarray) -> np.ndarray:
    """``x * log2(x)``, 0 below 1e-6 (as WEKA's entropy functions do)."""
    x = np.asarray(x, dtype=np.float64)
    safe = np.where(x < 1e-6, 1.0, x)
    return np.where(x < 1e-6, 0.0, x * np.log2(safe))


def mdl_cut_points(values: np.ndarray, codes: np.ndarray, n_classes: int) -> np.ndarray:
    """Cut points of one numeric attribute.

    Parameters
    ----------
    values : ndarray of shape (n_samples,)
        The attribute; NaN values are left out.
    codes : ndarray of shape (n_samples,)
        Class codes ``0..n_classes-1``.
    n_classes : int

    Returns
    -------
    ndarray of shape (n_cuts,)
        Increasing cut points (midpoints between adjacent distinct values).  A value ``v``
        falls in interval ``searchsorted(cuts, v, side="left")`` (``v <= cuts[j]`` is
        interval ``j``), as in WEKA.
    """
    known = ~np.isnan(values)
    order = np.argsort(values[known], kind="stable")
    v = values[known][order]
    indicator = np.zeros((v.size, n_classes))
    indicator[np.arange(v.size), codes[known][order]] = 1.0
    cumulative = np.vstack([np.zeros((1, n_classes)), np.cumsum(indicator, axis=0)])
    cuts: list[float] = []
    _cut(v, cumulative, 0, v.size, cuts)
    return np.asarray(sorted(cuts), dtype=np.float64)


def _cut(v: np.ndarray, cumulative: np.ndarray, first: int, stop: int, cuts: list[float]) -> None:
    n = stop - first
    if n < 2:
        return
    prior = cumulative[stop] - cumulative[first]
    left = cumulative[first + 1 : stop] - cumulative[first]  # after rows first..i, (n-1, C)
    right = prior - left
    boundary = v[first : stop - 1] < v[first + 1 : stop]
    if not boundary.any():
        return
    conditional = (
        left.sum(axis=1) * entropy_bits(left) + right.sum(axis=1) * entropy_bits(right)
    ) / n
    conditional = np.where(boundary, conditional, np.inf)
    best = int(np.argmin(conditional))
    prior_entropy = float(entropy_bits(prior))
    if not conditional[best] < prior_entropy:
        return
    if not _fayyad_irani_accepts(prior, left[best], right[best], n, n - 1):
        return
    _cut(v, cumulative, first, first + best + 1, cuts)
    cuts.append((v[first + best] + v[first + best + 1]) / 2.0)
    _cut(v, cumulative, first + best + 1, stop, cuts)


def _fayyad_irani_accepts(
    prior: np.ndarray, left: np.ndarray, right: np.ndarray, n: int, n_cut_points: int
) -> bool:
    prior_entropy = float(entropy_bits(prior))
    left_entropy, right_entropy = float(entropy_bits(left)), float(entropy_bits(right))
    conditional = (left.sum() * left_entropy + right.sum() * right_entropy) / n
    gain = prior_entropy - conditional
    k, k_left, k_right = (int(np.count_nonzero(c > 0)) for c in (prior, left, right))
    delta = np.log2(3.0**k - 2) - (
        k * prior_entropy - k_right * right_entropy - k_left * left_entropy
    )
    return bool(gain > (np.log2(n_cut_points) + delta) / n)
