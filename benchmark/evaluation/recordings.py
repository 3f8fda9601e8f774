"""Per-recording scores: the windows of one recording scored as one prediction.

A data set extracted from recordings holds many windows (events) per recording; its folds
keep each recording's windows together (group k-fold), so every recording of a test fold
is seen whole.  Scored per recording, a fold's predictions are first pooled per recording:

* the mean of the windows' class probabilities, its most probable class the prediction
  (the usual soft vote);
* for a classifier without probabilities, the majority of the windows' predicted classes
  (ties: the lowest class code);
* for numeric targets, the mean of the windows' predictions.

The truth of a recording is the one label its windows share (:func:`check_one_label`
refuses a data set whose recordings hold several).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from touchbench.benchmark.errors import ConfigurationError


@dataclass(frozen=True)
class Recordings:
    """Which recording each window of a test fold belongs to.

    Parameters
    ----------
    index : ndarray of shape (n_windows,), int64
        The window's recording, ``0..n_recordings-1`` in order of first appearance.
    n_recordings : int
    first : ndarray of shape (n_recordings,), int64
        The first window of each recording (its truth stands for all of them).
    """

    index: np.ndarray
    n_recordings: int
    first: np.ndarray

    @classmethod
    def of(cls, groups: np.ndarray) -> Recordings:
        """The recordings of ``groups`` (shape (n_windows,), one recording id per window)."""
        keys = np.asarray([str(group) for group in groups], dtype=object)
        _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
        # numbered in order of first appearance, so that scores do not depend on the names
        order = np.argsort(first, kind="stable")
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        return cls(rank[inverse].astype(np.int64), int(order.size), first[order].astype(np.int64))

    def truth(self, values: np.ndarray) -> np.ndarray:
        """Each recording's value (its first window's), shape (n_recordings, ...)."""
        return np.asarray(values)[self.first]

    def mean(self, values: np.ndarray) -> np.ndarray:
        """Mean over each recording's windows of ``values`` (shape (n_windows, ...)),
        shape (n_recordings, ...)."""
        values = np.asarray(values, dtype=np.float64)
        sums = np.zeros((self.n_recordings, *values.shape[1:]), dtype=np.float64)
        np.add.at(sums, self.index, values)
        counts = np.bincount(self.index, minlength=self.n_recordings).astype(np.float64)
        return sums / counts.reshape(-1, *([1] * (values.ndim - 1)))

    def vote(self, labels: np.ndarray, n_classes: int) -> np.ndarray:
        """The most frequent class code of each recording's windows (ties: the lowest
        code), shape (n_recordings,), from ``labels`` of shape (n_windows,)."""
        counts = np.zeros((self.n_recordings, n_classes), dtype=np.int64)
        np.add.at(counts, (self.index, np.asarray(labels, dtype=np.int64)), 1)
        return np.argmax(counts, axis=1).astype(np.int64)

    def classes(
        self, labels: np.ndarray, proba: np.ndarray | None, n_classes: int
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Each recording's predicted class and probabilities: the argmax of the mean of
        ``proba`` (shape (n_windows, n_classes)) when given, else the vote of ``labels``.

        Returns
        -------
        labels : ndarray of shape (n_recordings,), int64
        proba : ndarray of shape (n_recordings, n_classes) or None
        """
        if proba is None or proba.shape[1] != n_classes:
            return self.vote(labels, n_classes), None
        mean = self.mean(proba)
        return np.argmax(mean, axis=1).astype(np.int64), mean


def check_one_label(
    Y: np.ndarray, groups: np.ndarray | None, target_names: Sequence[str], dataset: str
) -> None:
    """Refuse per-recording scores where they mean nothing.

    Parameters
    ----------
    Y : ndarray of shape (n_windows, n_targets)
    groups : ndarray of shape (n_windows,) or None
        The recording of each window.

    Raises
    ------
    ConfigurationError
        No recordings (an imported file), or a recording whose windows carry different
        values of a target (a session of several touches: score its windows instead).
    """
    if groups is None:
        raise ConfigurationError(
            f"needs windows grouped by recording, and data set '{dataset}' has no recording "
            "groups (only data sets extracted from recordings have them)"
        )
    recordings = Recordings.of(groups)
    truth = recordings.truth(Y)
    for t, name in enumerate(target_names):
        differ = np.flatnonzero(Y[:, t] != truth[recordings.index, t])
        if differ.size:
            mixed = np.unique(recordings.index[differ])
            first = str(groups[recordings.first[mixed[0]]])
            raise ConfigurationError(
                f"{mixed.size} recording(s) hold windows of several values of '{name}' (first: "
                f"'{first}'): a recording scored as one prediction needs one label"
            )
