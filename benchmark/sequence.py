"""Sequence data sets: one multichannel window per instance, stored as flat ARFF columns.

A sequence instance (``n_channels`` x ``length`` values: an event's samples, or its MFCC
frames) is stored as ``n_channels * length`` numeric attributes named ``CHANNEL[T]``,
channel after channel, ``T`` counting the time steps from 0::

    @attribute ch1[0] numeric      ... @attribute ch1[255] numeric
    @attribute ch2[0] numeric      ... @attribute ch2[255] numeric

The shape is recorded in the names, so it travels with the columns wherever they go.

Why flattened columns and not ARFF relational attributes, WEKA's own way to nest a
sequence in an instance:

* every part of touchbench reads an instance as one row of float64 values (the
  :class:`~benchmark.dataset.Dataset` matrix, the store's row encoding, the ARFF and CSV
  readers' fast paths, the API's ``{"name": value}`` instances); a relational value is a
  nested table that none of them, nor liac-arff, nor MEKA, can hold;
* flat classifiers (touchbench's and WEKA's alike: WEKA's J48 or RandomForest refuse a
  relational attribute) keep working on a sequence data set: they see the columns;
* a sequence survives any tool that keeps attribute names (WEKA's filters, a CSV round
  trip, a spreadsheet), and a damaged one is recognised: a missing or reordered column
  breaks the grid, and the data set is then read as flat, with a note saying why.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

_NAME = re.compile(r"^(?P<channel>.+)\[(?P<step>\d+)\]$")


@dataclass(frozen=True)
class SequenceLayout:
    """Where the sequence lies among a feature matrix's columns.

    Parameters
    ----------
    start : int
        The first column of the sequence block.
    channels : tuple of str
        Channel names in column order.
    length : int
        Time steps per channel.
    """

    start: int
    channels: tuple[str, ...]
    length: int

    @property
    def n_channels(self) -> int:
        return len(self.channels)

    @property
    def width(self) -> int:
        """Columns of the block: ``n_channels * length``."""
        return self.n_channels * self.length

    @property
    def stop(self) -> int:
        return self.start + self.width

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(start, n_channels, length)``: what a sequence classifier's ``sequence`` takes."""
        return (self.start, self.n_channels, self.length)

    def describe(self) -> str:
        return f"{self.n_channels} channel(s) x {self.length} steps"


def sequence_names(channels: Sequence[str], length: int) -> list[str]:
    """Attribute names of a sequence block: ``c[0] ... c[length-1]`` for each channel."""
    return [f"{channel}[{step}]" for channel in channels for step in range(length)]


def find_sequence(names: Sequence[str]) -> tuple[SequenceLayout | None, str | None]:
    """The sequence block among feature names, if they hold a whole one.

    Parameters
    ----------
    names : sequence of str
        Feature names in column order.

    Returns
    -------
    layout : SequenceLayout or None
        ``None`` for a flat data set.
    note : str or None
        Why names that look like a sequence (``X[T]``) do not form one: the data set is
        then flat, and the note says so.
    """
    parsed = [_NAME.match(name) for name in names]
    columns = [i for i, match in enumerate(parsed) if match is not None]
    if not columns:
        return None, None
    start, stop = columns[0], columns[-1] + 1
    if len(columns) != stop - start:
        outside = next(names[i] for i in range(start, stop) if parsed[i] is None)
        return None, _broken(f"attribute '{outside}' interrupts the block")
    runs: list[tuple[str, list[int]]] = []
    for position in range(start, stop):
        match = parsed[position]
        assert match is not None
        channel, step = match["channel"], int(match["step"])
        if not runs or runs[-1][0] != channel:
            if any(channel == seen for seen, _ in runs):
                return None, _broken(f"channel '{channel}' is split by another channel")
            runs.append((channel, []))
        runs[-1][1].append(step)
    length = len(runs[0][1])
    for channel, steps in runs:
        if steps != list(range(len(steps))):
            wrong = next(i for i, step in enumerate(steps) if step != i)
            return None, _broken(
                f"attribute '{channel}[{steps[wrong]}]' stands where '{channel}[{wrong}]' should"
            )
        if len(steps) != length:
            return None, _broken(
                f"channel '{channel}' has {len(steps)} steps, '{runs[0][0]}' has {length}"
            )
    channels = [channel for channel, _ in runs]
    return SequenceLayout(start=start, channels=tuple(channels), length=length), None


def panel(X: np.ndarray, shape: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Split a feature matrix into its sequences and the other columns.

    Parameters
    ----------
    X : ndarray of shape (n_instances, n_columns)
    shape : (start, n_channels, length)
        :attr:`SequenceLayout.shape`.

    Returns
    -------
    sequences : ndarray of shape (n_instances, n_channels, length)
    others : ndarray of shape (n_instances, n_columns - n_channels * length)
        The columns before and after the block, in order.
    """
    start, n_channels, length = shape
    stop = start + n_channels * length
    if X.ndim != 2 or X.shape[1] < stop:
        raise ValueError(
            f"a sequence of {n_channels} x {length} from column {start} needs at least "
            f"{stop} columns, got an array of shape {X.shape}"
        )
    sequences = X[:, start:stop].reshape(X.shape[0], n_channels, length)
    others = np.hstack([X[:, :start], X[:, stop:]])
    return sequences, others


def _broken(reason: str) -> str:
    return f"attributes named like a sequence (CHANNEL[T]) do not form one ({reason}): read as flat"
