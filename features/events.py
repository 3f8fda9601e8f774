"""Touch event detection: where in a recording the instances are.

Three kinds, each a function from samples ``(n_channels, n_samples)`` to a
:class:`Detection`, registered in :data:`EVENT_KINDS` with their options:

``snr``
    Each channel's SNR over its running noise floor (:mod:`features.snr`); touches that
    overlap on several channels form one event from the first onset to the last end.
    The contacts of an event are its bursts of active windows (on any channel)
    separated by more than ``contact_gap`` seconds.
``dbscan``
    Samples of the high-pass-filtered signal (first-order Butterworth, causal, so that
    onsets are not smeared backwards) beyond ``threshold`` robust standard deviations
    (``median |x| / 0.6745`` over the first ``initial`` seconds, so that a live stream
    finds the same events as the whole recording), pooled over channels, are clustered
    in time by
    DBSCAN (``eps`` seconds, ``min_samples`` samples); each cluster is one event with one
    contact, isolated detections are dropped as jitter.
``none``
    The whole recording, or consecutive segments of ``segment`` seconds, is each one
    event (a trailing remainder shorter than a segment is left out with a warning).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.signal import butter, sosfilt, sosfilt_zi
from sklearn.cluster import DBSCAN

from touchbench.features._checks import as_samplerate, as_signal
from touchbench.features.errors import FeatureError
from touchbench.features.options import (
    Option,
    fraction,
    non_negative_float,
    positive_float,
    positive_int,
    resolve_options,
)
from touchbench.features.snr import SnrTrack, snr_track


@dataclass(frozen=True)
class Event:
    """One detected touch event.

    Parameters
    ----------
    onset : int
        First sample of the event.
    offset : int
        One past its last sample.
    channels : tuple of int
        Channels that took part.
    n_contacts : int or None
        Contacts counted inside the event; ``None`` where the detector does not count.
    """

    onset: int
    offset: int
    channels: tuple[int, ...]
    n_contacts: int | None = None

    def seconds(self, samplerate: float) -> tuple[float, float]:
        """``(start, end)`` in seconds."""
        return self.onset / samplerate, self.offset / samplerate


@dataclass(frozen=True)
class Detection:
    """The events of one recording, the SNR track when the detector made one, warnings.

    ``origin`` is the recording's sample at index 0 of the samples the events refer to
    (non-zero when a stream hands an extractor one event's stretch of samples); it only
    places the times of messages.
    """

    events: tuple[Event, ...]
    snr: SnrTrack | None = None
    warnings: tuple[str, ...] = ()
    origin: int = 0


def detect_snr(
    y: np.ndarray,
    *,
    samplerate: float,
    window_length: int = 256,
    threshold: float = 10.0,
    hangover: float = 0.5,
    smoothing: float = 0.05,
    initial: float = 0.1,
    noise_min: float = 1e-5,
    contact_gap: float = 0.05,
) -> Detection:
    """Events where a channel's SNR over its tracked noise floor exceeds ``threshold``.

    Parameters
    ----------
    y : ndarray of shape (n_channels, n_samples)
        Finite samples.
    samplerate : float
        Sample rate in Hz.
    window_length, threshold, hangover, smoothing, initial, noise_min
        As :func:`features.snr.snr_track` (defaults: the UC3M values, 256 samples,
        SNR 10, 500 ms).
    contact_gap : float
        Seconds of inactivity on every channel that separate two contacts.

    Returns
    -------
    Detection
        Events in time order, with the SNR track.
    """
    samplerate = as_samplerate(samplerate)
    track = snr_track(
        y,
        samplerate=samplerate,
        window_length=window_length,
        threshold=threshold,
        hangover=hangover,
        smoothing=smoothing,
        initial=initial,
        noise_min=noise_min,
    )
    gap_windows = int(contact_gap * samplerate / track.window_length)
    active_windows = np.flatnonzero(track.active.any(axis=0))
    events = []
    for first, last, channels in _merge_touch_spans(track):
        inside = active_windows[
            np.searchsorted(active_windows, first) : np.searchsorted(active_windows, last, "right")
        ]
        contacts = 1 + int(np.count_nonzero(np.diff(inside) > gap_windows + 1))
        events.append(
            Event(
                onset=first * track.window_length,
                offset=(last + 1) * track.window_length,
                channels=channels,
                n_contacts=contacts,
            )
        )
    return Detection(events=tuple(events), snr=track)


def _merge_touch_spans(track: SnrTrack) -> list[tuple[int, int, tuple[int, ...]]]:
    """Touches that overlap in time, merged: (first window, last window, channels)."""
    merged: list[tuple[int, int, set[int]]] = []
    for touch in track.touches:
        if merged and touch.first_window <= merged[-1][1]:
            first, last, channels = merged[-1]
            channels.add(touch.channel)
            merged[-1] = (first, max(last, touch.last_window), channels)
        else:
            merged.append((touch.first_window, touch.last_window, {touch.channel}))
    return [(first, last, tuple(sorted(channels))) for first, last, channels in merged]


def detect_dbscan(
    y: np.ndarray,
    *,
    samplerate: float,
    cutoff: float = 1.0,
    threshold: float = 5.0,
    eps: float = 0.1,
    min_samples: int = 3,
    initial: float = 1.0,
) -> Detection:
    """Events as DBSCAN clusters of supra-threshold sample times.

    Parameters
    ----------
    y : ndarray of shape (n_channels, n_samples)
        Finite samples.
    samplerate : float
        Sample rate in Hz.
    cutoff : float
        Corner of the first-order Butterworth high-pass (causal), in Hz.
    threshold : float
        Detection level in robust standard deviations of each filtered channel.
    eps : float
        DBSCAN neighbourhood in seconds.
    min_samples : int
        Supra-threshold samples within ``eps`` that make a core point.
    initial : float
        Seconds at the start whose filtered samples give each channel's robust
        standard deviation (causal, so that a live stream detects the same events).

    Returns
    -------
    Detection
        One event per cluster, ``n_contacts = 1``.
    """
    samplerate = as_samplerate(samplerate)
    y = np.atleast_2d(as_signal(y))
    sos = dbscan_filter(samplerate, cutoff)
    # Start in the steady state of the first sample, so that an offset is no event.
    state = sosfilt_zi(sos)[:, np.newaxis, :] * y[np.newaxis, :, :1]
    filtered, _ = sosfilt(sos, y, axis=-1, zi=state)
    head = filtered[:, : max(1, round(initial * samplerate))]
    scale = np.median(np.abs(head), axis=-1, keepdims=True) / 0.6745
    above = np.abs(filtered) > threshold * np.maximum(scale, np.finfo(float).tiny)
    channel, start, stop = runs(above)
    return Detection(
        events=tuple(
            dbscan_events(channel, start, stop, radius=eps * samplerate, min_samples=min_samples)
        )
    )


def dbscan_filter(samplerate: float, cutoff: float) -> np.ndarray:
    """The first-order Butterworth high-pass of the ``dbscan`` detector, as SOS."""
    if not 0 < cutoff < samplerate / 2:
        raise FeatureError(
            f"dbscan cutoff must be between 0 and the Nyquist frequency "
            f"{samplerate / 2:g} Hz, got {cutoff:g}"
        )
    return np.asarray(butter(1, cutoff, btype="highpass", fs=samplerate, output="sos"))


def dbscan_events(
    channel: np.ndarray, start: np.ndarray, stop: np.ndarray, *, radius: float, min_samples: int
) -> list[Event]:
    """DBSCAN over runs of supra-threshold samples: one event per cluster, in time order."""
    if start.size == 0:
        return []
    times, weights, owner = run_points(start, stop, stride=max(1, int(radius // 2)))
    labels = DBSCAN(eps=radius, min_samples=min_samples).fit_predict(
        times[:, np.newaxis], sample_weight=weights
    )
    channels_of = channel[owner]
    events = []
    for label in np.unique(labels[labels >= 0]):
        member = labels == label
        events.append(
            Event(
                onset=int(times[member].min()),
                offset=int(times[member].max()) + 1,
                channels=tuple(int(c) for c in np.unique(channels_of[member])),
                n_contacts=1,
            )
        )
    events.sort(key=lambda event: event.onset)
    return events


def run_points(
    start: np.ndarray, stop: np.ndarray, *, stride: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points standing for runs of samples: (times, weights, run index), one per stride.

    A run is represented by samples ``stride`` apart from its start, plus its last
    sample, so that consecutive points stay within DBSCAN's ``eps``; the points of a run
    share its length as weight, so that it counts as its samples towards
    ``min_samples``.
    """
    lengths = stop - start
    counts = (lengths - 1) // stride + 1 + ((lengths - 1) % stride > 0)
    owner = np.repeat(np.arange(start.size), counts)
    rank = np.arange(owner.size) - np.repeat(np.cumsum(counts) - counts, counts)
    times = np.minimum(start[owner] + rank * stride, stop[owner] - 1).astype(np.float64)
    weights = (lengths / counts)[owner].astype(np.float64)
    return times, weights, owner


def runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs of True along the last axis: (channel, start, stop) arrays, stop exclusive."""
    padded = np.zeros((mask.shape[0], mask.shape[1] + 2), dtype=np.int8)
    padded[:, 1:-1] = mask
    change = np.diff(padded, axis=-1)
    channel, start = np.nonzero(change == 1)
    _, stop = np.nonzero(change == -1)
    return channel, start, stop


def detect_none(y: np.ndarray, *, samplerate: float, segment: float | None = None) -> Detection:
    """The whole recording, or each whole ``segment`` seconds of it, as one event.

    Parameters
    ----------
    y : ndarray of shape (n_channels, n_samples)
    samplerate : float
        Sample rate in Hz.
    segment : float, optional
        Segment length in seconds.

    Returns
    -------
    Detection
        Events without a contact count.
    """
    samplerate = as_samplerate(samplerate)
    n_channels, n_samples = np.atleast_2d(y).shape
    channels = tuple(range(n_channels))
    if segment is None:
        return Detection(events=(Event(0, n_samples, channels),))
    length = round(segment * samplerate)
    if segment <= 0 or length < 1:
        raise FeatureError(f"segment must be a positive number of seconds, got {segment}")
    count = n_samples // length
    if count == 0:
        raise FeatureError(
            f"the recording lasts {n_samples / samplerate:g} s, shorter than one segment "
            f"of {segment:g} s"
        )
    warnings = []
    if n_samples % length:
        warnings.append(
            f"the last {(n_samples % length) / samplerate:g} s are shorter than a segment "
            "and were left out"
        )
    events = tuple(Event(k * length, (k + 1) * length, channels) for k in range(count))
    return Detection(events=events, warnings=tuple(warnings))


@dataclass(frozen=True)
class EventKind:
    """A registered detector: its name, a description, its options and the function."""

    name: str
    description: str
    options: tuple[Option, ...]
    detect: Callable[..., Detection]


EVENT_KINDS: dict[str, EventKind] = {
    kind.name: kind
    for kind in (
        EventKind(
            name="snr",
            description="SNR over a running noise floor with a hangover (audio)",
            options=(
                Option("window_length", 256, positive_int, "samples per SNR window"),
                Option("threshold", 10.0, positive_float, "SNR (linear ratio) of a touch"),
                Option("hangover", 0.5, non_negative_float, "seconds below threshold to end"),
                Option("smoothing", 0.05, fraction, "weight of a quiet window in the floor"),
                Option("initial", 0.1, positive_float, "seconds that start the noise floor"),
                Option("noise_min", 1e-5, positive_float, "lowest noise floor (RMS)"),
                Option("contact_gap", 0.05, non_negative_float, "seconds between contacts"),
            ),
            detect=detect_snr,
        ),
        EventKind(
            name="dbscan",
            description="high-pass threshold, then DBSCAN over detection times",
            options=(
                Option("cutoff", 1.0, positive_float, "high-pass corner in Hz"),
                Option("threshold", 5.0, positive_float, "robust standard deviations"),
                Option("eps", 0.1, positive_float, "DBSCAN neighbourhood in seconds"),
                Option("min_samples", 3, positive_int, "samples that make a core point"),
                Option("initial", 1.0, positive_float, "seconds that give the robust scale"),
            ),
            detect=detect_dbscan,
        ),
        EventKind(
            name="none",
            description="each recording (or each `segment` seconds of it) is one instance",
            options=(),
            detect=detect_none,
        ),
    )
}


def detect_events(
    kind: str,
    y: np.ndarray,
    *,
    samplerate: float,
    segment: float | None = None,
    options: Mapping[str, Any] | None = None,
) -> Detection:
    """Run the detector called ``kind`` with ``options`` (see :data:`EVENT_KINDS`).

    Raises
    ------
    FeatureError
        For an unknown kind or option, a segment with a kind other than ``none``, or bad
        samples.
    """
    if kind not in EVENT_KINDS:
        raise FeatureError(f"unknown event detection '{kind}' (known: {', '.join(EVENT_KINDS)})")
    spec = EVENT_KINDS[kind]
    parsed = resolve_options(spec.options, options or {}, owner=f"events '{kind}'")
    if kind == "none":
        return detect_none(y, samplerate=samplerate, segment=segment)
    if segment is not None:
        raise FeatureError(f"a segment length only applies to events 'none', not '{kind}'")
    return spec.detect(y, samplerate=samplerate, **parsed)
