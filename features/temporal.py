"""Time-domain features of framed signals: RMS, zero crossings, peak level.

Every function takes frames of shape ``(..., frame_length, n_frames)`` (see
:func:`features.framing.frame`) and returns one value per frame, ``(..., n_frames)``.
"""

from __future__ import annotations

import numpy as np


def rms(frames: np.ndarray) -> np.ndarray:
    """Root mean square of each frame.

    ``rms[t] = sqrt(mean_n x_t[n]**2)``, shape (..., n_frames).  Equal to
    ``librosa.feature.rms(y=..., center=False)`` with the same frame and hop lengths.
    """
    return np.sqrt(np.einsum("...nt,...nt->...t", frames, frames) / frames.shape[-2])


def zero_crossings(frames: np.ndarray) -> np.ndarray:
    """Number of sign changes between consecutive samples in each frame.

    A sample of exactly 0 counts as positive (as in librosa's ``zero_pos=True``).

    Returns
    -------
    ndarray of shape (..., n_frames), int64
        Between 0 and ``frame_length - 1``.
    """
    negative = np.signbit(frames) & (frames != 0)
    return np.count_nonzero(negative[..., 1:, :] != negative[..., :-1, :], axis=-2)


def zero_crossing_rate(frames: np.ndarray) -> np.ndarray:
    """Zero crossings per sample: ``zero_crossings(frames) / frame_length``.

    Equal to ``librosa.feature.zero_crossing_rate(y, center=False)`` with the same frame
    and hop lengths, where no sample is within librosa's 1e-10 threshold of zero.
    Shape (..., n_frames).
    """
    return zero_crossings(frames) / frames.shape[-2]


def peak_level(frames: np.ndarray) -> np.ndarray:
    """Largest absolute sample of each frame, ``max_n |x_t[n]|``, shape (..., n_frames)."""
    return np.max(np.abs(frames), axis=-2)
