"""Labels files: which targets each recording's instances take.

A labels CSV has a header row, then one row per interval or per file::

    file,start,end,gesture,place        file,gesture,place
    s1.wav,0.5,1.9,tap,head             s1.wav,tap,head

``file`` is a recording's file name; ``start``/``end`` are seconds (for a ROS bag,
seconds from its first message).  An instance takes the targets of the interval of its
file it overlaps most (the earlier one on a tie); one that overlaps none is dropped and
counted.  Without ``start``/``end``, every instance of a file takes that file's targets.
An empty cell or ``?`` is a missing target value.  Rows of recordings not given are left
out, with one note counting them (a session's labels used for some of its takes); their
values stay declared.

A labels file is read as recordings are (:mod:`drivers.limits`): row by row, a line too
long refused as it streams in, and at most ``TOUCHBENCH_MAX_LABEL_ROWS`` rows (its lines
are counted first, in C, so that a file of millions of rows is refused before one is
parsed), so that its work and memory follow the rows a session can have, not the file's
size.
"""

from __future__ import annotations

import csv
import functools
import itertools
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from touchbench.app.services.limits import raised_by
from touchbench.benchmark.dataset import Attribute
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.csv import csv_problem
from touchbench.drivers.limits import LINE_CHARS, LineTooLongError, bounded_lines

_MISSING = frozenset({"", "?"})
_SPECIAL = frozenset({"file", "start", "end"})


class LabelRow(NamedTuple):
    """One row of a labels file: an interval (or the whole file) and its target values (a
    named tuple: made once per row, it is much cheaper than a frozen dataclass)."""

    line: int
    start: float
    end: float
    values: tuple[str | None, ...]


@dataclass(frozen=True)
class LabelTable:
    """A parsed labels file: target names and rows per recording file name."""

    source: str
    targets: tuple[str, ...]
    intervals: bool
    rows: dict[str, list[LabelRow]]


def long_line_error(source: str, line: int, limit: int = LINE_CHARS) -> DataFormatError:
    """The refusal of a labels file's line longer than ``limit`` characters (as
    :func:`read_labels` says it; the service's early refusal of an upload says the same)."""
    return DataFormatError(f"a line longer than {limit:,} characters", source=source, line=line)


def count_label_targets(path: Path) -> int:
    """How many target columns the header of a labels CSV names (the file is read up to
    its first non-empty row only; a file that cannot be read counts 0, and
    :func:`read_labels` says what is wrong with it)."""
    try:
        with Path(path).open(newline="", encoding="utf-8-sig") as handle:
            for _, row in _rows(handle, str(path)):
                return sum(1 for cell in row if cell.strip().lower() not in _SPECIAL)
    except (OSError, UnicodeDecodeError, csv.Error, LineTooLongError):
        pass
    return 0


def read_labels(path: Path, *, max_rows: int | None = None) -> LabelTable:
    """Parse a labels CSV (see the module docstring), row by row.

    Parameters
    ----------
    path : Path
    max_rows : int, optional
        Most rows after the header (by default the setting ``TOUCHBENCH_MAX_LABEL_ROWS``).

    Raises
    ------
    DataFormatError
        Missing file or columns, a row of the wrong width, a bad time, a file labelled
        twice, overlapping intervals of one file, a line too long or too many rows; with
        the line number.
    """
    if max_rows is None:
        # start-up time: a command that lists or shows reads no settings (pydantic-settings)
        from touchbench.app.settings import get_settings

        max_rows = get_settings().max_label_rows
    source = str(path)
    line = 0
    try:
        _check_lines(Path(path), max_rows, source)
        with Path(path).open(newline="", encoding="utf-8-sig") as handle:
            rows = _rows(handle, source)
            first = next(rows, None)
            if first is None:
                raise DataFormatError("the labels file is empty", source=source)
            line = first[0]
            columns = _Columns.of(first[1], source, line)
            by_file: dict[str, list[LabelRow]] = {}
            for count, (line, row) in enumerate(rows, 1):
                if count > max_rows:
                    raise _too_many(max_rows, source, line)
                entry = columns.row(row, source, line)
                by_file.setdefault(entry[0], []).append(entry[1])
    except FileNotFoundError:
        raise DataFormatError("no such labels file", source=source) from None
    except (OSError, UnicodeDecodeError) as error:
        raise DataFormatError(f"cannot read the labels file: {error}", source=source) from None
    except csv.Error as error:
        raise DataFormatError(csv_problem(error), source=source, line=line + 1) from None
    except LineTooLongError as error:
        raise long_line_error(source, error.line, error.limit) from None
    if not by_file:
        raise DataFormatError("the labels file has a header but no rows", source=source)
    for file_name, entries in by_file.items():
        _check_overlaps(file_name, entries, columns.intervals, source)
    return LabelTable(
        source=source, targets=columns.targets, intervals=columns.intervals, rows=by_file
    )


