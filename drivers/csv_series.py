"""CSV time series: one row per sample, one column per channel, perhaps a time column.

* A header row names the channels (``pac1``, ``ele3``...), which are kept; a file whose
  first row is all numbers has none (channels are then numbered).
* A time column is found by its name (:data:`TIME_COLUMNS`, any case) or given
  (``time_column``); it is never a channel.  Its stamps are seconds, or nanoseconds
  when they are that large (:func:`stamps_in_seconds`).  Stamps even to 1 % give the
  sample rate (the given one, if they agree with it to 1 %); uneven ones (real drivers
  jitter) are resampled onto an even grid at the given sample rate, else at their mean
  rate (:class:`drivers.resample.Jitter`; :func:`drivers.resample.resample_even`), and a
  note says how uneven they were.
* A delimiter at the end of every row (a trailing comma) is accepted.
* With a time column, a row equal to the one before in every column (a sample logged
  twice) is left out with a note; the same stamp with other values is refused.
* ``channels`` picks columns by name (or 1-based number among the channels).
* Work follows the file's size, not what its values say (:class:`drivers.limits.ReadLimits`):
  a line too long is refused as it streams in, the values read or resampled are bounded,
  and a gap between stamps that resampling would fill with too many samples is refused,
  naming its line; so are stamps that are NaN, infinite or do not rise.

Every problem is a :class:`~drivers.errors.DriverError` naming the file, and the line
and column where there is one.
"""

from __future__ import annotations

import bisect
import copy
import csv
import itertools
from array import array
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from touchbench.drivers.errors import DriverError
from touchbench.drivers.limits import ReadLimits, bounded_lines
from touchbench.drivers.resample import check_grid, jitter_of, resample_even

#: Names of a time column, lower case: the common ones and those ROS tools write
#: (``rostopic echo -p`` writes ``%time`` and ``field.header.stamp``, in nanoseconds).
TIME_COLUMNS = frozenset(
    {
        "time",
        "t",
        "timestamp",
        "timestamps",
        "time_stamp",
        "stamp",
        "header.stamp",
        "field.header.stamp",
        "%time",
        "ros_time",
        "rostime",
        "time_s",
        "time_ns",
        "timestamp_ns",
        "t_ns",
    }
)
#: Stamps larger than this (in absolute value), or steps longer than :data:`NS_STEP`, are
#: nanoseconds: 1e11 s is more than 3000 years, 1e3 s between two samples is no series.
NS_MAGNITUDE = 1e11
NS_STEP = 1e3
#: Seconds per unit of a time column, by the unit's name (``auto``: seconds or nanoseconds,
#: told apart by magnitude).
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
#: A median step longer than this, in seconds, is said in a note: few sensors sample
#: slower than once a second, and stamps in milliseconds read as seconds look like that.
SLOW_STEP = 1.0
#: Steps within this fraction of the median step count as even.
EVEN = 0.01


@dataclass(frozen=True)
class CsvSeries:
    """What :func:`read_csv_series` read.

    Parameters
    ----------
    samples : ndarray of shape (n_channels, n_samples), float64
    samplerate : float or None
        From the time column, or the given one; None when neither says it.
    channels : tuple of str or None
        The channels' names from the header, None without a header.
    notes : tuple of str
        What was done on reading (resampling, the time column's unit).
    resampled : bool
        True when uneven stamps were put on a grid at a rate chosen here (none given).
    """

    samples: np.ndarray
    samplerate: float | None
    channels: tuple[str, ...] | None
    notes: tuple[str, ...]
    resampled: bool = False


