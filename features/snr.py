"""Signal-to-noise ratio of each window against a tracked noise floor, and the touches it finds.

The level of a window is its RMS.  Each channel keeps a running noise floor, an
exponential average of the levels of quiet windows,
``noise <- (1 - smoothing) noise + smoothing level``, started from the median level of
the first ``initial`` seconds.  A window's SNR is its level over the floor before it (a
linear amplitude ratio, not dB, as in the UC3M data where it is at least the threshold,
10).  A touch starts at the first window whose SNR exceeds ``threshold``; while it lasts
the floor is frozen, and it ends with the ``hangover``-th consecutive window at or
below the threshold (that window included).

The floor only follows the signal between touches, so the search jumps from one touch
to the next: each quiet stretch is one ``scipy.signal.lfilter`` call and each touch one
vectorised run search, with no Python loop over windows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from touchbench.features._checks import as_positive_int, as_samplerate, as_signal
from touchbench.features.errors import FeatureError
from touchbench.features.framing import frame
from touchbench.features.temporal import rms

_FIRST_CHUNK = 1024


@dataclass(frozen=True)
class Touch:
    """One channel's touch, in windows.

    Parameters
    ----------
    channel : int
        Channel index.
    first_window : int
        The window whose SNR first exceeded the threshold.
    last_window : int
        The last window of the hangover (inclusive), or the recording's last window.
    """

    channel: int
    first_window: int
    last_window: int


@dataclass(frozen=True)
class SnrTrack:
    """Per-window SNR of every channel and the touches it gives.

    Parameters
    ----------
    snr : ndarray of shape (n_channels, n_windows)
        Level over the noise floor in force at each window (linear ratio).
    noise : ndarray of shape (n_channels, n_windows)
        That noise floor (RMS units).
    level : ndarray of shape (n_channels, n_windows)
        RMS of each window.
    touches : tuple of Touch
        Sorted by first window, then channel.
    threshold : float
        SNR above which a window is active.
    window_length : int
        Samples per window (windows do not overlap).
    """

    snr: np.ndarray
    noise: np.ndarray
    level: np.ndarray
    touches: tuple[Touch, ...]
    threshold: float
    window_length: int

    @property
    def active(self) -> np.ndarray:
        """Windows whose SNR exceeds the threshold, bool (n_channels, n_windows)."""
        return self.snr > self.threshold


def snr_track(
    y: np.ndarray,
    *,
    samplerate: float,
    window_length: int = 256,
    threshold: float = 10.0,
    hangover: float = 0.5,
    smoothing: float = 0.05,
    initial: float = 0.1,
    noise_min: float = 1e-5,
) -> SnrTrack:
    """Track each channel's noise floor and find its touches.

    Parameters
    ----------
    y : ndarray of shape (n_channels, n_samples) or (n_samples,)
        Finite samples, at least one window long.
    samplerate : float
        Sample rate in Hz.
    window_length : int
        Samples per non-overlapping window (256 at 44.1 kHz in the UC3M data).
    threshold : float
        SNR (linear amplitude ratio) above which a window is active.
    hangover : float
        Seconds a touch must stay at or below the threshold to end;
        ``floor(hangover * samplerate / window_length)`` windows.
    smoothing : float
        Weight of a quiet window's level in the running noise floor, in (0, 1].
    initial : float
        Seconds at the start whose median level is the first noise floor.
    noise_min : float
        Lowest noise floor (RMS), so that digital silence does not divide by zero.

    Returns
    -------
    SnrTrack
    """
    samplerate = as_samplerate(samplerate)
    window_length = as_positive_int(window_length, name="window_length")
    y = np.atleast_2d(as_signal(y, min_samples=window_length))
    if y.ndim != 2:
        raise FeatureError(f"y must have shape (n_channels, n_samples), got {y.shape}")
    hangover_windows, initial_windows = tracking_windows(
        samplerate=samplerate,
        window_length=window_length,
        threshold=threshold,
        hangover=hangover,
        smoothing=smoothing,
        initial=initial,
        noise_min=noise_min,
    )
    level = rms(frame(y, frame_length=window_length, hop_length=window_length))
    noise = np.empty_like(level)
    touches: list[Touch] = []
    for channel in range(level.shape[0]):
        start_floor = max(float(np.median(level[channel, :initial_windows])), noise_min)
        touches += _track_channel(
            level[channel],
            noise[channel],
            channel=channel,
            floor=start_floor,
            threshold=threshold,
            hangover_windows=hangover_windows,
            smoothing=smoothing,
            noise_min=noise_min,
        )
    touches.sort(key=lambda touch: (touch.first_window, touch.channel))
    return SnrTrack(
        snr=level / noise,
        noise=noise,
        level=level,
        touches=tuple(touches),
        threshold=float(threshold),
        window_length=window_length,
    )


def tracking_windows(
    *,
    samplerate: float,
    window_length: int,
    threshold: float,
    hangover: float,
    smoothing: float,
    initial: float,
    noise_min: float,
) -> tuple[int, int]:
    """Check the tracker's parameters; ``(hangover_windows, initial_windows)``."""
    if threshold <= 0 or hangover < 0 or not 0 < smoothing <= 1 or noise_min <= 0:
        raise FeatureError(
            "threshold and noise_min must be positive, hangover at least 0 and smoothing in "
            f"(0, 1]; got threshold={threshold}, hangover={hangover}, smoothing={smoothing}, "
            f"noise_min={noise_min}"
        )
    hangover_windows = int(hangover * samplerate / window_length)
    return hangover_windows, max(1, int(initial * samplerate / window_length))


