"""Reading a CSV file with a header row into a :class:`~benchmark.dataset.Dataset`.

The delimiter is whichever of ``,`` ``;`` and tab splits the first lines into the same
number of columns (the most columns wins); quoting follows RFC 4180 (a quote inside
quotes is doubled; quoted cells may hold line breaks).  Cells are stripped of surrounding
whitespace; empty cells, ``?``, ``NA``, ``NaN`` and ``nan`` are missing.

A column is numeric when every non-missing cell is a number, otherwise nominal with its
labels in order of first appearance; when most of a nominal column's cells are numbers, a
:class:`~benchmark.errors.DataWarning` names the words that made it nominal (a stray word
in a column of measurements is more likely a typo than a label).  One exception makes
class labels usable: a target column whose cells are all integers (``0``, ``1``, ``2``...)
is nominal, with its labels sorted by value, since a classifier needs a nominal target.

Columns set aside (:mod:`benchmark.io.columns`) are not typed: ignored ones are dropped
unread, and the group column's cells, as written, are the instances' groups.
"""

from __future__ import annotations

import csv
import io
import os
import re
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from touchbench.benchmark.dataset import Attribute, Dataset, Schema, resolve_targets
from touchbench.benchmark.errors import ConfigurationError, DataFormatError, DataWarning
from touchbench.benchmark.io.columns import ColumnChoice, plan_columns
from touchbench.benchmark.io.textfile import read_text_file

MISSING = frozenset({"", "?", "NA", "NaN", "nan"})
_DELIMITERS = (",", ";", "\t")
_SNIFF_LINES = 20
_INTEGER = re.compile(r"[+-]?\d+")
#: The longest line of a CSV file, in characters: a file of one long line (no line break)
#: would otherwise be parsed into millions of cells of one header row.  Rows of sequence
#: data sets are long (44 channels x 800 steps are about 700 KB), hence the room.
MAX_LINE = 8 << 20
_LONG_LINE = re.compile(rf"[^\n]{{{MAX_LINE + 1}}}")

Record = tuple[int, list[str]]


def sniff_delimiter(text: str) -> str:
    """The delimiter among ``,`` ``;`` and tab that best splits the first lines.

    Parameters
    ----------
    text : str
        The file's text.

    Returns
    -------
    str
        The delimiter giving the same number (> 1) of columns on every sampled line, the
        most columns if several do; else the one giving the header the most columns;
        ``,`` for a file of one column.
    """
    sample = "\n".join([line for line in text.splitlines() if line.strip()][:_SNIFF_LINES])
    consistent: list[tuple[int, str]] = []
    header_counts: list[tuple[int, str]] = []
    for delimiter in _DELIMITERS:
        try:
            counts = [len(row) for row in csv.reader(io.StringIO(sample), delimiter=delimiter)]
        except csv.Error:  # a field over the limit: the reading proper says where
            continue
        counts = [count for count in counts if count]
        if not counts:
            continue
        header_counts.append((counts[0], delimiter))
        if counts[0] > 1 and len(set(counts)) == 1:
            consistent.append((counts[0], delimiter))
    for candidates in (consistent, header_counts):
        best = max(candidates, key=lambda pair: pair[0], default=(1, ","))
        if best[0] > 1:
            return best[1]
    return ","


def _records(text: str, delimiter: str, source: str) -> list[Record]:
    """Non-blank records with the 1-based line each starts on."""
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter, strict=True)
    records: list[Record] = []
    start = 1
    try:
        for row in reader:
            if row and not (len(row) == 1 and not row[0].strip()):
                records.append((start, [cell.strip() for cell in row]))
            start = reader.line_num + 1
    except csv.Error as error:
        raise DataFormatError(csv_problem(error), source=source, line=reader.line_num) from None
    return records


def long_line_error(source: str, line: int) -> DataFormatError:
    """The refusal of a line longer than :data:`MAX_LINE` characters, ``\\n`` alone ending
    a line (as :func:`read_csv` finds it; the service's early refusal of an upload says the
    same)."""
    return DataFormatError(
        f"a line longer than {MAX_LINE:,} characters (a file of one line?)",
        source=source,
        line=line,
    )


def csv_problem(error: csv.Error) -> str:
    """What ``csv``'s ``error`` means, in the words of a file's author.

    A field longer than ``csv.field_size_limit()`` characters (131,072 unless raised) is
    the one error whose text names no CSV rule; the others say what rule was broken.
    """
    text = str(error)
    if text.startswith("field larger than field limit"):
        return f"a field is longer than {csv.field_size_limit():,} characters"
    return f"malformed CSV ({text})"