def read_csv_series(
    path: Path,
    *,
    samplerate: float | None = None,
    time_column: str | None = None,
    time_unit: str = "auto",
    channels: Sequence[str] | None = None,
    limits: ReadLimits | None = None,
) -> CsvSeries:
    """Read a CSV time series (see the module docstring).

    Parameters
    ----------
    path : Path
        A ``.csv`` (comma), ``.tsv`` (tab) or ``.txt`` (comma) file.
    samplerate : float, optional
        Hz: the rate of a file without a time column, or the grid uneven stamps are
        resampled onto.
    time_column : str, optional
        The time column's name, when it has none of the usual ones.
    time_unit : {"auto", "s", "ms", "us", "ns"}
        The time column's unit; ``auto``: seconds or nanoseconds, by magnitude.
    channels : sequence of str, optional
        The columns to keep as channels, by name or 1-based number; all by default.
    limits : ReadLimits, optional
        The bounds of the work (by default :class:`~drivers.limits.ReadLimits`'s).

    Raises
    ------
    DriverError
        Naming the file, and the line where there is one.
    """
    limits = limits or ReadLimits()
    table = _read_table(
        path, limits, lambda header, width: _layout(path, header, width, time_column, channels)
    )
    layout, samples, lines = table.layout, table.samples, table.lines
    names, time = layout.names, layout.time
    kept_names = tuple(names[i] for i in layout.picked) if table.header is not None else None
    if time is None or table.times is None:
        return CsvSeries(samples, samplerate, kept_names, ())
    times, repeated = table.times, None
    if table.repeats:
        repeated = (
            f"{len(table.repeats)} row(s) repeat the row before, stamp and values (from line "
            f"{lines[table.repeats[0]]}): left out as logged twice"
        )
        dropped = np.zeros(len(lines), dtype=bool)
        dropped[np.frombuffer(table.repeats, dtype=np.int64)] = True
        lines = lines.without(dropped)
    _check_stamps(path, names[time], times, lines)
    unit = _to_seconds(times, time_unit)
    rate, samples, notes, step = _on_even_grid(
        path, names[time], times, lines, samples, samplerate, limits
    )
    resampled = samplerate is None and bool(notes)  # the grid's notes only
    if repeated is not None:
        notes.insert(0, repeated)
    if time_unit == "auto" and unit != "s":
        notes.insert(0, f"column '{names[time]}' holds nanoseconds")
    if time_unit == "auto" and unit == "s" and step > SLOW_STEP:
        notes.insert(
            0,
            f"column '{names[time]}' read as seconds: {step:g} s between samples "
            f"({1 / step:.3g} Hz); if its stamps are milliseconds, give the time unit (ms)",
        )
    return CsvSeries(samples, rate, kept_names, tuple(notes), resampled)


def stamps_in_seconds(stamps: np.ndarray, unit: str = "auto") -> tuple[np.ndarray, str]:
    """Stamps of shape (n,) as seconds from the first one, and their unit.

    ``unit`` is one of :data:`TIME_UNITS` or ``auto``: then nanoseconds are told from
    seconds by magnitude, stamps beyond :data:`NS_MAGNITUDE` or a median step beyond
    :data:`NS_STEP` (ROS stamps since 1970 in nanoseconds are about 1.7e18; in seconds
    about 1.7e9).
    """
    seconds = np.array(stamps, dtype=np.float64)  # a copy: the stamps given stay
    return seconds, _to_seconds(seconds, unit)


def _to_seconds(stamps: np.ndarray, unit: str) -> str:
    """Turn ``stamps`` (float64, shape (n,)) in place into seconds from the first one, as
    :func:`stamps_in_seconds` says; their unit.  In place, and no temporary array but one
    of the steps: the time column of a long recording is read once, not copied."""
    first = stamps[0]
    if unit == "auto":
        # The largest |stamp| without an array of them; NaN compares false either way.
        largest = max(float(stamps.max()), -float(stamps.min()))
        step = float(np.median(np.diff(stamps), overwrite_input=True)) if stamps.size > 1 else 0.0
        unit = "ns" if largest > NS_MAGNITUDE or step > NS_STEP else "s"
        factor = 1e-9 if unit == "ns" else None
    else:
        factor = TIME_UNITS[unit]
    np.subtract(stamps, first, out=stamps)
    if factor is not None:
        np.multiply(stamps, factor, out=stamps)
    return unit


#: Rows parsed into one block of floats at a time (text is never held for the whole file).
ROWS_PER_BLOCK = 4096
#: Values moved at a time when the columns are closed up (:meth:`_Columns.samples`).
MOVE_VALUES = 1 << 16


class LineNumbers:
    """Each row's line number in its file, kept as runs of consecutive lines: a file of one
    row per line costs two numbers, whatever its length; a blank line or a quoted field
    over several lines starts another run.
    """

    def __init__(self) -> None:
        self._starts = array("q")  # the row that starts each run
        self._firsts = array("q")  # that row's line
        self._count = 0
        self.last = 0  # the line of the last row appended (0: none yet)
        self._rows: np.ndarray | None = None  # rows kept by `without`, shape (n_kept,)

    def append(self, line: int) -> None:
        """The next row is on ``line``."""
        if line != self.last + 1 or not self._count:
            self._starts.append(self._count)
            self._firsts.append(line)
        self.last = line
        self._count += 1

    def __len__(self) -> int:
        return self._count if self._rows is None else int(self._rows.size)

    def __getitem__(self, row: int) -> int:
        """The line of row ``row`` (of the rows kept)."""
        if self._rows is not None:
            row = int(self._rows[row])
        run = bisect.bisect_right(self._starts, row) - 1
        return int(self._firsts[run] + row - self._starts[run])

    def without(self, dropped: np.ndarray) -> LineNumbers:
        """The line numbers of the rows not ``dropped`` (a boolean mask over the rows)."""
        kept = copy.copy(self)  # the runs are shared: nothing is appended once read
        rows = np.flatnonzero(~dropped)
        kept._rows = rows if self._rows is None else self._rows[rows]
        return kept


