"""Sequence data sets made in the test (channels x time steps per instance)."""

from __future__ import annotations

import numpy as np

from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.sequence import sequence_names

CHANNELS, LENGTH = ("x", "z"), 48


def shapes(n: int = 80, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Sawtooth waves that rise slowly and fall fast (class 0) or the reverse (class 1).

    Class 1 is class 0 played backwards: every window holds the same values in another
    order, with a random shift, level and gain, so that no statistic of the values alone
    (mean, spread, extremes, quantiles) tells the classes apart; the shape does.

    Returns
    -------
    sequences : ndarray of shape (n, 2, LENGTH)
    y : ndarray of shape (n,)
    """
    rng = np.random.default_rng(seed)
    y = np.arange(n) % 2
    steps = np.arange(LENGTH)
    sequences = np.empty((n, len(CHANNELS), LENGTH))
    for i in range(n):
        for c in range(len(CHANNELS)):
            phase = (steps + rng.integers(LENGTH)) % 16 / 16.0  # sawtooth of period 16
            wave = phase if y[i] == 0 else phase[::-1]
            gain, level = rng.uniform(0.5, 2.0), rng.normal(0, 3)
            sequences[i, c] = level + gain * wave + 0.05 * rng.normal(size=LENGTH)
    return sequences, y


def sequence_dataset(sequences: np.ndarray, y: np.ndarray) -> Dataset:
    """Target first, then a flat 'gain' column, then the windows as CHANNEL[T] columns."""
    n = len(y)
    names = sequence_names(CHANNELS, LENGTH)
    attributes = (
        Attribute("slope", "nominal", ("up", "down")),
        Attribute("gain", "numeric"),
        *(Attribute(name, "numeric") for name in names),
    )
    values = np.column_stack([y, np.ones(n), sequences.reshape(n, -1)])
    return Dataset(Schema("shapes: -C 1", attributes, (0,)), values, name="shapes")
