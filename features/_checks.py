"""Validation shared by the feature functions: every bad input becomes a FeatureError."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from touchbench.features.errors import FeatureError


def as_signal(y: Any, *, name: str = "y", min_samples: int = 1) -> np.ndarray:
    """``y`` as a finite float64 array of at least ``min_samples`` samples on its last axis.

    Parameters
    ----------
    y : array_like of shape (..., n_samples)
        Samples; the last axis is time.
    name : str
        The parameter's name, for the message.
    min_samples : int
        The fewest samples the caller can work with (one window, usually).

    Returns
    -------
    ndarray of shape (..., n_samples), float64
    """
    array = np.asarray(y)
    if array.dtype.kind not in "biuf":
        raise FeatureError(f"{name} must hold real numbers, got dtype {array.dtype}")
    array = array.astype(np.float64, copy=False)
    if array.ndim == 0:
        raise FeatureError(f"{name} must have a time axis, got a scalar")
    n_samples = array.shape[-1]
    if n_samples < min_samples:
        raise FeatureError(
            f"{name} has {n_samples} sample(s), shorter than one window of {min_samples}"
        )
    # A sum is finite only if every term is (an overflow to inf falls through to the
    # elementwise search, which then finds nothing): one pass instead of a boolean copy.
    if not np.isfinite(np.sum(array)) and not np.isfinite(array).all():
        bad = np.argwhere(~np.isfinite(array))[0]
        where = ", ".join(str(int(i)) for i in bad)
        raise FeatureError(f"{name} has a NaN or infinite sample at index ({where})")
    return array


def as_samplerate(samplerate: Any, *, name: str = "samplerate") -> float:
    """A finite, positive sample rate in Hz."""
    try:
        rate = float(samplerate)
    except (TypeError, ValueError):
        raise FeatureError(f"{name} must be a number in Hz, got {samplerate!r}") from None
    if not math.isfinite(rate) or rate <= 0:
        raise FeatureError(f"{name} must be a positive number of Hz, got {samplerate!r}")
    return rate


def as_positive_int(value: Any, *, name: str) -> int:
    """A whole number of at least 1 (a window length, a hop, a count)."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise FeatureError(f"{name} must be a whole number, got {value!r}")
    if value < 1:
        raise FeatureError(f"{name} must be at least 1, got {value}")
    return int(value)