@dataclass(frozen=True)
class _Layout:
    """Where a file's columns go: ``names`` of every column, the ``time`` column's index
    (None without one), the ``picked`` columns' indices, in the channels' order."""

    names: list[str]
    time: int | None
    picked: list[int]


def _layout(
    path: Path,
    header: list[str] | None,
    width: int,
    time_column: str | None,
    channels: Sequence[str] | None,
) -> _Layout:
    """The :class:`_Layout` of a file of ``width`` columns under ``header``."""
    names = header if header is not None else [f"column {i + 1}" for i in range(width)]
    time = _time_column(path, header, time_column)
    signal = [i for i in range(len(names)) if i != time]
    if not signal:
        raise DriverError(f"{path}: has a time column but no signal column")
    picked = signal if not channels else _pick(path, names, signal, channels, header is not None)
    return _Layout(names, time, picked)


class _Columns:
    """The picked columns of the rows read, put straight into their final layout: the
    samples of shape (n_channels, capacity) and the time column of shape (capacity,), filled
    block by block.  ``capacity`` is what the file's lines allow (:func:`_count_lines`), so
    that the arrays are allocated once and only what is read is ever touched (an ``empty``
    array's pages cost no memory until written); a file that outgrows it (a pipe, a file
    still being written) has its arrays grown to twice the size, copied.

    With a time column, a row equal to the row before in every column (all of the file's,
    not only the picked ones) is not kept, and its index among the rows read is in
    :attr:`repeats`.
    """

    def __init__(self, layout: _Layout, capacity: int) -> None:
        self.picked, self.time = layout.picked, layout.time
        self.capacity = capacity
        self.count = 0  # rows kept
        self.read = 0  # rows read
        self.repeats = array("q")
        self._flat = np.empty(len(self.picked) * capacity)
        self._times = np.empty(capacity) if self.time is not None else None
        self._last: np.ndarray | None = None  # the last row read, every column

    def add(self, block: list[list[float]]) -> None:
        """Keep the rows of ``block`` (each row's every column, as floats)."""
        values = np.array(block)
        first, self.read = self.read, self.read + len(block)
        if self.time is not None:
            repeats = np.empty(values.shape[0], dtype=bool)
            repeats[0] = self._last is not None and bool((values[0] == self._last).all())
            repeats[1:] = (values[1:] == values[:-1]).all(axis=1)
            self._last = values[-1].copy()
            if repeats.any():
                self.repeats.extend((np.flatnonzero(repeats) + first).tolist())
                values = values[~repeats]
        start, stop = self.count, self.count + values.shape[0]
        if stop > self.capacity:
            self._grow(max(stop, 2 * self.capacity))
        samples = self._flat.reshape(len(self.picked), self.capacity)
        samples[:, start:stop] = values[:, self.picked].T
        if self._times is not None:
            self._times[start:stop] = values[:, self.time]
        self.count = stop

    def _grow(self, capacity: int) -> None:
        flat = np.empty(len(self.picked) * capacity)
        kept = self._flat.reshape(len(self.picked), self.capacity)[:, : self.count]
        flat.reshape(len(self.picked), capacity)[:, : self.count] = kept
        self._flat = flat
        if self._times is not None:
            times = np.empty(capacity)
            times[: self.count] = self._times[: self.count]
            self._times = times
        self.capacity = capacity

    def samples(self) -> np.ndarray:
        """The samples kept, shape (n_channels, n_rows), C order: the channels are moved
        down to close the capacity left unused, a bounded piece at a time, and the array
        shrunk in place to their size."""
        flat, n, capacity = self._flat, self.count, self.capacity
        if n < capacity:
            for channel in range(1, len(self.picked)):
                to, at = channel * n, channel * capacity
                for start in range(0, n, MOVE_VALUES):
                    stop = min(n, start + MOVE_VALUES)
                    flat[to + start : to + stop] = flat[at + start : at + stop]
            flat.resize(len(self.picked) * n, refcheck=False)  # nothing else refers to it
        return flat.reshape(len(self.picked), n)

    def times(self) -> np.ndarray | None:
        """The time column of the rows kept, shape (n_rows,), or None without one."""
        if self._times is not None and self.count < self.capacity:
            self._times.resize(self.count, refcheck=False)
        return self._times


