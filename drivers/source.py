"""Sources of signal blocks: the one interface a sound card, a file replay and a ROS bag share.

A :class:`Source` has a sample rate and a channel count and yields consecutive
:class:`Block` s of shape (n_channels, n) with the time of their first sample; it is a
context manager, and :meth:`Source.close` releases what it holds (a file, a stream).
Errors of the libraries underneath come out as :class:`~drivers.errors.DriverError`
with a line that says what to do.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from types import TracebackType
from typing import Self

import numpy as np

from touchbench.drivers.errors import DriverError
from touchbench.drivers.recording import Recording

#: Samples per block for live prediction (11.6 ms at 44.1 kHz): a touch is predicted once
#: the block holding its end has arrived, so half a block of waiting adds on average to
#: the computing.  Recording, where latency does not matter, keeps larger blocks.
LIVE_BLOCK = 512


@dataclass(frozen=True)
class Block:
    """Consecutive samples of every channel.

    Parameters
    ----------
    samples : ndarray of shape (n_channels, n_samples), float64
        Finite samples; audio in full-scale units (-1 to 1).
    time : float
        Seconds from the source's time origin to the first sample (for a file, its
        start; for a ROS bag, its first message).
    arrived : float or None
        ``time.perf_counter()`` when a live source had the block complete, else None.
    """

    samples: np.ndarray
    time: float
    arrived: float | None = None


class Source(ABC):
    """Blocks of samples at a fixed rate.

    Attributes
    ----------
    name : str
        What the source is (a file path, a device), for messages.
    samplerate : float
        Samples per second per channel.
    n_channels : int
        Channels of every block.
    overflows : int
        Blocks a live source had to drop because the consumer fell behind (always 0 for
        files).
    channel_names : sequence of str or None
        The channels' names when the source has them (a CSV header), else None.
    notes : sequence of str
        What the user should know about how the signal was read (stamps resampled, a
        format guessed), one line each; filled when the source opens.
    resampled : bool
        True when the source chose ``samplerate`` itself for samples it put on an even
        grid (the rate of uneven stamps); given a rate, it would use that one.
    """

    name: str
    samplerate: float
    n_channels: int
    overflows: int = 0
    channel_names: Sequence[str] | None = None
    notes: Sequence[str] = ()
    resampled: bool = False

    @abstractmethod
    def blocks(self) -> Iterator[Block]:
        """The blocks in order, until the source ends (or is closed)."""

    def close(self) -> None:  # noqa: B027 - most sources hold nothing
        """Release what the source holds; safe to call twice."""

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()


def paced(blocks: Iterator[Block], samplerate: float) -> Iterator[Block]:
    """``blocks`` delivered no faster than real time (each when its last sample is due)."""
    start = time.perf_counter()
    for block in blocks:
        due = start + block.time + block.samples.shape[1] / samplerate
        delay = due - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        yield Block(block.samples, block.time, arrived=time.perf_counter())


def check_finite(samples: np.ndarray, *, first: int, samplerate: float, name: str) -> None:
    """Raise :class:`DriverError` at the first NaN or infinite sample (index ``first`` +)."""
    if np.isfinite(np.sum(samples)) or np.isfinite(samples).all():
        return
    channel, index = np.argwhere(~np.isfinite(samples))[0]
    index += first
    raise DriverError(
        f"{name}: channel {channel + 1} has a NaN or infinite sample at index {index} "
        f"({index / samplerate:.6g} s)"
    )


class RecordingSource(Source):
    """Replays a :class:`Recording` in memory, ``block_length`` samples at a time."""

    def __init__(self, recording: Recording, *, block_length: int = 65536) -> None:
        if block_length < 1:
            raise DriverError(f"block_length must be at least 1, got {block_length}")
        self.recording = recording
        self.block_length = block_length
        self.name = recording.path
        self.samplerate = recording.samplerate
        self.n_channels = recording.n_channels
        self.channel_names = recording.channels
        self.notes = recording.notes
        self.resampled = recording.resampled

    def blocks(self) -> Iterator[Block]:
        samples = self.recording.samples
        for start in range(0, samples.shape[1], self.block_length):
            yield Block(samples[:, start : start + self.block_length], start / self.samplerate)
