"""A bounded history of a growing 2-D array: what a stream keeps of its recent past.

Columns (samples or windows) arrive at the end and are dropped from the front once no
event can need them, so memory follows the longest event, not the recording.
"""

from __future__ import annotations

import numpy as np

from touchbench.features.errors import FeatureError


class History:
    """The columns ``[start, stop)`` of a stream of shape (n_rows, ...), in one buffer.

    Parameters
    ----------
    n_rows : int
        Rows (channels).
    dtype : numpy dtype
        Element type.
    """

    def __init__(self, n_rows: int, dtype: type = np.float64) -> None:
        self._buffer: np.ndarray = np.zeros((n_rows, 1024), dtype=dtype)
        self._first = 0  # buffer column of absolute column ``start``
        self.start = 0
        self.stop = 0

    def append(self, columns: np.ndarray) -> None:
        """Add columns at the end; ``columns`` has shape (n_rows, n)."""
        n = columns.shape[1]
        used = self.stop - self.start
        if self._first + used + n > self._buffer.shape[1]:
            capacity = self._buffer.shape[1]
            while used + n > capacity // 2:
                capacity *= 2
            grown = np.empty((self._buffer.shape[0], capacity), dtype=self._buffer.dtype)
            grown[:, :used] = self._buffer[:, self._first : self._first + used]
            self._buffer, self._first = grown, 0
        end = self._first + used
        self._buffer[:, end : end + n] = columns
        self.stop += n

    def view(self, start: int, stop: int) -> np.ndarray:
        """Columns ``[start, stop)`` (absolute indices), a view valid until the next append."""
        if start < self.start or stop > self.stop or stop < start:
            raise FeatureError(
                f"columns {start}-{stop} are not in the history (it holds {self.start}-{self.stop})"
            )
        return self._buffer[:, self._first + start - self.start : self._first + stop - self.start]

    def discard_before(self, column: int) -> None:
        """Forget the columns before ``column`` (absolute)."""
        column = min(max(column, self.start), self.stop)
        self._first += column - self.start
        self.start = column
        if self._first > self._buffer.shape[1] // 2:
            used = self.stop - self.start
            self._buffer[:, :used] = self._buffer[:, self._first : self._first + used]
            self._first = 0
