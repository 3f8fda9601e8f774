"""How sure a classifier is, against how often it is right: reliability bins and the
expected calibration error (ECE) of its top-label confidence.

Each fold keeps only its bins (per bin: instances, summed confidence, summed hits), not its
probabilities: bins of several folds add up, so a run's out-of-fold reliability diagram and
ECE are exact from what the store keeps, at 3 x ``n_bins`` numbers per fold.

ECE (Naeini et al. 2015; Guo et al. 2017) with ``B`` equal-width bins of the top-label
confidence ``p̂ = max_k p(k | x)``::

    ECE = sum_b (n_b / n) * | acc_b - conf_b |

where ``acc_b`` is the fraction of the bin's instances whose top label is the true one
and ``conf_b`` their mean confidence.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

#: Equal-width confidence bins of a fold.
N_BINS = 10
#: A multi-target fold keeps ``{PER_TARGET: {target name: bins}}``: each target's own.
PER_TARGET = "targets"


@dataclass(frozen=True)
class Reliability:
    """Summed reliability bins.

    Attributes
    ----------
    count : ndarray of shape (n_bins,)
        Instances whose top-label confidence falls in each bin.
    confidence : ndarray of shape (n_bins,)
        Their summed confidence.
    correct : ndarray of shape (n_bins,)
        How many of them the top label got right.
    """

    count: np.ndarray
    confidence: np.ndarray
    correct: np.ndarray

    @property
    def n_bins(self) -> int:
        return int(self.count.size)

    @property
    def edges(self) -> np.ndarray:
        """Bin edges, shape (n_bins + 1,), from 0 to 1."""
        return np.linspace(0.0, 1.0, self.n_bins + 1)

    def mean_confidence(self) -> np.ndarray:
        """Mean confidence per bin, shape (n_bins,); NaN for empty bins."""
        return _ratio(self.confidence, self.count)

    def accuracy(self) -> np.ndarray:
        """Fraction right per bin, shape (n_bins,); NaN for empty bins."""
        return _ratio(self.correct, self.count)

    def ece(self) -> float:
        """Expected calibration error; NaN without instances."""
        n = self.count.sum()
        if n == 0:
            return float("nan")
        gaps = np.abs(self.correct - self.confidence)  # n_b * |acc_b - conf_b|
        return float(gaps.sum() / n)

    def to_json(self) -> dict[str, list[float]]:
        return {
            "count": self.count.tolist(),
            "confidence": self.confidence.tolist(),
            "correct": self.correct.tolist(),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Sequence[float]]) -> Reliability:
        return cls(
            np.asarray(data["count"], dtype=np.float64),
            np.asarray(data["confidence"], dtype=np.float64),
            np.asarray(data["correct"], dtype=np.float64),
        )


def reliability(y_true: np.ndarray, proba: np.ndarray, *, n_bins: int = N_BINS) -> Reliability:
    """The reliability bins of one fold's predictions.

    Parameters
    ----------
    y_true : ndarray of shape (n_samples,)
        Integer labels.
    proba : ndarray of shape (n_samples, n_classes)
        Class probabilities (rows normalised to sum 1 here; a zero row counts as
        confidence 0).
    n_bins : int
        Equal-width bins over [0, 1]; a confidence of exactly 1 falls in the last.

    Returns
    -------
    Reliability
    """
    proba = np.asarray(proba, dtype=np.float64)
    truth = np.asarray(y_true, dtype=np.int64)
    totals = proba.sum(axis=1, keepdims=True)
    normalised = np.divide(proba, totals, out=np.zeros_like(proba), where=totals > 0)
    top = normalised.argmax(axis=1)
    confidence = normalised[np.arange(truth.size), top]
    hit = (top == truth).astype(np.float64)
    which = np.minimum((confidence * n_bins).astype(np.int64), n_bins - 1)
    return Reliability(
        np.bincount(which, minlength=n_bins).astype(np.float64),
        np.bincount(which, weights=confidence, minlength=n_bins),
        np.bincount(which, weights=hit, minlength=n_bins),
    )


def merge(parts: Iterable[Reliability]) -> Reliability | None:
    """The sum of several folds' bins (same number of bins); ``None`` without any."""
    parts = list(parts)
    if not parts:
        return None
    return Reliability(
        np.sum([p.count for p in parts], axis=0),
        np.sum([p.confidence for p in parts], axis=0),
        np.sum([p.correct for p in parts], axis=0),
    )


def _ratio(numerator: np.ndarray, denominator: np.ndarray) -> np.ndarray:
    out = np.full(numerator.shape, np.nan)
    np.divide(numerator, denominator, out=out, where=denominator > 0)
    return out
