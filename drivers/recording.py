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
    """

    samples: np.ndarray
    samplerate: float
    path: str

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
