"""The data section of an ARFF file, line by line, exactly as WEKA reads it.

Each attribute has a column decoder from the text of a value to its float code (see
:mod:`benchmark.dataset`).  :class:`DataSection` reads lines into rows: a line without
double quotes, backslashes, braces or comments (nearly every line of a real data set) is
split on commas and decoded a column at a time; any other line, and any block of lines
that split cannot take on its own, goes through WEKA's tokenizer
(:mod:`benchmark.io.tokens`), which is also what reports errors, so both ways accept
exactly the same files.  String tables grow as rows are read, in order of first
appearance.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from touchbench.benchmark.dataset import Attribute, InstanceBlock
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.dates import DateFormat
from touchbench.benchmark.io.tokens import (
    CLOSE,
    OPEN,
    QUOTED,
    SEPARATORS,
    WORD,
    WORD_PATTERN,
    LineError,
    Token,
    describe,
    shortlist,
    tokenize,
)

_PLAIN_WORD = re.compile(WORD_PATTERN)
# A line that contains none of these can be split on commas (see _simple_block).
_NOT_SIMPLE = re.compile(r"""["\\{}%]""")
_SEPARATORS = SEPARATORS
_BLOCK_ROWS = 2048


class Column(Protocol):
    name: str

    def decode(self, text: str) -> float:
        """The code of one unquoted, non-missing value; raises LineError."""

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        """Codes of comma-split pieces of simple rows, ``None`` if any needs the tokenizer.

        Must not change the column's state when it returns ``None``.
        """

    def attribute(self) -> Attribute:
        """The attribute as read (string attributes get their string table)."""


def _simple_text(piece: str) -> str | None:
    """The value of a comma-split piece of a simple row; ``None`` if it needs the tokenizer.

    A missing value gives ``"?"``; since a quoted ``'?'`` gives ``None`` the two differ.
    """
    piece = piece.strip(_SEPARATORS)
    if piece.startswith("'"):
        if len(piece) >= 2 and piece.endswith("'") and "'" not in piece[1:-1]:
            return piece[1:-1] if piece != "'?'" else None
        return None
    return piece if _PLAIN_WORD.fullmatch(piece) else None


@dataclass
class NumericColumn:
    name: str
    declared: Attribute

    def decode(self, text: str) -> float:
        try:
            return float(text)
        except ValueError:
            raise LineError(f"'{text}' is not a number", self.name) from None

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        try:
            return np.array(pieces, dtype=np.float64)
        except ValueError:
            pass
        if "?" not in pieces:
            return None
        try:
            return np.array([p if p != "?" else "nan" for p in pieces], dtype=np.float64)
        except ValueError:
            return None

    def attribute(self) -> Attribute:
        return self.declared


@dataclass
class NominalColumn:
    name: str
    declared: Attribute
    codes: dict[str, float] = field(init=False)
    piece_codes: dict[str, float] = field(init=False)

    def __post_init__(self) -> None:
        labels = self.declared.values
        self.codes = {label: float(i) for i, label in enumerate(labels)}
        self.piece_codes = {"?": np.nan}
        for i, label in enumerate(labels):
            if "'" not in label and "," not in label:
                self.piece_codes[f"'{label}'"] = float(i)
            if label != "?" and _PLAIN_WORD.fullmatch(label):
                self.piece_codes[label] = float(i)

    def decode(self, text: str) -> float:
        code = self.codes.get(text)
        if code is None:
            raise LineError(
                f"'{text}' is not one of the declared values {shortlist(self.declared.values)}",
                self.name,
            )
        return code

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        lookup = self.piece_codes
        try:
            return np.array([lookup[p] for p in pieces])
        except KeyError:
            pass
        try:
            return np.array([lookup[p.strip(_SEPARATORS)] for p in pieces])
        except KeyError:
            return None

    def attribute(self) -> Attribute:
        return self.declared


@dataclass
class StringColumn:
    name: str
    declared: Attribute
    table: dict[str, int] = field(default_factory=dict)

    def decode(self, text: str) -> float:
        code = self.table.get(text)
        if code is None:
            code = self.table[text] = len(self.table)
        return float(code)

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        texts = self.texts(pieces)
        return None if texts is None else self.decode_texts(texts)

    @staticmethod
    def texts(pieces: Sequence[str]) -> list[str] | None:
        """First half of :meth:`decode_pieces`: the texts, without touching the table."""
        texts = [_simple_text(piece) for piece in pieces]
        return None if None in texts else texts  # type: ignore[return-value]

    def decode_texts(self, texts: list[str]) -> np.ndarray:
        """Second half of :meth:`decode_pieces`: codes, adding new strings to the table."""
        return np.array([np.nan if text == "?" else self.decode(text) for text in texts])

    def attribute(self) -> Attribute:
        return Attribute(self.name, "string", tuple(self.table), self.declared.declared_type)


