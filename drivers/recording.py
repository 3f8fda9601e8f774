"""The recording type every driver returns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Recording:
    """Samples of one recording.

    Parameters
    ----------
    samples : ndarray of shape (n_channels, n_samples), float64
        Finite samples, channel axis first.  Audio is in full-scale units (-1 to 1).
    samplerate : float
        Samples per second per channel.
    path : str
        Where it came from (a file path, or a description for generated data).
    channels : tuple of str, optional
        The channels' names when the file has them (a CSV header), one per channel.
    notes : tuple of str
        What was done to the samples on reading (resampled stamps...), one line each.
    resampled : bool
        True when the reader chose ``samplerate`` itself for stamps it put on an even grid.
    """

    samples: np.ndarray
    samplerate: float
    path: str
    channels: tuple[str, ...] | None = None
    notes: tuple[str, ...] = ()
    resampled: bool = False

    @property
    def n_channels(self) -> int:
        return int(self.samples.shape[0])

    @property
    def n_samples(self) -> int:
        return int(self.samples.shape[1])

    @property
    def duration(self) -> float:
        """Length in seconds."""
        return self.n_samples / self.samplerate
