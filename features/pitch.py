"""Pitch of each frame: by FFT peak, by autocorrelation, and by a dyadic wavelet tracker.

Every function returns one frequency in Hz per frame, shape ``(..., n_frames)``; the
autocorrelation and wavelet trackers return 0 for a frame without a pitch (silence).
"""

from __future__ import annotations

import math

import numpy as np

from touchbench.features._checks import as_positive_int, as_samplerate
from touchbench.features.errors import FeatureError


def pitch_fft(
    S: np.ndarray,
    *,
    frequencies: np.ndarray,
    fmin: float | None = None,
    fmax: float | None = None,
) -> np.ndarray:
    """Frequency of the largest bin of each frame's spectrum.

    ``pitch[t] = f[argmax_k S[k, t]]`` over the bins with ``fmin <= f[k] <= fmax``
    (every bin, the DC bin included, by default), so the result is a multiple of
    ``samplerate / n_fft``.

    Parameters
    ----------
    S : ndarray of shape (..., n_bins, n_frames)
        Magnitude or power spectrogram.
    frequencies : ndarray of shape (n_bins,)
        Bin frequencies in Hz.
    fmin, fmax : float, optional
        Search range in Hz.

    Returns
    -------
    ndarray of shape (..., n_frames)
    """
    frequencies = np.asarray(frequencies, dtype=np.float64)
    if S.ndim < 2 or frequencies.shape != (S.shape[-2],):
        raise FeatureError(
            f"S has shape {S.shape}; frequencies must have shape ({S.shape[-2]},), "
            f"got {frequencies.shape}"
        )
    low = -np.inf if fmin is None else fmin
    high = np.inf if fmax is None else fmax
    searched = np.flatnonzero((frequencies >= low) & (frequencies <= high))
    if searched.size == 0:
        raise FeatureError(f"no frequency bin between fmin={fmin} and fmax={fmax} Hz")
    best = np.argmax(S[..., searched, :], axis=-2)
    return frequencies[searched[best]]


