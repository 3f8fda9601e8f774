"""Sources of signal blocks: the interface a live capture and a file replay share.

A :class:`Source` yields consecutive blocks of shape (n_channels, block_length); the
last block may be shorter.  :class:`RecordingSource` replays a recording; a sound-card
source will implement the same protocol.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Protocol

import numpy as np

from drivers.errors import DriverError
from drivers.recording import Recording


class Source(Protocol):
    """Anything that produces blocks of samples at a fixed rate."""

    @property
    def samplerate(self) -> float: ...

    @property
    def n_channels(self) -> int: ...

    def blocks(self, block_length: int) -> Iterator[np.ndarray]:
        """Consecutive blocks, each of shape (n_channels, <= block_length), float64."""
        ...


class RecordingSource:
    """Replays a :class:`Recording` block by block (views, no copies)."""

    def __init__(self, recording: Recording) -> None:
        self.recording = recording

    @property
    def samplerate(self) -> float:
        return self.recording.samplerate

    @property
    def n_channels(self) -> int:
        return self.recording.n_channels

    def blocks(self, block_length: int) -> Iterator[np.ndarray]:
        if block_length < 1:
            raise DriverError(f"block_length must be at least 1, got {block_length}")
        samples = self.recording.samples
        for start in range(0, samples.shape[1], block_length):
            yield samples[:, start : start + block_length]
