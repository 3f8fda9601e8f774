"""C4.5's split selection, data partition and error estimates, shared by J48 and PART.

WEKA's ``C45ModelSelection`` and ``C45Split``: the numeric split search is vectorised (one
sort per attribute and node, cumulative class weights, every candidate cut scored at
once); an instance with a missing test value goes down every branch with a fractional
weight proportional to the branch's known weight.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtri

#: WEKA's tolerance in comparisons (``Utils.SMALL``).
SMALL = 1e-6
#: Cells (rows x columns x classes) of one array of the numeric split search: the search
#: holds about ten such float arrays, so 2**18 cells cost some 20 MB at most, whatever the
#: data's width and number of classes.
CHUNK_CELLS = 2**18


@dataclass
class Split:
    """A test on one attribute: ``feature <= threshold`` or one branch per label."""

    feature: int
    numeric: bool
    threshold: float
    n_branches: int


def x_log2_x(x: np.ndarray) -> np.ndarray:
    """``x * log2(x)``, 0 below 1e-6 (WEKA's ``logFunc``)."""
    x = np.asarray(x, dtype=np.float64)
    logs = np.log2(x, out=np.zeros_like(x), where=x >= 1e-6)
    return np.asarray(x * logs)


class SplitSelector:
    """Chooses and applies C4.5 splits on one training set (``C45ModelSelection``, ``C45Split``).

    Parameters
    ----------
    X : ndarray of shape (n_samples, n_features)
        The whole training set (thresholds are moved to its values, as WEKA does).
    codes : ndarray of shape (n_samples,)
        Class codes.
    n_classes : int
    nominal : dict of int to int
        Nominal column to its number of declared labels.
    min_instances : float
        Minimum weight per branch.
    mdl_correction : bool
        Penalise numeric cuts by log2(#candidates) / n.
    """

    def __init__(
        self,
        X: np.ndarray,
        codes: np.ndarray,
        n_classes: int,
        nominal: dict[int, int],
        min_instances: float,
        mdl_correction: bool,
    ) -> None:
        self.X, self.codes, self.n_classes, self.nominal = X, codes, n_classes, nominal
        self.min_instances = float(min_instances)
        self.mdl = mdl_correction
        self.numeric = np.array([c for c in range(X.shape[1]) if c not in nominal], dtype=np.intp)
        self.sorted_values = [np.unique(X[~np.isnan(X[:, c]), c]) for c in range(X.shape[1])]
        n = X.shape[0]
        self.multi_valued = self.numeric.size == 0 and all(k >= 0.3 * n for k in nominal.values())

    def class_counts(self, rows: np.ndarray, weight: np.ndarray) -> np.ndarray:
        return np.bincount(self.codes[rows], weights=weight, minlength=self.n_classes)

    def partition(
        self, split: Split, rows: np.ndarray, weight: np.ndarray
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

    def select(self, rows: np.ndarray, weight: np.ndarray, counts: np.ndarray) -> Split | None:
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
    ) -> tuple[float, float, Split] | None:
        n_labels = self.nominal[feature]
        values = self.X[rows, feature]
        known = ~np.isnan(values)
        bags = np.zeros((n_labels, self.n_classes))
        np.add.at(bags, (values[known].astype(np.intp), self.codes[rows][known]), weight[known])
        if np.count_nonzero(bags.sum(axis=1) >= self.min_instances - SMALL) < 2:
            return None
        gain = _info_gain(bags[None], total)[0]
        ratio = _gain_ratio(bags[None], total, np.array([gain]))[0]
        return float(gain), float(ratio), Split(feature, False, np.nan, n_labels)

    def _numeric_splits(
        self, rows: np.ndarray, weight: np.ndarray, total: float
    ) -> list[tuple[float, float, Split]]:
        """The best cut of every numeric attribute (``C45Split`` on each), a few columns at
        a time: the scoring holds arrays of (n_rows, columns, n_classes), so that columns
        are taken in chunks of at most :data:`CHUNK_CELLS` cells (memory linear in the
        data, not times the classes; each column's arithmetic is the same)."""
        if self.numeric.size == 0 or rows.size < 2:
            return []
        width = max(1, CHUNK_CELLS // (rows.size * self.n_classes))
        found: list[tuple[float, float, Split]] = []
        for start in range(0, self.numeric.size, width):
            found += self._numeric_chunk(self.numeric[start : start + width], rows, weight, total)
        return found

    def _numeric_chunk(
        self, columns: np.ndarray, rows: np.ndarray, weight: np.ndarray, total: float
    ) -> list[tuple[float, float, Split]]:
        """The best cut of each numeric attribute in ``columns`` at once.

        Each column is sorted (missing values last); cumulative class weights give the
        class distribution on each side of every candidate cut, of shape
        (n_rows - 1, n_columns, n_classes).
        """
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
        old = x_log2_x(known_total) - x_log2_x(known_counts).sum(axis=1)
        new = (
            x_log2_x(left_total)
            + x_log2_x(right_total)
            - x_log2_x(left).sum(axis=2)
            - x_log2_x(right).sum(axis=2)
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
            (float(g), float(r), Split(int(columns[j]), True, float(t), 2))
            for j, g, r, t in zip(chosen, corrected, ratios, thresholds, strict=True)
        ]


def _info_gain(bags: np.ndarray, total: float) -> np.ndarray:
    """Information gain (bits per instance) of splits ``bags`` (n_splits, n_bags, C).

    ``total`` is the node's weight, unknown values included; gain is scaled by the known
    fraction as in C4.5.
    """
    per_class = bags.sum(axis=1)
    known = per_class.sum(axis=1)
    old = x_log2_x(known) - x_log2_x(per_class).sum(axis=1)
    new = x_log2_x(bags.sum(axis=2)).sum(axis=1) - x_log2_x(bags).sum(axis=(1, 2))
    numerator = (known / total) * (old - new)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = numerator / known
    return np.where(np.abs(numerator) < SMALL, 0.0, out)


def _gain_ratio(bags: np.ndarray, total: float, gains: np.ndarray) -> np.ndarray:
    """Gain ratio of splits ``bags`` (n_splits, n_bags, C) with information ``gains``."""
    per_bag = bags.sum(axis=2)
    unknown = total - per_bag.sum(axis=1)
    split_info = (
        -x_log2_x(per_bag).sum(axis=1) - x_log2_x(unknown) + x_log2_x(np.full_like(unknown, total))
    )
    split_info = np.where(per_bag.sum(axis=1) > SMALL, split_info, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = gains / (split_info / total)
    return np.where(np.abs(split_info) < SMALL, 0.0, out)


def check_pruning(confidence: float, min_instances: int) -> None:
    """Raise ValueError unless ``confidence`` is in (0, 0.5] and ``min_instances`` >= 1."""
    if not 0 < confidence <= 0.5:
        raise ValueError(f"confidence must lie in (0, 0.5], got {confidence!r}")
    if not isinstance(min_instances, int | np.integer) or min_instances < 1:
        raise ValueError(f"min_instances must be a positive integer, got {min_instances!r}")


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


def training_errors(counts: np.ndarray) -> float:
    """Training errors of a class distribution: its weight outside the majority class."""
    return float(counts.sum() - counts.max()) if counts.size else 0.0