def pitch_autocorrelation(
    frames: np.ndarray, *, samplerate: float, fmin: float, fmax: float
) -> np.ndarray:
    """Pitch from the autocorrelation of each frame.

    ``r[tau] = sum_n x[n] x[n + tau]`` (computed by FFT) is searched over the lags
    ``tau_min = ceil(samplerate / fmax)`` to ``tau_max = floor(samplerate / fmin)``: from
    the first local minimum of ``r`` in that range, the lag ``tau*`` of the largest value
    is the period, and ``pitch = samplerate / tau*``.  When ``r`` only falls over the
    range (content below ``fmin``) the period is ``tau_max`` and the pitch ``fmin``.
    A silent frame gives 0.

    Parameters
    ----------
    frames : ndarray of shape (..., frame_length, n_frames)
        Frames as :func:`features.framing.frame` returns them.
    samplerate : float
        Sample rate of the frames in Hz.
    fmin, fmax : float
        Lowest and highest pitch in Hz; ``samplerate / fmin`` must be shorter than a frame.

    Returns
    -------
    ndarray of shape (..., n_frames)
        Multiples of ``samplerate / tau`` for whole lags ``tau``.
    """
    samplerate = as_samplerate(samplerate)
    frame_length = frames.shape[-2]
    lag_min = max(1, math.ceil(samplerate / fmax - 1e-9))
    lag_max = math.floor(samplerate / fmin + 1e-9)
    if not 0 < fmin < fmax or lag_max < lag_min + 1 or lag_max >= frame_length:
        raise FeatureError(
            f"pitch range [{fmin:g}, {fmax:g}] Hz gives lags {lag_min}..{lag_max} samples, "
            f"which must be at least two lags shorter than a frame of {frame_length}"
        )
    n_fft = 1 << (2 * frame_length - 1).bit_length()
    spectrum = np.fft.rfft(np.swapaxes(frames, -1, -2), n=n_fft, axis=-1)
    power = spectrum.real**2 + spectrum.imag**2
    # Only the first lags are needed: the inverse DFT of the (real, even) power spectrum
    # at those lags is a small cosine product, cheaper than a whole inverse transform.
    bins = np.arange(power.shape[-1])
    fold = np.where((bins == 0) | (bins == n_fft // 2), 1.0, 2.0) / n_fft
    basis = fold[:, np.newaxis] * np.cos(2 * np.pi * np.outer(bins, np.arange(lag_max + 1)) / n_fft)
    r = np.swapaxes(power @ basis, -1, -2)
    searched = r[..., lag_min:, :]
    rising = searched[..., 1:, :] >= searched[..., :-1, :]
    first_minimum = np.where(
        rising.any(axis=-2), np.argmax(rising, axis=-2), searched.shape[-2] - 1
    )
    lags = np.arange(searched.shape[-2])[:, np.newaxis]
    candidates = np.where(lags >= first_minimum[..., np.newaxis, :], searched, -np.inf)
    period = lag_min + np.argmax(candidates, axis=-2)
    silent = r[..., 0, :] <= 0
    return np.where(silent, 0.0, samplerate / period)


def pitch_wavelet(
    frames: np.ndarray,
    *,
    samplerate: float,
    fmax: float = 3000.0,
    levels: int = 6,
    threshold_ratio: float = 0.75,
    neighbours: int = 3,
) -> np.ndarray:
    """Pitch by the dyadic wavelet tracker of Larson and Maddox (2005).

    At each level the mean-removed frame is searched for the extremum of every lobe
    between zero crossings that exceeds ``threshold_ratio`` of the frame's largest
    (maxima) or smallest (minima) value.  The distances from each such extremum to the
    next ``neighbours`` extrema of the same kind are histogrammed; the mode, allowing
    ``delta = max(1, floor(rate / (2 fmax)))`` samples of tolerance (less than half
    the shortest period, so that a period and its double never merge), and refined as the mean
    of the distances within ``delta`` of it, is the period candidate.  When the candidate
    at one level is half the candidate of the level above (within ``2 delta``), the period
    is confirmed and ``pitch = rate / period`` at the finer level.  Otherwise the frame is
    replaced by its Haar approximation (pairwise means, half the rate) and the next level
    is tried.  Frames confirmed at no level, or with a pitch above ``fmax``, give 0.

    Parameters
    ----------
    frames : ndarray of shape (..., frame_length, n_frames)
        Frames as :func:`features.framing.frame` returns them.
    samplerate : float
        Sample rate in Hz.
    fmax : float
        Highest pitch in Hz.
    levels : int
        Most wavelet levels to descend.
    threshold_ratio : float
        Fraction of the frame's extreme values an extremum must reach, in (0, 1].
    neighbours : int
        How many following extrema each extremum is measured against.

    Returns
    -------
    ndarray of shape (..., n_frames)
    """
    samplerate = as_samplerate(samplerate)
    levels = as_positive_int(levels, name="levels")
    neighbours = as_positive_int(neighbours, name="neighbours")
    if not 0 < threshold_ratio <= 1:
        raise FeatureError(f"threshold_ratio must be in (0, 1], got {threshold_ratio}")
    if not 0 < fmax < samplerate / 2:
        raise FeatureError(f"fmax must be between 0 and {samplerate / 2:g} Hz, got {fmax}")
    batch_shape = frames.shape[:-2] + frames.shape[-1:]
    signal = np.moveaxis(frames, -2, -1).reshape(-1, frames.shape[-2])
    signal = signal - signal.mean(axis=1, keepdims=True)
    pitch = np.zeros(signal.shape[0])
    undecided = np.ones(signal.shape[0], dtype=bool)
    previous_period = np.full(signal.shape[0], np.nan)
    previous_delta = 1
    rate = samplerate
    for _ in range(levels):
        if signal.shape[1] < 4 or not undecided.any():
            break
        delta = max(1, int(rate / (2 * fmax)))
        period = _period_candidates(signal, threshold_ratio, neighbours, delta)
        confirmed = undecided & (np.abs(previous_period - 2 * period) <= 2 * previous_delta)
        pitch[confirmed] = (2 * rate) / previous_period[confirmed]
        undecided &= ~confirmed
        previous_period, previous_delta = period, delta
        even = signal.shape[1] - signal.shape[1] % 2
        signal = 0.5 * (signal[:, 0:even:2] + signal[:, 1:even:2])
        rate /= 2
    pitch[pitch > fmax] = 0.0
    return pitch.reshape(batch_shape)


def _period_candidates(
    signal: np.ndarray, threshold_ratio: float, neighbours: int, delta: int
) -> np.ndarray:
    """Mode of the extremum distances of each row, NaN where there is none; shape (n_rows,)."""
    n_rows, length = signal.shape
    histogram = np.zeros((n_rows, length + 1))
    for extrema in (
        _lobe_extrema(signal, threshold_ratio),
        _lobe_extrema(-signal, threshold_ratio),
    ):
        rows, columns = np.nonzero(extrema)
        for offset in range(1, neighbours + 1):
            same_row = rows[offset:] == rows[:-offset]
            distances = (columns[offset:] - columns[:-offset])[same_row]
            np.add.at(histogram, (rows[:-offset][same_row], distances), 1.0)
    width = 2 * delta + 1
    distance_axis = np.arange(length + 1, dtype=np.float64)
    counts = _moving_sum(histogram, width)
    sums = _moving_sum(histogram * distance_axis, width)
    mode = np.argmax(counts, axis=1)
    best = counts[np.arange(n_rows), mode]
    return np.where(best > 0, sums[np.arange(n_rows), mode] / np.maximum(best, 1), np.nan)


def _lobe_extrema(signal: np.ndarray, threshold_ratio: float) -> np.ndarray:
    """Where each positive lobe of each row peaks above ``threshold_ratio`` of the row maximum."""
    positive = signal > 0
    starts = np.ones_like(positive)
    starts[:, 1:] = positive[:, 1:] != positive[:, :-1]
    flat_starts = np.flatnonzero(starts)
    lobe = np.cumsum(starts.ravel()) - 1
    lobe_max = np.maximum.reduceat(signal.ravel(), flat_starts)[lobe].reshape(signal.shape)
    threshold = threshold_ratio * signal.max(axis=1, keepdims=True)
    at_peak = positive & (signal == lobe_max) & (signal >= threshold)
    repeated = np.zeros_like(at_peak)
    repeated[:, 1:] = at_peak[:, 1:] & at_peak[:, :-1] & ~starts[:, 1:]
    return at_peak & ~repeated


def _moving_sum(values: np.ndarray, width: int) -> np.ndarray:
    """Centred sum over ``width`` neighbours along axis 1, zero-padded; same shape."""
    half = width // 2
    padded = np.pad(values, ((0, 0), (half + 1, half)))
    cumulative = np.cumsum(padded, axis=1)
    return cumulative[:, width:] - cumulative[:, :-width]
