"""Dense ARFF rows made with Apache Arrow's compute functions, the same text as the row
writer's (:class:`~benchmark.io.arff_writer.ArffWriter`) byte for byte, four times faster.

Arrow writes a double as its shortest round-trip digits, as Python's ``repr`` does; the two
differ only in notation.  From 1e-4 to 1e10 in magnitude, and for zero, both write fixed
notation, Arrow without the ``.0`` that :func:`~benchmark.io.arff_writer.format_number`
drops as well, so those cells keep Arrow's text.  Every other cell (NaN, infinities, other
magnitudes, nominal labels, strings and dates) takes the text the row writer gives it.
Consecutive numeric attributes are cast to text in one call and joined row by row in
another; the other attributes are joined to them a column at a time.  The tests compare
both writers on random values and on the edges of that range.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

#: Magnitudes whose Arrow text is Python's ``repr`` (fixed notation on both sides).
_FIXED_LOW, _FIXED_HIGH = 1e-4, 1e10


class DenseRows:
    """Makes the text of dense rows of one schema's attributes.

    Parameters
    ----------
    labels : sequence of (sequence of str or None)
        For each attribute, the ARFF text of each code (nominal labels and strings, quoted
        as written), or ``None`` for a numeric or date attribute.
    cells : sequence of (callable or None)
        For each date attribute, the function from a stored value to its text (which may
        raise); ``None`` for the others.
    number : callable
        The text of a number outside Arrow's range (``format_number``).
    """

    def __init__(
        self,
        labels: Sequence[Sequence[str] | None],
        cells: Sequence[Callable[[float], str] | None],
        number: Callable[[float], str],
    ) -> None:
        self._labels = [None if table is None else [*table, "?"] for table in labels]
        self._cells = list(cells)
        self._number = number
        #: Runs of attributes: (first, stop) of consecutive numeric ones, or one other.
        self._runs: list[tuple[int, int]] = []
        for j, (table, cell) in enumerate(zip(labels, cells, strict=True)):
            numeric = table is None and cell is None
            if numeric and self._runs and self._runs[-1][1] == j and self._numeric(j - 1):
                self._runs[-1] = (self._runs[-1][0], j + 1)
            else:
                self._runs.append((j, j + 1))

    def _numeric(self, j: int) -> bool:
        return self._labels[j] is None and self._cells[j] is None

    def text(self, values: np.ndarray, suffixes: dict[int, str] | None = None) -> str:
        """The rows of ``values``, each followed by a line break.

        Parameters
        ----------
        values : ndarray of shape (n, n_attributes)
            Codes already checked against their tables.
        suffixes : dict, optional
            Text to add to the end of some rows (by row index), such as an instance weight.

        Returns
        -------
        str
        """
        import pyarrow as pa
        import pyarrow.compute as pc

        n = values.shape[0]
        if n == 0:
            return ""
        pieces = [
            self._numbers(values[:, first:stop])
            if self._numeric(first)
            else self._others(values[:, first], first)
            for first, stop in self._runs
        ]
        lines = pieces[0] if len(pieces) == 1 else pc.binary_join_element_wise(*pieces, ",")
        if suffixes:
            ends = [""] * n
            for row, suffix in suffixes.items():
                ends[row] = suffix
            lines = pc.binary_join_element_wise(lines, pa.array(ends, pa.string()), "")
        return _concatenated(pc.binary_join_element_wise(lines, "", "\n"))

    def _numbers(self, values: np.ndarray) -> Any:
        """Each row of numbers as text joined by commas (an Arrow string array)."""
        import pyarrow as pa
        import pyarrow.compute as pc

        flat = np.ascontiguousarray(values, dtype=np.float64).reshape(-1)
        texts = pc.cast(pa.array(flat), pa.string())
        magnitude = np.abs(flat)
        other = ~((magnitude >= _FIXED_LOW) & (magnitude < _FIXED_HIGH)) & (flat != 0)
        if other.any():
            replaced = [self._number(value) for value in flat[other].tolist()]
            texts = pc.replace_with_mask(texts, pa.array(other), pa.array(replaced, pa.string()))
        if values.shape[1] == 1:
            return texts
        starts = pa.array(np.arange(0, flat.size + 1, values.shape[1], dtype=np.int32))
        return pc.binary_join(pa.ListArray.from_arrays(starts, texts), ",")

    def _others(self, column: np.ndarray, j: int) -> Any:
        """The texts of a nominal, string or date column (an Arrow string array)."""
        import pyarrow as pa

        table = self._labels[j]
        if table is None:
            cell = self._cells[j]
            assert cell is not None
            return pa.array([cell(value) for value in column.tolist()], pa.string())
        missing = np.isnan(column)
        codes = np.where(missing, len(table) - 1, np.where(missing, 0, column)).astype(np.int64)
        return pa.array(table, pa.string()).take(pa.array(codes))


def _concatenated(array: object) -> str:
    """The text of an Arrow string array's items, one after the other."""
    offsets_buffer, data = array.buffers()[1:3]  # type: ignore[attr-defined]
    length = len(array)  # type: ignore[arg-type]
    offset = array.offset  # type: ignore[attr-defined]
    offsets = np.frombuffer(offsets_buffer, dtype=np.int32, count=length + 1, offset=offset * 4)
    return memoryview(data)[int(offsets[0]) : int(offsets[-1])].tobytes().decode("utf-8")