def _check_header(line: int, names: list[str], source: str) -> None:
    seen: set[str] = set()
    for position, name in enumerate(names, start=1):
        if not name:
            raise DataFormatError(f"column {position} has no name", source=source, line=line)
        if name in seen:
            raise DataFormatError("duplicate column name", source=source, line=line, attribute=name)
        seen.add(name)
    if all(_is_number(name) for name in names):
        raise DataFormatError(
            "no header: the first line holds numbers, not column names", source=source, line=line
        )


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _column(
    name: str, cells: list[str], lines: list[int], *, is_target: bool, source: str
) -> tuple[Attribute, np.ndarray]:
    """The attribute and codes, shape (n_rows,), of one column of stripped cells."""
    present = [cell for cell in cells if cell not in MISSING]
    words = [i for i, cell in enumerate(cells) if cell not in MISSING and not _is_number(cell)]
    labels: list[str]
    if words and len(words) < len(present) - len(words):
        _warn_stray_words(name, cells, lines, words, len(present) - len(words), source)
    if not words:
        if not (is_target and present and all(_INTEGER.fullmatch(c) for c in present)):
            numbers = [np.nan if cell in MISSING else float(cell) for cell in cells]
            return Attribute(name, "numeric", (), "numeric"), np.array(numbers, dtype=np.float64)
        labels = sorted(set(present), key=lambda label: (int(label), label))
    else:
        labels = list(dict.fromkeys(present))
    codes = {label: float(i) for i, label in enumerate(labels)}
    values = np.array([codes.get(cell, np.nan) for cell in cells], dtype=np.float64)
    return Attribute(name, "nominal", tuple(labels), "nominal"), values


def _warn_stray_words(
    name: str, cells: list[str], lines: list[int], words: list[int], numbers: int, source: str
) -> None:
    shown = ", ".join(f"'{cells[i]}' (line {lines[i]})" for i in words[:3])
    more = f" and {len(words) - 3} more" if len(words) > 3 else ""
    warnings.warn(
        DataWarning(
            f"{source}: column '{name}' is nominal because of {shown}{more}, while its other "
            f"{numbers} cells are numbers; if these are typos, fix them or write ? for a "
            "missing value"
        ),
        stacklevel=4,
    )


def read_csv(
    path: str | os.PathLike[str],
    *,
    targets: int | Sequence[str] | None = None,
    relation: str | None = None,
    source: str | None = None,
    columns: ColumnChoice | None = None,
) -> Dataset:
    """Read a CSV file whose first row names the columns.

    Parameters
    ----------
    path : str or path-like
        The file (UTF-8, else Latin-1).
    targets : int, sequence of str, or None
        ``N``: the first N columns; ``-N``: the last N; names: those columns; ``None``:
        the last column.
    relation : str, optional
        The relation name; the file name without its extension by default.
    source : str, optional
        The name messages give the file (an upload's name when ``path`` is a temporary
        copy); ``path`` by default.
    columns : ColumnChoice, optional
        The column naming each row's group and the columns left out; targets are chosen
        among all the file's columns, and may be neither.

    Returns
    -------
    Dataset
        ``values`` of shape (n_rows, n_kept), numeric and nominal attributes: every
        column but the group column and the ignored ones; ``groups`` of shape (n_rows,),
        the group column's cells as text, when there is one.

    Raises
    ------
    DataFormatError
        If the file is missing, empty, has no header, duplicate or empty column names,
        rows with another number of cells than the header, unknown targets, or a row
        without a group; the error names the file and the line.
    ColumnError
        A column choice that does not fit the file (see :func:`plan_columns`).

    Warns
    -----
    DataWarning
        When a column is nominal because of a few words among numbers.
    """
    text, named = read_text_file(path)
    source = source or named
    long_line = _LONG_LINE.search(text)  # one pass in C before any cell is made
    if long_line is not None:
        raise long_line_error(source, text.count("\n", 0, long_line.start()) + 1)
    records = _records(text, sniff_delimiter(text), source)
    if not records:
        raise DataFormatError("empty file", source=source)
    header_line, names = records[0]
    _check_header(header_line, names, source)
    try:
        target_indices = resolve_targets(-1 if targets is None else targets, names)
    except ConfigurationError as error:
        raise DataFormatError(f"targets: {error}", source=source, line=header_line) from None
    by_default = "the last column, by default" if targets is None else None
    plan = plan_columns(names, target_indices, columns, source=source, targets_by=by_default)
    rows = records[1:]
    for line, cells in rows:
        if len(cells) != len(names):
            raise DataFormatError(
                f"expected {len(names)} columns (as in the header), found {len(cells)}",
                source=source,
                line=line,
            )
    attributes = []
    lines = [line for line, _ in rows]
    values = np.empty((len(rows), len(plan.kept)))
    for position, j in enumerate(plan.kept):
        cells = [row[j] for _, row in rows]
        is_target = j in target_indices
        attribute, codes = _column(names[j], cells, lines, is_target=is_target, source=source)
        attributes.append(attribute)
        values[:, position] = codes
    groups = None
    if plan.group is not None:
        cells_of = [(line, row[plan.group]) for line, row in rows]
        groups = _group_cells(names[plan.group], cells_of, source)
    name = Path(source).stem if relation is None else relation
    schema = Schema(
        name,
        tuple(attributes),
        plan.target_indices,
        group_column=None if plan.group is None else names[plan.group],
    )
    return Dataset(schema, values, groups=groups)


def _group_cells(name: str, cells: list[tuple[int, str]], source: str) -> np.ndarray:
    """The group column's cells as written, shape (n_rows,), object; each row needs one."""
    for line, cell in cells:
        if cell in MISSING:
            raise DataFormatError(
                "no group: every row needs a value in the group column",
                source=source,
                line=line,
                attribute=name,
            )
    return np.array([cell for _, cell in cells], dtype=object)