def _track_channel(
    level: np.ndarray,
    noise_out: np.ndarray,
    *,
    channel: int,
    floor: float,
    threshold: float,
    hangover_windows: int,
    smoothing: float,
    noise_min: float,
) -> list[Touch]:
    """Fill ``noise_out`` (n_windows,) with the floor each window met; return the touches."""
    n_windows = level.shape[0]
    touches = []
    position = 0
    while position < n_windows:
        onset, floor = _quiet_until_onset(
            level, noise_out, position, floor, threshold, smoothing, noise_min
        )
        if onset is None:
            break
        end = _touch_end(level, onset, floor * threshold, hangover_windows)
        noise_out[onset : end + 1] = floor
        touches.append(Touch(channel=channel, first_window=onset, last_window=end))
        position = end + 1
    return touches


def _quiet_until_onset(
    level: np.ndarray,
    noise_out: np.ndarray,
    start: int,
    floor: float,
    threshold: float,
    smoothing: float,
    noise_min: float,
) -> tuple[int | None, float]:
    """Follow the floor from ``start`` to the first active window; (onset or None, floor)."""
    n_windows = level.shape[0]
    chunk = _FIRST_CHUNK
    while start < n_windows:
        stop = min(n_windows, start + chunk)
        levels = level[start:stop]
        after = follow_floor(levels, floor=floor, smoothing=smoothing, noise_min=noise_min)
        before = np.concatenate([[floor], after[:-1]])
        loud = np.flatnonzero(levels > threshold * before)
        if loud.size:
            onset = start + int(loud[0])
            noise_out[start : onset + 1] = before[: loud[0] + 1]
            return onset, float(before[loud[0]])
        noise_out[start:stop] = before
        floor = float(after[-1])
        start = stop
        chunk *= 2
    return None, floor


def follow_floor(
    levels: np.ndarray, *, floor: float, smoothing: float, noise_min: float
) -> np.ndarray:
    """The noise floor after each quiet window, shape (n_windows,).

    ``floor[n] = max(noise_min, (1 - smoothing) floor[n - 1] + smoothing level[n])``,
    starting from ``floor``: one ``lfilter`` call, and an exact loop only where the
    floor would sink below ``noise_min`` (digital silence), so that the result does not
    depend on how the windows are split into calls.
    """
    after, _ = lfilter([smoothing], [1.0, smoothing - 1.0], levels, zi=[(1.0 - smoothing) * floor])
    if after.size == 0 or after.min() >= noise_min:
        return np.asarray(after)
    first = int(np.argmax(after < noise_min))
    current = float(after[first - 1]) if first else floor
    for index in range(first, after.size):
        current = max(noise_min, (1.0 - smoothing) * current + smoothing * float(levels[index]))
        after[index] = current
    return np.asarray(after)


def _touch_end(level: np.ndarray, onset: int, limit: float, hangover_windows: int) -> int:
    """Last window of the touch that starts at ``onset`` (inclusive)."""
    n_windows = level.shape[0]
    chunk = _FIRST_CHUNK
    while True:
        stop = min(n_windows, onset + 1 + chunk)
        loud = np.concatenate([[0], np.flatnonzero(level[onset + 1 : stop] > limit) + 1])
        gaps = np.diff(np.concatenate([loud, [stop - onset]])) - 1
        long_enough = np.flatnonzero(gaps >= hangover_windows)
        if long_enough.size:
            return min(onset + int(loud[long_enough[0]]) + hangover_windows, n_windows - 1)
        if stop == n_windows:
            return n_windows - 1
        chunk *= 2
