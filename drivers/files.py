"""Reading recordings from files: audio (WAV, FLAC, ... via soundfile), CSV, ``.npy``.

* Audio: any channel count and sample format, scaled to full scale (-1 to 1) as
  soundfile does; the sample rate comes from the file.
* CSV: one column per channel, perhaps a time column (:mod:`drivers.csv_series`: named
  channels, stamps in seconds or nanoseconds, uneven stamps resampled); without a time
  column ``samplerate`` is required.
* ``.npy``: shape (n_channels, n_samples), or (n_samples,) for one channel;
  ``samplerate`` is required.

Every problem is a :class:`~drivers.errors.DriverError` naming the file (and the line
and column for CSV).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import soundfile

from touchbench.drivers.csv_series import read_csv_series
from touchbench.drivers.errors import DriverError
from touchbench.drivers.limits import ReadLimits
from touchbench.drivers.recording import Recording

_CSV_SUFFIXES = frozenset({".csv", ".tsv", ".txt"})


def read_recording(
    path: str | Path,
    *,
    samplerate: float | None = None,
    time_column: str | None = None,
    time_unit: str = "auto",
    fields: Sequence[str] | None = None,
    limits: ReadLimits | None = None,
) -> Recording:
    """Read one recording, choosing the reader by the file's suffix.

    Parameters
    ----------
    path : str or Path
        A ``.wav``/``.flac``/other soundfile format, ``.csv``/``.tsv``/``.txt``, or ``.npy``.
    samplerate : float, optional
        Samples per second, for CSV files without a time column and ``.npy`` files; for
        audio files it must agree with the file if given; for timed CSV files, the even
        grid their stamps are resampled onto if they differ.
    time_column : str, optional
        A CSV file's time column, when it has none of the usual names.
    time_unit : {"auto", "s", "ms", "us", "ns"}
        The unit of a CSV file's time column (``auto``: seconds or nanoseconds).
    fields : sequence of str, optional
        The CSV columns to keep as channels (names, or 1-based numbers); all by default.
    limits : ReadLimits, optional
        The bounds of reading a CSV file (:mod:`drivers.limits`).

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
    if (time_column is not None or fields) and suffix not in _CSV_SUFFIXES:
        raise DriverError(f"{path}: `time_column` and `fields` apply to CSV files only")
    names: tuple[str, ...] | None = None
    notes: tuple[str, ...] = ()
    resampled = False
    if suffix == ".npy":
        samples, rate = np.asarray(open_npy(path), dtype=np.float64), samplerate
    elif suffix in _CSV_SUFFIXES:
        series = read_csv_series(
            path,
            samplerate=samplerate,
            time_column=time_column,
            time_unit=time_unit,
            channels=fields,
            limits=limits,
        )
        samples, rate, names, notes = (
            series.samples,
            series.samplerate,
            series.channels,
            series.notes,
        )
        resampled = series.resampled
    else:
        samples, rate = _read_audio(path, samplerate)
    if rate is None:
        raise no_sample_rate(path)
    recording = _finish(samples, rate, path)
    return Recording(recording.samples, rate, recording.path, names, notes, resampled)


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
    for channel, row in enumerate(samples):  # a channel's flags at a time, not the whole's
        finite = np.isfinite(row)
        if not finite.all():
            index = int(np.argmin(finite))
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
