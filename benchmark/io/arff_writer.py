"""Writing a :class:`~benchmark.dataset.Dataset` as WEKA ARFF text.

The output is what :mod:`benchmark.io.arff_reader` (and WEKA) reads back to the same
dataset: names and values are quoted only when WEKA's tokenizer would otherwise split or
misread them, with the escapes the reader decodes; numbers use Python's shortest
round-trip ``repr`` (``3`` rather than ``3.0``); a sparse dataset is written as sparse
rows; instance weights other than 1 follow their row as ``{w}``.  Once a writer has written
:data:`VECTORISED_MIN_CELLS` cells, dense rows are made with Arrow
(:mod:`benchmark.io.arff_fast_writer`), the same text four times faster.
"""

from __future__ import annotations

import io
import math
import os
import re
from collections.abc import Callable
from typing import TextIO

import numpy as np

from touchbench.benchmark.dataset import Attribute, Dataset, Schema, resolve_targets
from touchbench.benchmark.errors import ConfigurationError, DataFormatError
from touchbench.benchmark.io.arff_fast_writer import DenseRows
from touchbench.benchmark.io.dates import DateFormat

#: Cells a writer writes row by row before it hands dense rows to Arrow (whose import costs
#: what formatting this many cells does).
VECTORISED_MIN_CELLS = 1 << 18
#: At most this many cells are made into text at a time by Arrow.
_ARROW_CELLS = 1 << 20

_NEEDS_QUOTES = re.compile(r"""[\x00-\x20,{}'"%\\\x7f]""")
_TO_ESCAPE = re.compile(r"""[\x00-\x1f'"%\\\x7f]""")
_ESCAPES = {"\\": "\\\\", "'": "\\'", '"': '\\"', "%": "\\%", "\n": "\\n", "\r": "\\r", "\t": "\\t"}
_MEKA_OPTION = re.compile(r"(?:^|(?<=\s))-C\s+-?\d+")
_NUMERIC_TYPES = ("numeric", "real", "integer")


def quote(text: str) -> str:
    """``text`` as one ARFF token.

    Left as it is when WEKA's tokenizer reads it back as one plain word; otherwise (empty,
    ``?``, separators, quotes, braces, ``%``, backslashes, control characters) put in
    single quotes with backslash escapes, control characters as octal ``\\ooo``.
    """
    if text and text != "?" and _NEEDS_QUOTES.search(text) is None:
        return text
    return "'" + _TO_ESCAPE.sub(_escape_one, text) + "'"


def _escape_one(match: re.Match[str]) -> str:
    char = match.group()
    return _ESCAPES.get(char) or f"\\{ord(char):03o}"


def format_number(value: float) -> str:
    """The shortest text that reads back as ``value``: ``?`` for NaN, ``3`` for 3.0."""
    if math.isnan(value):
        return "?"
    if math.isinf(value):
        return "Infinity" if value > 0 else "-Infinity"
    text = repr(value)
    return text[:-2] if text.endswith(".0") else text


def _number_texts(column: np.ndarray) -> list[str]:
    """:func:`format_number` of each value of a float column of shape (n,), faster."""
    texts = [text[:-2] if text.endswith(".0") else text for text in map(repr, column.tolist())]
    if not np.isfinite(column).all():
        for i in np.flatnonzero(~np.isfinite(column)).tolist():
            texts[i] = format_number(float(column[i]))
    return texts


def _attribute_line(attribute: Attribute) -> str:
    declared = attribute.declared_type
    if attribute.kind == "numeric":
        kind = declared if declared.lower() in _NUMERIC_TYPES else "numeric"
    elif attribute.kind == "nominal":
        kind = "{" + ",".join(quote(label) for label in attribute.values) + "}"
    elif attribute.kind == "string":
        kind = declared if declared.lower() == "string" else "string"
    else:
        kind = declared if declared.lower() == "date" else "date"
        if attribute.date_format is not None:
            kind += " " + quote(attribute.date_format)
    return f"@attribute {quote(attribute.name)} {kind}"