@dataclass
class DateColumn:
    name: str
    declared: Attribute
    date_format: DateFormat = field(init=False)

    def __post_init__(self) -> None:
        self.date_format = DateFormat(self.declared.date_format)

    def decode(self, text: str) -> float:
        try:
            return self.date_format.parse(text)
        except ValueError as error:
            raise LineError(str(error), self.name) from None

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        texts = [_simple_text(p) for p in pieces]
        if None in texts:
            return None
        try:
            return np.array(
                [np.nan if t == "?" else self.date_format.parse(t) for t in texts]  # type: ignore[arg-type]
            )
        except ValueError:
            return None

    def attribute(self) -> Attribute:
        return self.declared


def make_column(attribute: Attribute) -> Column:
    if attribute.kind == "numeric":
        return NumericColumn(attribute.name, attribute)
    if attribute.kind == "nominal":
        return NominalColumn(attribute.name, attribute)
    if attribute.kind == "string":
        return StringColumn(attribute.name, attribute)
    return DateColumn(attribute.name, attribute)


# ---------------------------------------------------------------------------------- rows


def _decode(column: Column, token: Token) -> float:
    kind, text = token
    if kind == WORD and text == "?":
        return np.nan
    return column.decode(text)


def _weight(tokens: list[Token], start: int) -> float:
    """The instance weight ``{w}`` at ``tokens[start]``, which must end the row."""
    rest = tokens[start:]
    if len(rest) != 3 or rest[0][0] != OPEN or rest[2][0] != CLOSE or rest[1][0] != WORD:
        raise LineError("after the values a row may only have an instance weight such as {0.5}")
    try:
        weight = float(rest[1][1])
    except ValueError:
        raise LineError(f"instance weight '{rest[1][1]}' is not a number") from None
    if not weight >= 0:
        raise LineError(f"instance weight {rest[1][1]} is negative or not a number")
    return weight


def _dense_row(tokens: list[Token], columns: list[Column]) -> tuple[np.ndarray, float | None]:
    n = len(columns)
    end = next((i for i, token in enumerate(tokens) if token[0] in (OPEN, CLOSE)), len(tokens))
    if end != n:
        raise LineError(f"expected {n} values, found {end}")
    row = np.array([_decode(column, token) for column, token in zip(columns, tokens, strict=False)])
    weight = _weight(tokens, end) if end < len(tokens) else None
    return row, weight


def _sparse_row(
    tokens: list[Token], columns: list[Column]
) -> tuple[np.ndarray, float | None, set[int]]:
    """The values and weight of a sparse row, and the indices it gives explicitly."""
    n = len(columns)
    row = np.zeros(n)
    given: set[int] = set()
    previous = -1
    position = 1
    while True:
        if position >= len(tokens):
            raise LineError("sparse row has no closing '}'")
        kind, text = tokens[position]
        if kind == CLOSE:
            position += 1
            break
        if kind != WORD:
            raise LineError(f"expected a sparse index, found {describe(tokens[position])}")
        try:
            index = int(text)
        except ValueError:
            raise LineError(f"sparse index '{text}' is not an integer") from None
        if not 0 <= index < n:
            raise LineError(f"sparse index {index} is out of range 0..{n - 1}")
        if index <= previous:
            raise LineError(f"sparse indices must increase: {index} comes after {previous}")
        if position + 1 >= len(tokens) or tokens[position + 1][0] not in (WORD, QUOTED):
            raise LineError(f"sparse index {index} has no value", columns[index].name)
        row[index] = _decode(columns[index], tokens[position + 1])
        given.add(index)
        previous = index
        position += 2
    weight = _weight(tokens, position) if position < len(tokens) else None
    return row, weight, given


@dataclass
class _Rows:
    """Rows of one stretch of lines, in order: blocks of values, weights, line numbers."""

    blocks: list[np.ndarray] = field(default_factory=list)
    lines: list[np.ndarray] = field(default_factory=list)
    weights: dict[int, float] = field(default_factory=dict)
    count: int = 0

    def add_block(self, block: np.ndarray, lines: np.ndarray) -> None:
        self.blocks.append(block)
        self.lines.append(lines)
        self.count += block.shape[0]

    def add_row(self, row: np.ndarray, weight: float | None, line: int) -> None:
        if weight is not None:
            self.weights[self.count] = weight
        self.add_block(row[np.newaxis, :], np.array([line]))

    def block(self, n_columns: int) -> InstanceBlock:
        values = np.vstack(self.blocks) if self.blocks else np.empty((0, n_columns))
        lines = np.concatenate(self.lines) if self.lines else np.empty(0, dtype=np.int64)
        weights = None
        if self.weights:
            weights = np.ones(self.count)
            weights[list(self.weights)] = list(self.weights.values())
        return InstanceBlock(values, weights=weights, lines=lines)


