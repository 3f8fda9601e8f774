"""Replaying a recording file block by block: everything ``extract`` reads.

* Audio (WAV, FLAC, OGG, ... via soundfile): read block by block, never whole.
* ``.npy``: memory-mapped, so read block by block too.
* CSV/TSV/TXT: parsed whole (:func:`drivers.files.read_recording`), then replayed.
* ROS bags (``.bag``, ``.mcap``, ``.db3``, or a ROS 2 bag folder): :mod:`drivers.bags`
  (audio) and :mod:`drivers.bag_fields` (numeric fields of any topic).

As fast as possible by default, or paced in real time (``realtime=True``) to stand in
for a sound card.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
import soundfile

from touchbench.drivers.errors import DriverError
from touchbench.drivers.files import check_rate, no_sample_rate, open_npy, read_recording
from touchbench.drivers.limits import ReadLimits
from touchbench.drivers.source import Block, RecordingSource, Source, check_finite, paced

CSV_SUFFIXES = frozenset({".csv", ".tsv", ".txt"})
BAG_SUFFIXES = frozenset({".bag", ".mcap", ".db3"})
FORMATS = "WAV/FLAC/OGG (libsndfile formats), CSV/TSV/TXT, .npy and ROS bags (.bag, .mcap, .db3)"
DEFAULT_BLOCK = 65536


def is_bag(path: Path) -> bool:
    """A ROS bag file, or a ROS 2 bag folder (with its metadata.yaml)."""
    return path.suffix.lower() in BAG_SUFFIXES or (path / "metadata.yaml").is_file()


class FileReplaySource(Source):
    """A recording file as a :class:`Source`.

    Parameters
    ----------
    path : str or Path
        The recording (see the module docstring for the formats).
    samplerate : float, optional
        For CSV without a time column and ``.npy``; must agree with the file otherwise.
    block_length : int
        Samples per block (a bag gives one block per message instead).
    realtime : bool
        Deliver blocks no faster than real time.
    topic : str, optional
        The topic of a ROS bag to read (its audio, or its numeric fields).
    fields : sequence of str, optional
        Numeric fields of a bag's ``topic``, or columns of a CSV file (names or 1-based
        numbers), to read as channels.
    time_column : str, optional
        A CSV file's time column (:func:`drivers.files.read_recording`).
    channels, sample_format : optional
        Raw PCM audio of a bag without ``AudioInfo``: channels per frame and
        ``S16LE``/``S32LE``/``F32LE``.
    limits : ReadLimits, optional
        The bounds of reading (:mod:`drivers.limits`): a CSV file's lines and values, and
        the gaps resampling fills (CSV files and bag fields).
    """

    def __init__(
        self,
        path: str | Path,
        *,
        samplerate: float | None = None,
        block_length: int = DEFAULT_BLOCK,
        realtime: bool = False,
        topic: str | None = None,
        fields: Sequence[str] | None = None,
        channels: int | None = None,
        sample_format: str | None = None,
        time_column: str | None = None,
        time_unit: str = "auto",
        limits: ReadLimits | None = None,
    ) -> None:
        self.path = Path(path)
        self.name = str(path)
        self.realtime = realtime
        if block_length < 1:
            raise DriverError(f"block_length must be at least 1, got {block_length}")
        self.block_length = block_length
        if not self.path.exists():
            raise DriverError(f"{path}: no such file")
        if samplerate is not None:
            samplerate = check_rate(samplerate, self.path, "the given samplerate")
        self._inner: Source | None = None
        self._start = 0.0
        self._audio: soundfile.SoundFile | None = None
        self._array: np.ndarray | None = None
        csv_file = self.path.suffix.lower() in CSV_SUFFIXES
        if time_column is not None and not csv_file:
            raise DriverError(f"{path}: `time_column` applies to CSV files only")
        bag_only = {
            "topic": topic,
            "fields": None if csv_file else fields,
            "channels": channels,
            "sample_format": sample_format,
        }
        given = [option for option, value in bag_only.items() if value]
        if given and not is_bag(self.path):
            also = " and CSV files" if given[0] == "fields" else ""
            raise DriverError(f"{path}: `{given[0]}` applies to ROS bags{also} only")
        if is_bag(self.path):
            from touchbench.drivers.bags import open_bag_source

            bag = open_bag_source(
                self.path,
                topic=topic,
                fields=fields,
                samplerate=samplerate,
                channels=channels,
                sample_format=sample_format,
                limits=limits,
            )
            self._inner, self._start = bag, float(getattr(bag, "start_time", 0.0))
            rate: float | None = bag.samplerate
            self.n_channels, self.channel_names = bag.n_channels, bag.channel_names
            self.notes, self.resampled = bag.notes, bag.resampled
        elif self.path.is_dir():
            raise DriverError(f"{path}: is a folder, not a recording (nor a ROS 2 bag)")
        elif self.path.suffix.lower() in CSV_SUFFIXES:
            recording = read_recording(
                self.path,
                samplerate=samplerate,
                time_column=time_column,
                time_unit=time_unit,
                fields=fields,
                limits=limits,
            )
            inner = RecordingSource(recording, block_length=block_length)
            self._inner, self.channel_names, self.notes = inner, inner.channel_names, inner.notes
            self.resampled = inner.resampled
            rate, self.n_channels = recording.samplerate, recording.n_channels
        elif self.path.suffix.lower() == ".npy":
            self._array = open_npy(self.path)
            rate, self.n_channels = samplerate, self._array.shape[0]
        else:
            self._audio = _open_audio(self.path)
            rate, self.n_channels = float(self._audio.samplerate), self._audio.channels
            if samplerate is not None and abs(samplerate - rate) > 1e-6:
                self.close()
                raise DriverError(
                    f"{path}: the file is sampled at {rate:g} Hz, but samplerate={samplerate:g} "
                    "was given"
                )
        if rate is None:
            raise no_sample_rate(path)
        self.samplerate = rate

    @property
    def start_time(self) -> float:
        """Seconds from the file's time origin to its first sample (a bag's audio may
        start after its first message)."""
        return self._start

    def blocks(self) -> Iterator[Block]:
        blocks = self._blocks()
        return paced(blocks, self.samplerate) if self.realtime else blocks

    def _blocks(self) -> Iterator[Block]:
        position = 0
        for block in self._raw_blocks():
            check_finite(block.samples, first=position, samplerate=self.samplerate, name=self.name)
            position += block.samples.shape[1]
            yield block
        if position == 0:
            raise DriverError(f"{self.name}: the recording has no samples")

    def _raw_blocks(self) -> Iterator[Block]:
        if self._inner is not None:
            yield from self._inner.blocks()
        elif self._array is not None:
            for start in range(0, self._array.shape[1], self.block_length):
                chunk = np.asarray(self._array[:, start : start + self.block_length], np.float64)
                yield Block(chunk, start / self.samplerate)
        else:
            assert self._audio is not None
            self._audio.seek(0)
            start = 0
            try:
                for chunk in self._audio.blocks(self.block_length, dtype="float64", always_2d=True):
                    yield Block(np.ascontiguousarray(chunk.T), start / self.samplerate)
                    start += chunk.shape[0]
            except (soundfile.LibsndfileError, RuntimeError) as error:
                raise DriverError(f"{self.name}: cannot read as audio: {error}") from None

    def close(self) -> None:
        if self._audio is not None:
            self._audio.close()
        if self._inner is not None:
            self._inner.close()


def _open_audio(path: Path) -> soundfile.SoundFile:
    try:
        return soundfile.SoundFile(str(path))
    except (soundfile.LibsndfileError, RuntimeError, TypeError) as error:
        if path.stat().st_size == 0:
            raise DriverError(f"{path}: the recording has no samples (empty file)") from None
        raise DriverError(
            f"{path}: not a recording touchbench can read ({error}); it reads {FORMATS}"
        ) from None