def relation_for(schema: Schema) -> str:
    """The relation name to write so that reading it back gives the schema's targets.

    The stored name when it already implies the targets (MEKA's ``-C`` or WEKA's last
    attribute); otherwise, when the targets are the first or last N attributes, the name
    with a ``-C N`` or ``-C -N`` option added or replaced.  Targets that are neither
    cannot be expressed in ARFF, and the stored name is written unchanged.
    """
    names = [attribute.name for attribute in schema.attributes]
    targets = tuple(schema.target_indices)
    try:
        if resolve_targets(None, names, relation=schema.relation) == targets:
            return schema.relation
    except ConfigurationError:
        pass
    n, k = len(names), len(targets)
    if not 0 < k < n:
        return schema.relation
    if targets == tuple(range(k)):
        option = f"-C {k}"
    elif targets == tuple(range(n - k, n)):
        option = f"-C {-k}"
    else:
        return schema.relation
    name, colon, options = schema.relation.partition(":")
    if not colon:
        return f"{name}: {option}"
    if _MEKA_OPTION.search(options):
        return name + colon + _MEKA_OPTION.sub(option, options, count=1)
    return f"{schema.relation} {option}"


def _check_codes(attributes: tuple[Attribute, ...], values: np.ndarray, offset: int) -> None:
    """Raise DataFormatError if a nominal or string column holds an invalid code."""
    for j, attribute in enumerate(attributes):
        if attribute.kind not in ("nominal", "string"):
            continue
        column = values[:, j]
        present = ~np.isnan(column)
        codes = column[present]
        bad = (codes != np.floor(codes)) | (codes < 0) | (codes >= len(attribute.values))
        if bad.any():
            row = offset + int(np.flatnonzero(present)[np.argmax(bad)])
            raise DataFormatError(
                f"row {row} holds {format_number(float(codes[np.argmax(bad)]))}, which is not "
                f"the code of any of its {len(attribute.values)} {attribute.kind} values",
                attribute=attribute.name,
            )


def _cell_formatter(attribute: Attribute) -> Callable[[float], str]:
    """A function from one stored value of ``attribute`` to its ARFF text."""
    if attribute.kind == "numeric":
        return format_number
    if attribute.kind == "date":
        date_format = DateFormat(attribute.date_format)

        def date_text(value: float) -> str:
            if math.isnan(value):
                return "?"
            try:
                return quote(date_format.format(value))
            except ValueError as error:
                raise DataFormatError(f"cannot write {error}", attribute=attribute.name) from None

        return date_text
    texts = [quote(value) for value in attribute.values]

    def label_text(value: float) -> str:
        return "?" if math.isnan(value) else texts[int(value)]

    return label_text