@dataclass(frozen=True)
class _Table:
    """What :func:`_read_table` read."""

    header: list[str] | None
    layout: _Layout
    samples: np.ndarray  # (n_channels, n_rows), float64, C order
    times: np.ndarray | None  # (n_rows,), the time column, or None without one
    lines: LineNumbers  # of every row read, repeats included
    repeats: array[int]  # the rows read left out as repeats (time column only)


def _read_table(
    path: Path, limits: ReadLimits, layout_of: Callable[[list[str] | None, int], _Layout]
) -> _Table:
    """Read the header (None if the first row is numbers) and every row, keeping the columns
    ``layout_of(header, width)`` says in their final layout (:class:`_Columns`), and each
    row's line number.

    A trailing empty field (a delimiter at the end of the row) is removed.  Rows are
    converted as they are read, a block at a time, so memory holds the numbers once, not
    the text; a line longer than ``limits.line_chars``, or more values than
    ``limits.cells``, is refused there.  A file whose columns ``layout_of`` refuses is still
    read through first, so that a bad row is said before a bad column name, as ever.
    """
    numbers = LineNumbers()
    lines_in_file = _count_lines(path)
    columns: _Columns | None = None
    refused: DriverError | None = None
    block: list[list[float]] = []
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            dialect = csv.excel_tab if path.suffix.lower() == ".tsv" else csv.excel
            reader = csv.reader(
                bounded_lines(handle, limit=limits.line_chars, source=str(path)), dialect
            )
            rows = ((reader.line_num, row) for row in reader if any(cell.strip() for cell in row))
            first = next(rows, None)
            if first is None:
                raise DriverError(f"{path}: the recording has no samples")
            header: list[str] | None = [cell.strip() for cell in first[1]]
            assert header is not None
            pending: list[tuple[int, list[str]]] = []
            if all(_is_number(cell) for cell in header if cell):
                header, pending = None, [first]
            elif header and not header[-1]:
                header = header[:-1]
            width = len(header) if header is not None else len(_trimmed(first[1]))
            names = header or [f"column {i + 1}" for i in range(width)]
            try:
                layout = layout_of(header, width)
            except DriverError as error:
                refused = error
            else:
                rows_in_file = ROWS_PER_BLOCK  # a pipe: no counting first
                if lines_in_file is not None:  # the header's line holds no row
                    rows_in_file = lines_in_file - (header is not None)
                columns = _Columns(layout, max(0, min(rows_in_file, limits.cells // width)))
            for number, row in itertools.chain(pending, rows):
                block.append(_row_values(path, names, number, _trimmed(row, width)))
                numbers.append(number)
                if len(numbers) * width > limits.cells:
                    limits.check_cells(len(numbers), width, what=f"{path}:{number}")
                if len(block) == ROWS_PER_BLOCK:
                    if columns is not None:
                        columns.add(block)
                    block = []
    except (OSError, UnicodeDecodeError) as error:
        raise DriverError(f"{path}: cannot read as text: {error}") from None
    except csv.Error as error:  # a field over csv.field_size_limit(), a stray quote
        line = numbers.last + 1
        raise DriverError(f"{path}:{line}: cannot read as CSV ({error})") from None
    if block and columns is not None:
        columns.add(block)
    if not len(numbers):
        raise DriverError(f"{path}: the recording has no samples")
    if refused is not None or columns is None:
        raise refused or AssertionError("no layout and no refusal")
    return _Table(header, layout, columns.samples(), columns.times(), numbers, columns.repeats)


def _count_lines(path: Path) -> int | None:
    """The lines of the file at ``path`` (ended by ``\\n``, ``\\r\\n`` or ``\\r``, as
    ``open(newline="")`` reads them, and a last one without), at least its rows: a count of
    line breaks in the raw bytes, a megabyte at a time, much quicker than the parse.  None
    for what cannot be read twice (a pipe) or at all (then the parse says why)."""
    if not path.is_file():
        return None
    count, carriage, last = 0, False, b""
    try:
        with path.open("rb") as handle:
            while chunk := handle.read(1 << 20):
                count += chunk.count(b"\n") + chunk.count(b"\r") - chunk.count(b"\r\n")
                count -= carriage and chunk[:1] == b"\n"  # a \r\n across two chunks
                carriage, last = chunk[-1:] == b"\r", chunk[-1:]
    except OSError:
        return None
    return count + (last not in (b"", b"\n", b"\r"))


def _trimmed(row: list[str], width: int | None = None) -> list[str]:
    """``row`` without a last empty field where that field is one too many."""
    if row and not row[-1].strip() and (width is None or len(row) == width + 1):
        return row[:-1]
    return row


def _row_values(path: Path, names: list[str], number: int, row: list[str]) -> list[float]:
    """The cells of one row as floats; errors name the line and column."""
    if len(row) != len(names):
        raise DriverError(f"{path}:{number}: has {len(row)} fields, expected {len(names)}")
    try:
        return [float(cell) for cell in row]
    except ValueError:
        pass
    # Rare: only then look for the cell, to say which one.
    for column, cell in enumerate(row):
        if not cell.strip():
            raise DriverError(
                f"{path}:{number}: column '{names[column]}' is empty (a missing sample)"
            )
        if not _is_number(cell):
            raise DriverError(
                f"{path}:{number}: column '{names[column]}': {cell.strip()!r} is not a number"
            )
    raise AssertionError("a row that float() refuses has a cell that is not a number")


def _time_column(path: Path, header: list[str] | None, given: str | None) -> int | None:
    """The index of the time column: the given name, else the first usual name."""
    lowered = [name.lower() for name in header or []]
    if given is not None:
        if given.lower() not in lowered:
            raise DriverError(
                f"{path}: has no column '{given}' to read times from "
                f"(columns: {_few(header or [])})"
            )
        return lowered.index(given.lower())
    return next((i for i, name in enumerate(lowered) if name in TIME_COLUMNS), None)


def _pick(
    path: Path, names: list[str], signal: list[int], wanted: Sequence[str], named: bool
) -> list[int]:
    """The columns of ``wanted`` (names, or 1-based numbers among the channels)."""
    lowered = {names[i].lower(): i for i in signal} if named else {}
    picked = []
    for item in wanted:
        key = item.strip()
        if key.lower() in lowered:
            picked.append(lowered[key.lower()])
        elif key.isdigit() and 1 <= int(key) <= len(signal):
            picked.append(signal[int(key) - 1])
        else:
            raise DriverError(
                f"{path}: has no channel '{key}' (channels: "
                f"{_few([names[i] for i in signal]) if named else f'1 to {len(signal)}'})"
            )
    if len(set(picked)) != len(picked):
        raise DriverError(f"{path}: a channel is asked for twice")
    return picked


def _check_stamps(path: Path, name: str, stamps: np.ndarray, lines: LineNumbers) -> None:
    """Refuse a stamp of shape (n,) that is NaN or infinite, naming its line."""
    bad = ~np.isfinite(stamps)
    if bad.any():
        index = int(np.flatnonzero(bad)[0])
        raise DriverError(
            f"{path}:{lines[index]}: column '{name}': {float(stamps[index])} is not a time "
            "(NaN or infinite)"
        )


def _on_even_grid(
    path: Path,
    name: str,
    times: np.ndarray,
    lines: LineNumbers,
    samples: np.ndarray,
    samplerate: float | None,
    limits: ReadLimits,
) -> tuple[float, np.ndarray, list[str], float]:
    """The rate and the samples of shape (n_channels, n) on an even grid, notes, and the
    median step of ``times``."""
    if times.size < 2:
        raise DriverError(f"{path}: column '{name}' needs at least two times to give a rate")
    steps = np.diff(times)
    if not (steps > 0).all():
        index = int(np.flatnonzero(~(steps > 0))[0]) + 1
        raise DriverError(
            f"{path}:{lines[index]}: column '{name}': the time does not rise over the line before"
        )
    low, high = float(steps.min()), float(steps.max())
    median = float(np.median(steps, overwrite_input=True))  # the steps are not needed after
    del steps
    # The largest |step - median|, as rounding is monotonic and symmetric.
    even = max(high - median, median - low) <= EVEN * median
    if even and samplerate is None:
        return 1.0 / median, samples, [], median
    if even and samplerate is not None and abs(1.0 / median - samplerate) <= EVEN * samplerate:
        return samplerate, samples, [], median
    jitter = jitter_of(times)
    rate = samplerate if samplerate is not None else jitter.rate
    check_grid(
        times,
        rate,
        samples.shape[0],
        limits,
        at=lambda index: f"{path}:{lines[index]}: column '{name}' jumps",
        before="the line before",
    )
    resampled = resample_even(times, samples, rate)
    note = (
        f"column '{name}': {jitter.describe()}; {times.size} samples resampled to "
        f"{resampled.shape[1]} at {rate:.6g} Hz (linear interpolation)"
    )
    return rate, resampled, [note], median


def _few(names: Sequence[str], shown: int = 8) -> str:
    """At most ``shown`` names, then how many more."""
    text = ", ".join(names[:shown])
    return text + (f" and {len(names) - shown} more" if len(names) > shown else "")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
