"""Sequences of any length to a fixed number of steps, for sequence instances.

A longer sequence is shortened by averaging: step ``i`` of ``length`` is the mean of the
samples ``[floor(i n / length), floor((i + 1) n / length))``, a box filter that keeps
what varies slower than the new step and averages out the rest (no aliasing of content
above the new Nyquist frequency into the result).  A shorter one is stretched by linear
interpolation at ``length`` evenly spaced points from its first to its last sample.
"""

from __future__ import annotations

import numpy as np

from touchbench.features._checks import as_signal


def to_length(y: np.ndarray, length: int) -> np.ndarray:
    """``y`` with ``length`` steps on its last axis (see the module docstring).

    Parameters
    ----------
    y : ndarray of shape (..., n_samples)
        Finite samples, ``n_samples >= 1``.
    length : int
        Steps of the result, at least 1.

    Returns
    -------
    ndarray of shape (..., length), float64
        ``y`` itself (as float64) when ``n_samples == length``.
    """
    y = as_signal(y)
    n = y.shape[-1]
    if n == length:
        return y
    if n > length:
        edges = (np.arange(length + 1) * n) // length
        sums = np.add.reduceat(y, edges[:-1], axis=-1)
        return sums / np.diff(edges)
    if n == 1:
        return np.repeat(y, length, axis=-1)
    positions = np.linspace(0.0, n - 1, length)
    left = np.minimum(positions.astype(np.int64), n - 2)
    weight = positions - left
    return y[..., left] * (1 - weight) + y[..., left + 1] * weight