@functools.lru_cache(maxsize=4096)
def _file_name(cell: str) -> str:
    """The file name a cell names (folders left out); rows name few files, many times."""
    return Path(cell.strip()).name


def _too_many(max_rows: int, source: str, line: int | None) -> DataFormatError:
    return DataFormatError(
        f"more than {max_rows:,} rows, the most a labels file may have" + raised_by("label_rows"),
        source=source,
        line=line,
    )


def _check_lines(path: Path, max_rows: int, source: str) -> None:
    """Refuse a file with more lines holding something than a header and ``max_rows``
    rows, counted in blocks of bytes (array operations, no row parsed) before any row is
    parsed: a file of millions of rows costs milliseconds, not a parse of its first rows
    with the GIL held.  (A row whose quoted field holds a line break counts as two.)"""
    lines = 0
    before = np.frombuffer(b"\n", dtype=np.uint8)  # as if a line break came before the file
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            codes = np.frombuffer(block, dtype=np.uint8)
            codes = np.concatenate([before, codes[codes != 13]])  # "\r\n" ends a line as "\n"
            # a line break after something else than a line break ends a line that holds
            # something
            lines += int(np.count_nonzero((codes[1:] == 10) & (codes[:-1] != 10)))
            before = codes[-1:]
            if lines > max_rows + 1:
                raise _too_many(max_rows, source, None)


def _rows(handle: Iterator[str], source: str) -> Iterator[tuple[int, list[str]]]:
    """``(line number, cells)`` of the rows that are not empty, each line bounded."""
    reader = csv.reader(bounded_lines(handle, limit=LINE_CHARS, source=source))  # type: ignore[arg-type]
    for row in reader:
        if any(cell.strip() for cell in row):
            yield reader.line_num, row


@dataclass(frozen=True)
class _Columns:
    """Where the header puts the file, the interval and the targets."""

    width: int
    file: int
    interval: tuple[int, int] | None
    target_columns: tuple[int, ...]
    targets: tuple[str, ...]

    @property
    def intervals(self) -> bool:
        return self.interval is not None

    @classmethod
    def of(cls, cells: list[str], source: str, line: int) -> _Columns:
        header = [cell.strip() for cell in cells]
        columns = {cell.lower(): i for i, cell in enumerate(header)}
        if len(columns) != len(header):
            raise DataFormatError("a column name appears twice", source=source, line=line)
        if "file" not in columns:
            raise DataFormatError(
                "no 'file' column (expected file,start,end,TARGET... or file,TARGET...)",
                source=source,
                line=line,
            )
        if ("start" in columns) != ("end" in columns):
            missing = "end" if "start" in columns else "start"
            raise DataFormatError(
                f"has one of start/end but no '{missing}' column", source=source, line=line
            )
        interval = (columns["start"], columns["end"]) if "start" in columns else None
        special = {columns["file"], *(interval or ())}
        target_columns = tuple(i for i in range(len(header)) if i not in special)
        if not target_columns:
            raise DataFormatError(
                "no target column after file" + (",start,end" if interval else ""),
                source=source,
                line=line,
            )
        return cls(
            width=len(header),
            file=columns["file"],
            interval=interval,
            target_columns=target_columns,
            targets=tuple(header[i] for i in target_columns),
        )

    def row(self, row: list[str], source: str, line: int) -> tuple[str, LabelRow]:
        """The file a row names and what it says of it."""
        if len(row) != self.width:
            raise DataFormatError(
                f"has {len(row)} fields, the header has {self.width}", source=source, line=line
            )
        file_name = _file_name(row[self.file])
        if not file_name:
            raise DataFormatError("empty file name", source=source, line=line, attribute="file")
        start, end = 0.0, math.inf
        if self.interval is not None:
            start = _seconds(row[self.interval[0]], source, line, "start")
            end = _seconds(row[self.interval[1]], source, line, "end")
            if end <= start:
                raise DataFormatError(
                    f"end ({end:g}) must be after start ({start:g})", source=source, line=line
                )
        values = tuple(
            None if row[i].strip() in _MISSING else row[i].strip() for i in self.target_columns
        )
        return file_name, LabelRow(line, start, end, values)