class ArffWriter:
    """Writes ARFF text block by block: the header, then instances as they come.

    Memory stays that of one block, whatever the data set's size.

    Parameters
    ----------
    stream : text stream
        Where the text goes.
    schema : Schema
        Attributes, targets (written as MEKA's ``-C`` where needed, see
        :func:`relation_for`) and string tables.
    sparse : bool
        Whether rows are written sparse (``{index value, ...}``, zeros left out).
    """

    def __init__(self, stream: TextIO, schema: Schema, *, sparse: bool = False) -> None:
        self.stream = stream
        self.schema = schema
        self.sparse = sparse
        self.rows_written = 0
        self._formatters = [_cell_formatter(attribute) for attribute in schema.attributes]
        self._strings = np.array([a.kind == "string" for a in schema.attributes], dtype=bool)
        self._cells = 0
        self._dense = DenseRows(
            [
                [quote(value) for value in a.values] if a.kind in ("nominal", "string") else None
                for a in schema.attributes
            ],
            [
                f if a.kind == "date" else None
                for a, f in zip(schema.attributes, self._formatters, strict=True)
            ],
            format_number,
        )

    def write_header(self) -> None:
        """Write ``@relation``, the attributes and ``@data``."""
        lines = [f"@relation {quote(relation_for(self.schema))}", ""]
        lines += [_attribute_line(attribute) for attribute in self.schema.attributes]
        lines += ["", "@data"]
        self.stream.write("\n".join(lines) + "\n")

    def write_block(self, values: np.ndarray, weights: np.ndarray | None = None) -> None:
        """Write instances.

        Parameters
        ----------
        values : ndarray of shape (n, n_attributes)
            Encoded as in :class:`~benchmark.dataset.Dataset`.
        weights : ndarray of shape (n,) or None
            Instance weights; those other than 1 follow their row as ``{w}``.

        Raises
        ------
        DataFormatError
            If a nominal or string column holds a code with no value, or a date is
            outside the years 1 to 9999 (nothing of the block is written then).
        """
        _check_codes(self.schema.attributes, values, self.rows_written)
        self._cells += values.size
        if not self.sparse and self._cells >= VECTORISED_MIN_CELLS:
            texts = self._arrow_text(values, weights)
        else:
            texts = self._python_text(values, weights)
        for text in texts:
            self.stream.write(text)
        self.rows_written += values.shape[0]

    def _python_text(self, values: np.ndarray, weights: np.ndarray | None) -> list[str]:
        lines = self._sparse_lines(values) if self.sparse else self._dense_lines(values)
        if weights is not None:
            for i in np.flatnonzero(weights != 1).tolist():
                lines[i] += ",{" + format_number(float(weights[i])) + "}"
        return ["\n".join(lines) + "\n"] if lines else []

    def _arrow_text(self, values: np.ndarray, weights: np.ndarray | None) -> list[str]:
        """The text of dense rows, a part at a time, made before any is written (a date that
        cannot be written fails the whole block)."""
        rows = max(1, _ARROW_CELLS // max(1, values.shape[1]))
        texts = []
        for first in range(0, values.shape[0], rows):
            suffixes = None
            if weights is not None:
                part = weights[first : first + rows]
                suffixes = {
                    i: ",{" + format_number(float(part[i])) + "}"
                    for i in np.flatnonzero(part != 1).tolist()
                }
            texts.append(self._dense.text(values[first : first + rows], suffixes))
        return texts

    def _dense_lines(self, values: np.ndarray) -> list[str]:
        columns = [
            _number_texts(values[:, j])
            if formatter is format_number
            else list(map(formatter, values[:, j].tolist()))
            for j, formatter in enumerate(self._formatters)
        ]
        return list(map(",".join, zip(*columns, strict=True))) if columns else []

    def _sparse_lines(self, values: np.ndarray) -> list[str]:
        written = (values != 0) | np.isnan(values)
        # Strings are always written: an omitted one would mean "string number 0".
        written[:, self._strings] = True
        formatters = self._formatters
        lines = []
        for row, mask in zip(values.tolist(), written, strict=True):
            cells = (f"{j} {formatters[j](row[j])}" for j in np.flatnonzero(mask).tolist())
            lines.append("{" + ",".join(cells) + "}")
        return lines


def dumps_arff(dataset: Dataset) -> str:
    """The dataset as ARFF text.

    Parameters
    ----------
    dataset : Dataset
        Any dataset; ``values`` of shape (n_instances, n_attributes).

    Returns
    -------
    str
        Header, ``@data`` and one line per instance, ending with a newline.

    Raises
    ------
    DataFormatError
        If a nominal or string column holds a code with no value, or a date is outside
        the years 1 to 9999.
    """
    stream = io.StringIO()
    writer = ArffWriter(stream, dataset.schema, sparse=dataset.sparse)
    writer.write_header()
    writer.write_block(dataset.values, dataset.weights)
    return stream.getvalue()


def write_arff(dataset: Dataset, path_or_stream: str | os.PathLike[str] | TextIO) -> None:
    """Write the dataset as an ARFF file (UTF-8, ``\\n`` line ends).

    The text is made whole before anything is written; :class:`ArffWriter` writes a
    large data set block by block instead.

    Parameters
    ----------
    dataset : Dataset
        The dataset to write.
    path_or_stream : str, path-like or text stream
        A file name (created or replaced) or an open text stream.

    Raises
    ------
    DataFormatError
        As :func:`dumps_arff`; nothing is written then.
    """
    text = dumps_arff(dataset)
    if isinstance(path_or_stream, str | os.PathLike):
        with open(path_or_stream, "w", encoding="utf-8", newline="\n") as stream:
            stream.write(text)
    else:
        path_or_stream.write(text)
