"""Per-event statistics of frame-wise features: mean, minimum, maximum and range.

Frame values of many events are kept in one flat array, each event's frames
contiguous, so that every statistic of every event is one ``numpy.ufunc.reduceat``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from touchbench.features.errors import FeatureError


@dataclass(frozen=True)
class SegmentStatistics:
    """Statistics of each segment, each of shape (..., n_segments).

    ``range`` is ``maximum - minimum``.  An empty segment has every statistic 0.
    """

    mean: np.ndarray
    minimum: np.ndarray
    maximum: np.ndarray

    @property
    def range(self) -> np.ndarray:
        return self.maximum - self.minimum


def segment_statistics(values: np.ndarray, *, lengths: np.ndarray) -> SegmentStatistics:
    """Mean, minimum and maximum of consecutive segments along the last axis.

    Parameters
    ----------
    values : ndarray of shape (..., n_values)
        Frame-wise values; segment ``j`` is the next ``lengths[j]`` values.
    lengths : ndarray of shape (n_segments,), int
        Segment lengths, summing to ``n_values``; a length may be 0.

    Returns
    -------
    SegmentStatistics
        Arrays of shape (..., n_segments).
    """
    lengths = np.asarray(lengths, dtype=np.int64)
    if lengths.ndim != 1 or (lengths < 0).any() or lengths.sum() != values.shape[-1]:
        raise FeatureError(
            f"segment lengths must be non-negative and sum to {values.shape[-1]} values, "
            f"got {lengths.sum()}"
        )
    shape = (*values.shape[:-1], lengths.size)
    if values.shape[-1] == 0:
        zeros = np.zeros(shape)
        return SegmentStatistics(mean=zeros, minimum=zeros, maximum=zeros)
    filled = lengths > 0
    starts = (np.cumsum(lengths) - lengths)[filled]
    mean, minimum, maximum = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    mean[..., filled] = np.add.reduceat(values, starts, axis=-1) / lengths[filled]
    minimum[..., filled] = np.minimum.reduceat(values, starts, axis=-1)
    maximum[..., filled] = np.maximum.reduceat(values, starts, axis=-1)
    return SegmentStatistics(mean=mean, minimum=minimum, maximum=maximum)