class DataSection:
    """Decodes the lines of a data section into rows, one stretch of lines at a time.

    Parameters
    ----------
    attributes : sequence of Attribute
        The declared attributes.
    source : str
        The file name, for error messages.

    Attributes
    ----------
    columns : list of Column
        One decoder per attribute; string columns hold the string tables read so far.
    sparse : bool
        Whether some row so far was sparse.
    """

    def __init__(self, attributes: Sequence[Attribute], source: str) -> None:
        self.columns: list[Column] = [make_column(attribute) for attribute in attributes]
        self.source = source
        self.sparse = False
        self._implicit_strings: set[int] = set()  # string columns a sparse row left out
        self._string_indices = [
            j for j, column in enumerate(self.columns) if isinstance(column, StringColumn)
        ]

    def read(self, lines: Sequence[str], first_line: int, *, split: bool = True) -> InstanceBlock:
        """The rows of consecutive lines.

        Parameters
        ----------
        lines : sequence of str
            Lines without their line breaks; blank and comment lines give no row.
        first_line : int
            The 1-based line number of ``lines[0]``.
        split : bool
            Whether simple lines may be split on commas; ``False`` sends every line
            through the tokenizer (the reference the faster ways are tested against).

        Returns
        -------
        InstanceBlock
            ``values`` of shape (n_rows, n_attributes), ``weights`` (``None`` unless a
            row has one) and ``lines``, each row's line number.

        Raises
        ------
        DataFormatError
            For the first line that is wrong, naming it and the attribute.
        """
        rows = _Rows()
        simple: list[int] = []  # indices of consecutive simple lines not yet read
        for index, line in enumerate(lines):
            if split and _NOT_SIMPLE.search(line) is None:
                if line.strip():
                    simple.append(index)
                    if len(simple) >= _BLOCK_ROWS:
                        self._read_simple(lines, simple, first_line, rows)
                continue
            if simple:
                self._read_simple(lines, simple, first_line, rows)
            self._read_tokenized(lines[index], first_line + index, rows)
        if simple:
            self._read_simple(lines, simple, first_line, rows)
        return rows.block(len(self.columns))

    def finish(self) -> tuple[Attribute, ...]:
        """The attributes once every row was read (string tables complete).

        A sparse row that leaves out a string value means string number 0, so a string
        table left empty gets the empty string.
        """
        for j in self._implicit_strings:
            column = self.columns[j]
            assert isinstance(column, StringColumn)
            if not column.table:
                column.decode("")
        return self.attributes()

    def attributes(self) -> tuple[Attribute, ...]:
        """The attributes as read so far."""
        return tuple(column.attribute() for column in self.columns)

    def _read_simple(
        self, lines: Sequence[str], simple: list[int], first_line: int, rows: _Rows
    ) -> None:
        block = _simple_block([lines[i] for i in simple], self.columns)
        if block is None:
            for index in simple:
                self._read_tokenized(lines[index], first_line + index, rows)
        else:
            rows.add_block(block, first_line + np.array(simple))
        simple.clear()

    def _read_tokenized(self, line: str, number: int, rows: _Rows) -> None:
        try:
            tokens = tokenize(line)
            if not tokens:
                return
            if tokens[0][0] == OPEN:
                self.sparse = True
                row, weight, given = _sparse_row(tokens, self.columns)
                self._implicit_strings.update(j for j in self._string_indices if j not in given)
            else:
                row, weight = _dense_row(tokens, self.columns)
        except LineError as problem:
            raise DataFormatError(
                problem.message, source=self.source, line=number, attribute=problem.attribute
            ) from None
        rows.add_row(row, weight, number)


def _simple_block(lines: list[str], columns: list[Column]) -> np.ndarray | None:
    """Rows of non-blank lines without braces, double quotes, backslashes or comments.

    Returns
    -------
    ndarray of shape (len(lines), len(columns)) or None
        ``None`` when some line needs the tokenizer (which then reads or rejects it).
    """
    n = len(columns)
    pieces = [line.split(",") for line in lines]
    if any(len(row) != n for row in pieces):
        return None
    block = np.empty((len(lines), n))
    cells = list(zip(*pieces, strict=True))
    strings: list[tuple[int, StringColumn, list[str]]] = []
    for j, column in enumerate(columns):
        if isinstance(column, StringColumn):
            texts = column.texts(cells[j])
            if texts is None:
                return None
            strings.append((j, column, texts))
            continue
        decoded = column.decode_pieces(cells[j])
        if decoded is None:
            return None
        block[:, j] = decoded
    # String tables grow only once the whole block is known to be readable.
    for j, column, texts in strings:
        block[:, j] = column.decode_texts(texts)
    return block
