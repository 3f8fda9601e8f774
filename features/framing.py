"""Framing, the short-time Fourier transform and its frequency axis.

Frames follow librosa's layout: a signal of shape ``(..., n_samples)`` becomes a
read-only strided view of shape ``(..., frame_length, n_frames)`` (no copy), and a
spectrogram has shape ``(..., n_bins, n_frames)``, so every feature function reduces
over axis ``-2`` and returns ``(..., n_frames)``.  Frames start at sample 0 and are not
centred or padded: frame ``t`` covers samples ``[t * hop_length, t * hop_length +
frame_length)``.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.signal import get_window

from touchbench.features._checks import as_positive_int, as_samplerate, as_signal
from touchbench.features.errors import FeatureError

WindowSpec = Literal["hann", "rectangular"] | np.ndarray | None

#: Frames transformed at a time (a few hundred kB of samples, so the work stays in cache).
_BLOCK_FRAMES = 128


def frame_count(n_samples: int, *, frame_length: int, hop_length: int) -> int:
    """Number of whole frames in ``n_samples``: ``1 + (n_samples - frame_length) // hop_length``.

    Zero when the signal is shorter than one frame.
    """
    if n_samples < frame_length:
        return 0
    return 1 + (n_samples - frame_length) // hop_length


def frame(y: np.ndarray, *, frame_length: int, hop_length: int) -> np.ndarray:
    """Slice a signal into overlapping frames without copying it.

    Parameters
    ----------
    y : ndarray of shape (..., n_samples)
        Finite samples.
    frame_length : int
        Samples per frame.
    hop_length : int
        Samples between the starts of consecutive frames.

    Returns
    -------
    ndarray of shape (..., frame_length, n_frames)
        A read-only view; ``n_frames = 1 + (n_samples - frame_length) // hop_length``.
        Trailing samples that do not fill a frame are left out.

    Raises
    ------
    FeatureError
        If ``y`` is shorter than one frame or holds NaN samples.
    """
    frame_length = as_positive_int(frame_length, name="frame_length")
    hop_length = as_positive_int(hop_length, name="hop_length")
    y = as_signal(y, min_samples=frame_length)
    windows = sliding_window_view(y, frame_length, axis=-1)[..., ::hop_length, :]
    return np.swapaxes(windows, -1, -2)


def window_function(window: WindowSpec, frame_length: int) -> np.ndarray | None:
    """The analysis window as an array of shape (frame_length,), ``None`` for rectangular.

    ``"hann"`` is the periodic Hann window (``scipy.signal.get_window("hann", N)``), the
    one librosa uses.
    """
    if window is None or (isinstance(window, str) and window == "rectangular"):
        return None
    if isinstance(window, str):
        if window != "hann":
            raise FeatureError(f"window must be 'hann', 'rectangular' or an array, got {window!r}")
        return np.asarray(get_window("hann", frame_length, fftbins=True), dtype=np.float64)
    weights = np.asarray(window, dtype=np.float64)
    if weights.shape != (frame_length,):
        raise FeatureError(f"window has shape {weights.shape}, frames have {frame_length} samples")
    return weights


def stft(
    frames: np.ndarray, *, window: WindowSpec = "hann", n_fft: int | None = None
) -> np.ndarray:
    """One-sided discrete Fourier transform of every frame.

    Parameters
    ----------
    frames : ndarray of shape (..., frame_length, n_frames)
        Frames as :func:`frame` returns them.
    window : {"hann", "rectangular"}, ndarray of shape (frame_length,), or None
        Applied to each frame before the transform.
    n_fft : int, optional
        Transform length (frames are zero-padded); defaults to ``frame_length``.

    Returns
    -------
    ndarray of shape (..., 1 + n_fft // 2, n_frames), complex128
        ``X[k, t] = sum_n w[n] x_t[n] exp(-2 pi i k n / n_fft)``.
    """
    n_fft, weights = _transform_setup(frames, window, n_fft)
    rows = np.swapaxes(frames, -1, -2)
    out = np.empty((*rows.shape[:-1], n_fft // 2 + 1), dtype=np.complex128)
    for block in _blocks(rows.shape[-2]):
        out[..., block, :] = _block_transform(rows[..., block, :], weights, n_fft)
    return np.swapaxes(out, -1, -2)


def power_spectrogram(
    frames: np.ndarray, *, window: WindowSpec = "hann", n_fft: int | None = None
) -> np.ndarray:
    """``|stft(frames)|**2``, shape (..., 1 + n_fft // 2, n_frames), float64."""
    n_fft, weights = _transform_setup(frames, window, n_fft)
    rows = np.swapaxes(frames, -1, -2)
    out = np.empty((*rows.shape[:-1], n_fft // 2 + 1))
    for block in _blocks(rows.shape[-2]):
        spectrum = _block_transform(rows[..., block, :], weights, n_fft)
        out[..., block, :] = spectrum.real**2 + spectrum.imag**2
    return np.swapaxes(out, -1, -2)


def _transform_setup(
    frames: np.ndarray, window: WindowSpec, n_fft: int | None
) -> tuple[int, np.ndarray | None]:
    frame_length = frames.shape[-2]
    n_fft = frame_length if n_fft is None else as_positive_int(n_fft, name="n_fft")
    if n_fft < frame_length:
        raise FeatureError(f"n_fft ({n_fft}) must be at least the frame length ({frame_length})")
    return n_fft, window_function(window, frame_length)


def _blocks(n_frames: int) -> list[slice]:
    """Slices of ``_BLOCK_FRAMES`` frames: transforming block by block stays in cache."""
    return [slice(start, start + _BLOCK_FRAMES) for start in range(0, n_frames, _BLOCK_FRAMES)]


def _block_transform(rows: np.ndarray, weights: np.ndarray | None, n_fft: int) -> np.ndarray:
    """rfft of (..., n_block, frame_length) frames along their contiguous last axis."""
    windowed = rows if weights is None else rows * weights
    return np.fft.rfft(windowed, n=n_fft, axis=-1)


def fft_frequencies(*, samplerate: float, n_fft: int) -> np.ndarray:
    """Centre frequency in Hz of each one-sided DFT bin, shape (1 + n_fft // 2,).

    ``f[k] = k * samplerate / n_fft``.
    """
    samplerate = as_samplerate(samplerate)
    n_fft = as_positive_int(n_fft, name="n_fft")
    return np.arange(1 + n_fft // 2) * (samplerate / n_fft)