def _seconds(text: str, source: str, line: int, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise DataFormatError(
            f"{text.strip()!r} is not a number of seconds",
            source=source,
            line=line,
            attribute=column,
        ) from None
    if not math.isfinite(value) or value < 0:
        raise DataFormatError(
            f"{text.strip()!r} is not a time of at least 0 s",
            source=source,
            line=line,
            attribute=column,
        )
    return value


def _check_overlaps(file_name: str, entries: list[LabelRow], intervals: bool, source: str) -> None:
    if not intervals:
        if len(entries) > 1:
            raise DataFormatError(
                f"'{file_name}' is labelled again (first on line {entries[0].line})",
                source=source,
                line=entries[1].line,
            )
        return
    ordered = sorted(entries, key=lambda entry: entry.start)
    for before, after in itertools.pairwise(ordered):
        if after.start < before.end:
            first, second = sorted((before.line, after.line))
            raise DataFormatError(
                f"interval of '{file_name}' overlaps the one on line {first} "
                f"({before.start:g}-{before.end:g} s and {after.start:g}-{after.end:g} s)",
                source=source,
                line=second,
            )


def other_recordings(table: LabelTable, recordings: Mapping[str, Path]) -> str:
    """A note counting the rows of recordings not given ("" if there are none): a
    session's labels used for a subset of its takes.  Those rows label nothing, but their
    target values stay declared, so that the data sets of a session's subsets agree.

    Raises
    ------
    DataFormatError
        When no row names a recording given: the labels are for other recordings.
    """
    other = sorted(name for name in table.rows if name not in recordings)
    if not other:
        return ""
    count = sum(len(table.rows[name]) for name in other)
    if len(other) == len(table.rows):
        raise DataFormatError(
            f"names none of the {len(recordings)} recording(s) given "
            f"({few(sorted(recordings))}); it names {few(other)}",
            source=table.source,
            attribute="file",
        )
    return (
        f"{Path(table.source).name}: {count} row(s) of {len(other)} recording(s) not given "
        f"were left out ({few(other)})"
    )


def label_instances(
    table: LabelTable,
    spans: Sequence[tuple[str, float, float]],
    recordings: Mapping[str, Path],
) -> tuple[np.ndarray, list[Attribute], np.ndarray, list[str]]:
    """Which instances are kept, the target attributes, their codes, and warnings."""
    chosen: list[LabelRow | None] = []
    for file_name, start, end in spans:
        best, best_overlap = None, 0.0
        for row in table.rows.get(file_name, ()):
            overlap = min(end, row.end) - max(start, row.start)
            if overlap > best_overlap:
                best, best_overlap = row, overlap
        chosen.append(best)
    labels_in_order: list[list[str]] = [[] for _ in table.targets]
    for rows in table.rows.values():
        for row in sorted(rows, key=lambda r: r.line):
            for values, value in zip(labels_in_order, row.values, strict=True):
                if value is not None and value not in values:
                    values.append(value)
    attributes = [
        Attribute(target, "nominal", values=tuple(values), declared_type="nominal")
        for target, values in zip(table.targets, labels_in_order, strict=True)
    ]
    codes = np.full((len(spans), len(attributes)), np.nan)
    for i, match in enumerate(chosen):
        if match is None:
            continue
        for j, value in enumerate(match.values):
            if value is not None:
                codes[i, j] = attributes[j].values.index(value)
    keep = np.array([row is not None for row in chosen], dtype=bool)
    unlabelled = [file_name for file_name in recordings if file_name not in table.rows]
    warnings = []
    if unlabelled:
        warnings.append(
            f"{len(unlabelled)} recording(s) have no labels; their instances were dropped "
            f"({few(unlabelled)})"
        )
    return keep, attributes, codes, warnings


def few(names: Sequence[str], shown: int = 3) -> str:
    """At most ``shown`` names, then how many more: messages stay one short line."""
    text = ", ".join(str(name) for name in names[:shown])
    return text + (f" and {len(names) - shown} more" if len(names) > shown else "")
