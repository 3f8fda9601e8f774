"""Spectral shape features: centroid, roll-off, flux, and band peaks.

The frame-wise functions take a spectrogram ``S`` of shape ``(..., n_bins, n_frames)``
(magnitude or power, as each docstring says) and its bin frequencies, shape
``(n_bins,)``, and return ``(..., n_frames)``.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import find_peaks, peak_prominences

from touchbench.features.errors import FeatureError


def _check_bins(S: np.ndarray, frequencies: np.ndarray) -> np.ndarray:
    frequencies = np.asarray(frequencies, dtype=np.float64)
    if S.ndim < 2 or frequencies.shape != (S.shape[-2],):
        raise FeatureError(
            f"S has shape {S.shape}; frequencies must have shape (n_bins,) = ({S.shape[-2]},)"
            f" if S is (..., n_bins, n_frames), got {frequencies.shape}"
        )
    return frequencies


def spectral_centroid(S: np.ndarray, *, frequencies: np.ndarray) -> np.ndarray:
    """Centre of mass of each frame's spectrum, in Hz.

    ``centroid[t] = sum_k f[k] S[k, t] / sum_k S[k, t]``, and 0 for an all-zero frame.
    With ``S`` the magnitude spectrogram this is librosa's ``spectral_centroid``.

    Parameters
    ----------
    S : ndarray of shape (..., n_bins, n_frames)
        Non-negative spectrogram (magnitude, as librosa).
    frequencies : ndarray of shape (n_bins,)
        Bin frequencies in Hz.

    Returns
    -------
    ndarray of shape (..., n_frames)
    """
    frequencies = _check_bins(S, frequencies)
    total = S.sum(axis=-2)
    weighted = np.einsum("k,...kt->...t", frequencies, S)
    return np.divide(weighted, total, out=np.zeros_like(total), where=total > 0)


def spectral_rolloff(
    S: np.ndarray, *, frequencies: np.ndarray, roll_percent: float = 0.95
) -> np.ndarray:
    """Frequency below which ``roll_percent`` of each frame's spectrum lies.

    ``rolloff[t] = f[k*]`` with ``k*`` the first bin where
    ``sum_{j<=k} S[j, t] >= roll_percent * sum_j S[j, t]`` (librosa's definition; 0 for
    an all-zero frame).  Pass the power spectrogram for a roll-off of energy.

    Parameters
    ----------
    S : ndarray of shape (..., n_bins, n_frames)
        Non-negative spectrogram.
    frequencies : ndarray of shape (n_bins,)
        Bin frequencies in Hz, ascending.
    roll_percent : float
        Fraction in (0, 1).

    Returns
    -------
    ndarray of shape (..., n_frames)
    """
    frequencies = _check_bins(S, frequencies)
    if not 0.0 < roll_percent < 1.0:
        raise FeatureError(f"roll_percent must be between 0 and 1, got {roll_percent}")
    cumulative = np.cumsum(S, axis=-2)
    reached = cumulative >= roll_percent * cumulative[..., -1:, :]
    return frequencies[np.argmax(reached, axis=-2)]


def spectral_flux(S: np.ndarray, *, previous: np.ndarray | None = None) -> np.ndarray:
    """Change between consecutive L2-normalised spectra.

    ``flux[t] = || S[:, t] / ||S[:, t]|| - S[:, t-1] / ||S[:, t-1]|| ||_2``, between 0
    and sqrt(2) for a non-negative ``S``; an all-zero frame normalises to zeros.  This is
    the flux of ChucK/Marsyas (the UC3M features), not librosa's onset strength.

    Parameters
    ----------
    S : ndarray of shape (..., n_bins, n_frames)
        Magnitude spectrogram.
    previous : ndarray of shape (..., n_bins, n_frames), optional
        The spectrum each frame is compared with; by default the frame before it, and
        zeros before the first frame.

    Returns
    -------
    ndarray of shape (..., n_frames)
    """
    unit = _unit_columns(S)
    if previous is None:
        before = np.concatenate([np.zeros_like(unit[..., :1]), unit[..., :-1]], axis=-1)
    else:
        if previous.shape != S.shape:
            raise FeatureError(f"previous has shape {previous.shape}, S has {S.shape}")
        before = _unit_columns(previous)
    return np.linalg.norm(unit - before, axis=-2)


def _unit_columns(S: np.ndarray) -> np.ndarray:
    norms = np.linalg.norm(S, axis=-2, keepdims=True)
    return np.divide(S, norms, out=np.zeros_like(S, dtype=np.float64), where=norms > 0)


def band_peak(
    spectrum: np.ndarray, *, frequencies: np.ndarray, band: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """Highest spectral peak inside a frequency band, and its prominence.

    A peak is a local maximum as ``scipy.signal.find_peaks`` finds it over the whole
    spectrum; its prominence is ``scipy.signal.peak_prominences`` on the whole spectrum
    (so its bases may lie outside the band).  A band without a local maximum gives the
    frequency of its largest bin and a prominence of 0.

    Parameters
    ----------
    spectrum : ndarray of shape (..., n_bins)
        One magnitude spectrum per instance.
    frequencies : ndarray of shape (n_bins,)
        Bin frequencies in Hz, ascending.
    band : (float, float)
        Lowest and highest frequency in Hz, both included.

    Returns
    -------
    frequency : ndarray of shape (...)
        Peak frequency in Hz.
    prominence : ndarray of shape (...)
        Peak prominence, in the units of ``spectrum``.
    """
    frequencies = np.asarray(frequencies, dtype=np.float64)
    if frequencies.shape != spectrum.shape[-1:]:
        raise FeatureError(
            f"frequencies must have shape ({spectrum.shape[-1]},), got {frequencies.shape}"
        )
    low, high = float(band[0]), float(band[1])
    in_band = np.flatnonzero((frequencies >= low) & (frequencies <= high))
    if low > high or in_band.size == 0:
        raise FeatureError(
            f"band [{low:g}, {high:g}] Hz holds no frequency bin (bins span "
            f"{frequencies[0]:g} to {frequencies[-1]:g} Hz)"
        )
    rows = spectrum.reshape(-1, spectrum.shape[-1])
    peak_bins = np.empty(rows.shape[0], dtype=np.int64)
    prominences = np.zeros(rows.shape[0])
    for i, row in enumerate(rows):
        peaks, _ = find_peaks(row)
        peaks = peaks[(peaks >= in_band[0]) & (peaks <= in_band[-1])]
        if peaks.size == 0:
            peak_bins[i] = in_band[np.argmax(row[in_band])]
            continue
        best = peaks[np.argmax(row[peaks])]
        peak_bins[i] = best
        prominences[i] = peak_prominences(row, [best])[0][0]
    shape = spectrum.shape[:-1]
    return frequencies[peak_bins].reshape(shape), prominences.reshape(shape)
