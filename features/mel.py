"""Mel filter bank and mel-frequency cepstral coefficients.

The mel scale is HTK's, ``mel(f) = 2595 log10(1 + f / 700)``; the filters are
triangles between consecutive mel-spaced points, scaled to unit area (librosa's
``norm="slaney"``) unless ``normalize=False``.  MFCCs are the orthonormal DCT-II of the
log mel energies in dB, ``10 log10(max(E, amin))``; with these parameters they equal
``librosa.feature.mfcc(S=librosa.power_to_db(mel, top_db=None), norm="ortho")`` on a
mel spectrogram built with ``htk=True``.
"""

from __future__ import annotations

import numpy as np
from scipy.fft import dct

from touchbench.features._checks import as_positive_int, as_samplerate
from touchbench.features.errors import FeatureError


def hz_to_mel(frequencies: np.ndarray | float) -> np.ndarray:
    """``2595 log10(1 + f / 700)``, elementwise."""
    return 2595.0 * np.log10(1.0 + np.asarray(frequencies, dtype=np.float64) / 700.0)


def mel_to_hz(mels: np.ndarray | float) -> np.ndarray:
    """``700 (10 ** (m / 2595) - 1)``, the inverse of :func:`hz_to_mel`."""
    return 700.0 * (10.0 ** (np.asarray(mels, dtype=np.float64) / 2595.0) - 1.0)


def mel_filter_bank(
    *,
    samplerate: float,
    n_fft: int,
    n_mels: int = 40,
    fmin: float = 0.0,
    fmax: float | None = None,
    normalize: bool = True,
) -> np.ndarray:
    """Triangular filters on the mel scale, as a matrix over the one-sided DFT bins.

    Filter ``m`` rises linearly from ``h[m]`` to ``h[m + 1]`` and falls to ``h[m + 2]``,
    where ``h`` are ``n_mels + 2`` points equally spaced in mel between ``fmin`` and
    ``fmax``, converted back to Hz.

    Parameters
    ----------
    samplerate : float
        Sample rate in Hz.
    n_fft : int
        DFT length; the filters cover ``1 + n_fft // 2`` bins.
    n_mels : int
        Number of filters.
    fmin, fmax : float
        Frequency range in Hz (``fmax`` defaults to ``samplerate / 2``).
    normalize : bool
        Scale each triangle by ``2 / (h[m + 2] - h[m])`` (unit area).

    Returns
    -------
    ndarray of shape (n_mels, 1 + n_fft // 2)
    """
    samplerate = as_samplerate(samplerate)
    n_fft = as_positive_int(n_fft, name="n_fft")
    n_mels = as_positive_int(n_mels, name="n_mels")
    fmax = samplerate / 2 if fmax is None else fmax
    if not 0 <= fmin < fmax <= samplerate / 2:
        raise FeatureError(
            f"mel range must satisfy 0 <= fmin < fmax <= {samplerate / 2:g} Hz, "
            f"got fmin={fmin}, fmax={fmax}"
        )
    bins = np.arange(1 + n_fft // 2) * (samplerate / n_fft)
    edges = mel_to_hz(np.linspace(hz_to_mel(fmin), hz_to_mel(fmax), n_mels + 2))
    widths = np.diff(edges)
    offsets = edges[:, np.newaxis] - bins[np.newaxis, :]
    rising = -offsets[:-2] / widths[:-1, np.newaxis]
    falling = offsets[2:] / widths[1:, np.newaxis]
    weights = np.maximum(0.0, np.minimum(rising, falling))
    if normalize:
        weights *= (2.0 / (edges[2:] - edges[:-2]))[:, np.newaxis]
    return weights


def mel_spectrogram(power: np.ndarray, *, filter_bank: np.ndarray) -> np.ndarray:
    """Mel band energies, ``filter_bank @ power``.

    Parameters
    ----------
    power : ndarray of shape (..., n_bins, n_frames)
        Power spectrogram.
    filter_bank : ndarray of shape (n_mels, n_bins)

    Returns
    -------
    ndarray of shape (..., n_mels, n_frames)
    """
    if filter_bank.shape[-1] != power.shape[-2]:
        raise FeatureError(
            f"filter bank covers {filter_bank.shape[-1]} bins, the spectrogram has "
            f"{power.shape[-2]}"
        )
    return filter_bank @ power


def mfcc(mel_energies: np.ndarray, *, n_mfcc: int = 14, amin: float = 1e-10) -> np.ndarray:
    """Mel-frequency cepstral coefficients.

    ``c[..., q, t] = DCT-II_ortho(10 log10(max(E[..., :, t], amin)))[q]`` for
    ``q < n_mfcc``.

    Parameters
    ----------
    mel_energies : ndarray of shape (..., n_mels, n_frames)
        Mel spectrogram (power).
    n_mfcc : int
        Coefficients kept, at most ``n_mels``.
    amin : float
        Floor under the energies before the logarithm.

    Returns
    -------
    ndarray of shape (..., n_mfcc, n_frames)
    """
    n_mfcc = as_positive_int(n_mfcc, name="n_mfcc")
    if n_mfcc > mel_energies.shape[-2]:
        raise FeatureError(
            f"n_mfcc ({n_mfcc}) cannot exceed the number of mel bands ({mel_energies.shape[-2]})"
        )
    log_energies = 10.0 * np.log10(np.maximum(mel_energies, amin))
    return dct(log_energies, type=2, norm="ortho", axis=-2)[..., :n_mfcc, :]
