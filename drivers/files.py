"""Reading recordings from files: audio (WAV, FLAC, ... via soundfile), CSV, ``.npy``.

* Audio: any channel count and sample format, scaled to full scale (-1 to 1) as
  soundfile does; the sample rate comes from the file.
* CSV: one column per channel, with a header row (or none, when the first row is all
  numbers).  A column named ``time`` or ``t`` (any case) holds seconds and gives the
  sample rate (its steps must be even to 1 %); otherwise ``samplerate`` is required.
* ``.npy``: shape (n_channels, n_samples), or (n_samples,) for one channel;
  ``samplerate`` is required.

Every problem is a :class:`~drivers.errors.DriverError` naming the file (and the line
and column for CSV).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import soundfile

from drivers.errors import DriverError
from drivers.recording import Recording

TIME_COLUMNS = frozenset({"time", "t"})
_CSV_SUFFIXES = frozenset({".csv", ".tsv", ".txt"})


def read_recording(path: str | Path, *, samplerate: float | None = None) -> Recording:
    """Read one recording, choosing the reader by the file's suffix.

    Parameters
    ----------
    path : str or Path
        A ``.wav``/``.flac``/other soundfile format, ``.csv``/``.tsv``/``.txt``, or ``.npy``.
    samplerate : float, optional
        Samples per second, for CSV files without a time column and ``.npy`` files; for
        audio files and timed CSV files it must agree with the file if given.

    Returns
    -------
    Recording
        ``samples`` of shape (n_channels, n_samples), float64, all finite.

    Raises
    ------
    DriverError
        Missing or unreadable file, no samples, NaN samples, no or a bad sample rate.
    """
    path = Path(path)
    if not path.exists():
        raise DriverError(f"{path}: no such file")
    if path.is_dir():
        raise DriverError(f"{path}: is a folder, not a recording")
    if samplerate is not None:
        samplerate = check_rate(samplerate, path, "the given samplerate")
    suffix = path.suffix.lower()
    if suffix == ".npy":
        samples, rate = np.asarray(open_npy(path), dtype=np.float64), samplerate
    elif suffix in _CSV_SUFFIXES:
        samples, rate = _read_csv(path, samplerate)
    else:
        samples, rate = _read_audio(path, samplerate)
    if rate is None:
        raise no_sample_rate(path)
    return _finish(samples, rate, path)


def no_sample_rate(path: str | Path) -> DriverError:
    """The error for a file that does not say its sample rate when none was given."""
    return DriverError(f"{path}: no sample rate: give `samplerate` for a file without one")


def check_rate(rate: float, path: Path, what: str) -> float:
    try:
        value = float(rate)
    except (TypeError, ValueError):
        raise DriverError(f"{path}: {what} must be a number of Hz, got {rate!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise DriverError(f"{path}: {what} must be a positive number of Hz, got {rate!r}")
    return value


def _finish(samples: np.ndarray, rate: float, path: Path) -> Recording:
    if samples.shape[-1] == 0 or samples.size == 0:
        raise DriverError(f"{path}: the recording has no samples")
    bad = ~np.isfinite(samples)
    if bad.any():
        channel, index = np.argwhere(bad)[0]
        raise DriverError(
            f"{path}: channel {channel + 1} has a NaN or infinite sample at index {index} "
            f"({index / rate:.6g} s)"
        )
    return Recording(samples=np.ascontiguousarray(samples), samplerate=rate, path=str(path))


def _read_audio(path: Path, samplerate: float | None) -> tuple[np.ndarray, float]:
    try:
        data, rate = soundfile.read(str(path), dtype="float64", always_2d=True)
    except (soundfile.LibsndfileError, RuntimeError, TypeError) as error:
        raise DriverError(f"{path}: cannot read as audio: {error}") from None
    rate = check_rate(rate, path, "the file's sample rate")
    if samplerate is not None and abs(samplerate - rate) > 1e-6:
        raise DriverError(
            f"{path}: the file is sampled at {rate:g} Hz, but samplerate={samplerate:g} was given"
        )
    return data.T, rate


def open_npy(path: Path) -> np.ndarray:
    """A ``.npy`` recording memory-mapped, shape (n_channels, n_samples), values as stored."""
    try:
        data = np.load(path, mmap_mode="r", allow_pickle=False)
    except (OSError, ValueError) as error:
        raise DriverError(f"{path}: cannot read as a .npy array: {error}") from None
    if data.dtype.kind not in "biuf":
        raise DriverError(f"{path}: holds {data.dtype} values, not numbers")
    if data.ndim == 1:
        data = data[np.newaxis, :]
    if data.ndim != 2:
        raise DriverError(
            f"{path}: must be 1-D (samples) or 2-D (channels, samples), got shape {data.shape}"
        )
    return data


def _read_csv(path: Path, samplerate: float | None) -> tuple[np.ndarray, float | None]:
    rows: list[tuple[int, list[str]]] = []
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            dialect = csv.excel_tab if path.suffix.lower() == ".tsv" else csv.excel
            rows.extend(enumerate(csv.reader(handle, dialect), 1))
    except (OSError, UnicodeDecodeError) as error:
        raise DriverError(f"{path}: cannot read as text: {error}") from None
    except csv.Error as error:  # a field over csv.field_size_limit(), a stray quote
        raise DriverError(f"{path}:{len(rows) + 1}: cannot read as CSV ({error})") from None
    rows = [(number, row) for number, row in rows if any(cell.strip() for cell in row)]
    if not rows:
        raise DriverError(f"{path}: the recording has no samples")
    header: list[str] | None = [cell.strip() for cell in rows[0][1]]
    if header is not None and all(_is_number(cell) for cell in header):
        header = None
    else:
        rows = rows[1:]
    width = len(header) if header is not None else len(rows[0][1]) if rows else 0
    names = header if header is not None else [f"column {i + 1}" for i in range(width)]
    values = np.empty((len(rows), width))
    for row_index, (number, row) in enumerate(rows):
        if len(row) != width:
            raise DriverError(f"{path}:{number}: has {len(row)} fields, expected {width}")
        for column, cell in enumerate(row):
            if not cell.strip():
                raise DriverError(
                    f"{path}:{number}: column '{names[column]}' is empty (a missing sample)"
                )
            try:
                values[row_index, column] = float(cell)
            except ValueError:
                raise DriverError(
                    f"{path}:{number}: column '{names[column]}': {cell.strip()!r} is not a number"
                ) from None
    time_column = next(
        (i for i, name in enumerate(names) if name.lower() in TIME_COLUMNS and header), None
    )
    if time_column is None:
        return values.T, samplerate
    rate = _rate_from_times(values[:, time_column], path, names[time_column])
    if samplerate is not None and abs(rate - samplerate) > 0.01 * samplerate:
        raise DriverError(
            f"{path}: column '{names[time_column]}' gives {rate:g} Hz, "
            f"but samplerate={samplerate:g} was given"
        )
    channels = np.delete(values, time_column, axis=1).T
    if channels.shape[0] == 0:
        raise DriverError(f"{path}: has a time column but no signal column")
    return channels, rate


def _rate_from_times(times: np.ndarray, path: Path, name: str) -> float:
    if times.size < 2:
        raise DriverError(f"{path}: column '{name}' needs at least two times to give a rate")
    if not np.isfinite(times).all():
        raise DriverError(f"{path}: column '{name}' has an empty or non-finite time")
    steps = np.diff(times)
    step = float(np.median(steps))
    if step <= 0 or np.abs(steps - step).max() > 0.01 * step:
        raise DriverError(
            f"{path}: column '{name}' must rise in even steps (a uniformly sampled recording)"
        )
    return 1.0 / step


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
