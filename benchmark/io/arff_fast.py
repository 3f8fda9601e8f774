"""The vectorised reading of plain blocks of ARFF rows with Apache Arrow's CSV reader.

Most of a real data section is lines such as ``'tap','head',459.375,0,?``: numbers,
nominal labels (quoted or not) and ``?``, separated by single commas.  On such a block
WEKA's tokenizer and a CSV parser read the same fields, so Arrow's C++ reader reads the
block at C speed (in threads of its own, unless blocks are already read side by side).
:func:`read_plain_block` first proves, with numpy over the block's bytes, that Arrow cannot
read it differently without saying so, and gives up (returns ``None``) otherwise, leaving
the block to the exact reader (:mod:`benchmark.io.arff_data`):

- no double quote, backslash, brace, ``%``, and no whitespace or control character but
  the line breaks (``\\n``, or ``\\r\\n`` throughout);
- no comma at the start or end of a line, none two in a row, and as many on each line as
  there are attributes less one (Arrow itself refuses a line with another number);
- single quotes pair up on each line, each pair enclosing one whole field, and ``'?'``
  (the label ``?``, not a missing value) does not occur;
- every numeric field is a number Arrow reads (it refuses, for example, ``1_000``, which
  Python's ``float`` reads: such blocks go to the exact reader), and every nominal field
  is a declared label or ``?``; labels that could not be plain fields (with separators,
  quotes or braces) keep the whole file off this path.

Arrow converts text to float64 with ``fast_float``, correctly rounded as Python's own
``float`` is, so the values are the same bits whatever the version of pandas (whose C
parser rounds correctly only from 3.1, and before it only through Python's own conversion,
one number at a time); the tests compare both readers bit for bit.  pyarrow is imported
on the first block, so small files never pay for its import.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from touchbench.benchmark.dataset import Attribute

_FORBIDDEN = (b'"', b"\\", b"{", b"}", b"%")
_NOT_PLAIN = re.compile(r"""^$|[\x00-\x20,'"\\{}%]""")
_COMMA, _QUOTE, _LF, _CR = 44, 39, 10, 13


@dataclass(frozen=True)
class PlainPlan:
    """How the attributes of a file read in plain blocks.

    Attributes
    ----------
    numeric : ndarray of int
        Positions of the numeric attributes.
    nominal : ndarray of int
        Positions of the nominal attributes.
    labels : tuple of tuple of str
        The declared labels of each nominal attribute, in the order of ``nominal``.
    """

    numeric: np.ndarray
    nominal: np.ndarray
    labels: tuple[tuple[str, ...], ...]

    @property
    def n_columns(self) -> int:
        return len(self.numeric) + len(self.nominal)


def plain_plan(attributes: Sequence[Attribute]) -> PlainPlan | None:
    """The plan for ``attributes``; ``None`` when some are strings or dates, or some label
    could not be a plain field (empty, ``?``, or holding a separator, quote, brace or ``%``)."""
    if any(attribute.kind not in ("numeric", "nominal") for attribute in attributes):
        return None
    labels = [label for attribute in attributes for label in attribute.values]
    if any(label == "?" or _NOT_PLAIN.search(label) for label in labels):
        return None
    kinds = [attribute.kind for attribute in attributes]
    nominal = [j for j, kind in enumerate(kinds) if kind == "nominal"]
    return PlainPlan(
        numeric=np.array([j for j, kind in enumerate(kinds) if kind == "numeric"], dtype=np.intp),
        nominal=np.array(nominal, dtype=np.intp),
        labels=tuple(attributes[j].values for j in nominal),
    )


def read_plain_block(
    block: bytes, plan: PlainPlan, *, encoding: str, threads: bool = True
) -> tuple[np.ndarray, np.ndarray] | None:
    """The rows of a block of whole lines, if the block is plain.

    Parameters
    ----------
    block : bytes
        Whole lines of the data section, with their line breaks.
    plan : PlainPlan
        The attributes.
    encoding : str
        The file's encoding (``utf-8`` or ``latin-1``).
    threads : bool
        Whether Arrow reads the block in threads of its own (not worth it when blocks
        are already read side by side).

    Returns
    -------
    values : ndarray of shape (n_rows, n_attributes)
        As the exact reader decodes them.
    rows : ndarray of shape (n_rows,)
        The 0-based index, among the block's lines, of the line of each row.

    Or ``None`` when the block is not plain (see the module docstring).
    """
    rows = _plain_rows(block, plan.n_columns)
    if rows is None:
        return None
    if rows.size == 0:
        return np.empty((0, plan.n_columns)), rows
    table = _parse(block, plan, encoding, threads)
    if table is None or table.num_rows != rows.size:
        return None
    values = np.empty((rows.size, plan.n_columns))
    start = 0
    for batch in table.to_batches():
        part = values[start : start + batch.num_rows]
        for position in plan.numeric.tolist():
            part[:, position] = _numbers(batch.column(position))
        for position, labels in zip(plan.nominal.tolist(), plan.labels, strict=True):
            codes = _label_codes(batch.column(position), labels)
            if codes is None:
                return None
            part[:, position] = codes
        start += batch.num_rows
    return values, rows


def _plain_rows(block: bytes, n_columns: int) -> np.ndarray | None:
    """The indices of the non-blank lines of a plain block, ``None`` if it is not plain.

    What is checked here is what Arrow would read differently from WEKA's tokenizer
    without saying so; the rest (a line with too many fields, a field that is neither a
    number nor a label) makes Arrow fail or :func:`read_plain_block` refuse the values.
    """
    if any(byte in block for byte in _FORBIDDEN):
        return None
    data = np.frombuffer(block, dtype=np.uint8)
    commas = data == _COMMA
    if np.any(commas[1:] & commas[:-1]):
        return None  # an empty field
    breaks = np.flatnonzero(data == _LF)
    crlf = b"\r" in block
    carriage_returns = int(np.count_nonzero(data == _CR)) if crlf else 0
    if np.count_nonzero(data < 0x21) != breaks.size + carriage_returns:
        return None  # whitespace or control characters other than line breaks
    if crlf and (carriage_returns != breaks.size or np.any(data[breaks - 1] != _CR)):
        return None  # "\r" other than in "\r\n" line ends
    ends = breaks - 1 if crlf else breaks  # where each line's break starts
    if block[-1] != _LF:
        ends = np.append(ends, len(block))  # a last line without a line break
    starts = np.concatenate(([0], breaks + 1))[: ends.size]
    non_blank = np.flatnonzero(ends > starts)
    if non_blank.size == 0:
        return non_blank
    if np.any(data[ends[non_blank] - 1] == _COMMA) or np.any(data[starts[non_blank]] == _COMMA):
        return None  # a comma at the start or end of a line
    # Every line has as many fields as attributes: Arrow refuses lines with another number
    # of fields than the first, so the total settles it once the first line is right (a quoted
    # comma would show in a field that is neither a number nor a label).
    first = non_blank[0]
    if block.count(b",", starts[first], ends[first]) != n_columns - 1:
        return None
    if np.count_nonzero(commas) != non_blank.size * (n_columns - 1):
        return None
    if b"'" in block and not _quotes_enclose_fields(data, np.flatnonzero(data == _QUOTE), breaks):
        return None
    return non_blank


def _quotes_enclose_fields(data: np.ndarray, quotes: np.ndarray, breaks: np.ndarray) -> bool:
    """Whether the quotes pair up on each line, each pair enclosing one whole field that is
    neither empty nor ``?``."""
    if quotes.size % 2:
        return False
    opening, closing = quotes[0::2], quotes[1::2]
    inside = closing - opening - 1
    if np.any(inside == 0) or np.any((inside == 1) & (data[opening + 1] == ord("?"))):
        return False
    before = data[np.maximum(opening - 1, 0)]
    if np.any((opening > 0) & (before != _COMMA) & (before != _LF)):
        return False
    after = data[np.minimum(closing + 1, data.size - 1)]
    if np.any((closing + 1 < data.size) & (after != _COMMA) & (after != _LF) & (after != _CR)):
        return False
    return bool(np.all(np.searchsorted(breaks, opening) == np.searchsorted(breaks, closing)))


def _parse(block: bytes, plan: PlainPlan, encoding: str, threads: bool) -> Any | None:
    """The block as an Arrow table, ``None`` if Arrow cannot read it as planned."""
    import pyarrow as pa
    import pyarrow.csv as csv

    names = [str(j) for j in range(plan.n_columns)]
    types = {names[j]: pa.float64() for j in plan.numeric.tolist()}
    labels = pa.dictionary(pa.int32(), pa.string())
    types.update({names[j]: labels for j in plan.nominal.tolist()})
    try:
        return csv.read_csv(
            pa.py_buffer(block),
            read_options=csv.ReadOptions(
                column_names=names, encoding=encoding, use_threads=threads
            ),
            parse_options=csv.ParseOptions(
                delimiter=",", quote_char="'", double_quote=False, escape_char=False
            ),
            convert_options=csv.ConvertOptions(
                column_types=types,
                null_values=["?"],
                strings_can_be_null=True,
                quoted_strings_can_be_null=False,
            ),
        )
    except (pa.ArrowException, ValueError, UnicodeDecodeError):
        return None


# Arrow arrays are read through their buffers: pyarrow's own conversion to numpy of an
# array with nulls imports pandas, a large import for what a bitmap says.


def _numbers(array: Any) -> np.ndarray:
    """The values of an Arrow float64 array, NaN where null; shape (len(array),)."""
    return _with_nulls(array, _buffer(array, np.dtype(np.float64)))


def _label_codes(array: Any, labels: tuple[str, ...]) -> np.ndarray | None:
    """Codes of an Arrow dictionary array of nominal texts, NaN where missing; ``None`` if
    some text is not one of ``labels``."""
    lookup = {label: float(code) for code, label in enumerate(labels)}
    texts = array.dictionary.to_pylist()
    if any(text not in lookup for text in texts):
        return None
    table = np.array([lookup[text] for text in texts] or [np.nan])
    indices = _buffer(array.indices, np.dtype(np.int32))
    if array.null_count:
        indices = np.where(_valid(array), indices, 0)
    return _with_nulls(array, table[indices])


def _buffer(array: Any, dtype: np.dtype) -> np.ndarray:
    """The values buffer of a primitive Arrow array, as a read-only view."""
    data = array.buffers()[1]
    return np.frombuffer(data, dtype=dtype, count=len(array), offset=array.offset * dtype.itemsize)


def _valid(array: Any) -> np.ndarray:
    """Which items of an Arrow array with nulls are not null (its validity bitmap)."""
    bitmap = np.frombuffer(array.buffers()[0], dtype=np.uint8)
    bits = np.unpackbits(bitmap, count=array.offset + len(array), bitorder="little")
    return bits[array.offset :].astype(bool)


def _with_nulls(array: Any, values: np.ndarray) -> np.ndarray:
    """``values`` with NaN where ``array`` is null (a new array if it has nulls)."""
    return np.where(_valid(array), values, np.nan) if array.null_count else values
