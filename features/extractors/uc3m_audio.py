"""``uc3m-audio``: the 33 statistics per contact microphone of the UC3M touch data sets.

Names and order are those of ``uc3m-touch/*/gesture_and_place.arff`` (``pitchFFT_1`` ...
``duration_1``, then ``_2``, ``_3``), generated for any number of channels.  Units and
semantics follow what the published values show:

* Analysis windows are 256 samples at 44.1 kHz, not overlapping (the pitchFFT and
  roll-off values are multiples of 44100 / 256 = 172.27 Hz and the durations multiples
  of 256 / 44.1 = 5.805 ms).  Spectra use a periodic Hann window.
* Statistics of a channel are taken over its *active* windows in the event: those whose
  SNR exceeds the detection threshold (so ``SNR`` is never below 10, as in the data).
  ``X`` is the mean, ``XMin``/``XMax`` the extremes, ``XDif`` the range.
* ``pitchFFT``: frequency of the largest magnitude bin, DC included (Hz).
* ``pitchAutocorrelation``: the window averaged in pairs (22.05 kHz) and searched over
  lags 2 to 31 (:func:`features.pitch.pitch_autocorrelation`), which reproduces the
  data's value set 22050 / lag, from 711.29 Hz (lag 31) to 11025 Hz (lag 2).
* ``pitchWavelet``: 0 in every published instance, so 0 by default; option
  ``wavelet_pitch=true`` fills it with the Larson-Maddox tracker
  (:func:`features.pitch.pitch_wavelet`) instead, which a model trained on the public
  data has never seen.
* ``centroide``: magnitude-weighted spectral centroid (Hz).  ``rollOff``: 95 % of the
  energy (power spectrum), in Hz; both as in the data, where the roll-off is mostly
  below the centroid.
* ``ganancia``: mean RMS of the active windows (full scale 1.0).
* ``flux``: distance between the L2-normalised magnitude spectra of a window and the
  window before it, between 0 and sqrt(2) (:func:`features.spectral.spectral_flux`).
* ``SNR``/``SNRMax``: mean and largest window RMS over the noise floor, a linear
  amplitude ratio (the data's values reach 447, impossible in dB).
* ``zeroXMean``, ``ZCRmin``, ``ZCRmax``, ``ZCRmax - ZCRmin``: zero crossings counted
  per 256-sample window.
* ``numWordsMinute``: a speech feature of the original pipeline, 0 in every published
  instance; always 0 here.
* ``duration``: milliseconds from the channel's first active window to the end of its
  hangover inside the event, a whole number of windows (with the 500 ms hangover the
  shortest touch lasts 87 windows = 505.03 ms, the data's minimum for the Mini robot).

A channel without an active window in the event gives 33 zeros; an event in which no
channel has one (clipped full-scale noise, whose floor is as loud as any touch) gives
all zeros, with a warning.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from touchbench.features.errors import FeatureError
from touchbench.features.events import Detection, Event
from touchbench.features.extractors.base import Extractor, Instances, channel_suffixed
from touchbench.features.framing import fft_frequencies, stft
from touchbench.features.options import Option, flag
from touchbench.features.pitch import pitch_autocorrelation, pitch_fft, pitch_wavelet
from touchbench.features.snr import SnrTrack, snr_track
from touchbench.features.spectral import spectral_centroid, spectral_flux, spectral_rolloff
from touchbench.features.stats import SegmentStatistics, segment_statistics
from touchbench.features.temporal import zero_crossings

WINDOW_LENGTH = 256
SAMPLERATE = 44100.0

_WITH_RANGE = ("", "Min", "Max", "Dif")

#: The 33 names of one channel, without the ``_N`` suffix, in the data sets' order.
CHANNEL_FEATURES: tuple[str, ...] = (
    *(f"pitchFFT{s}" for s in _WITH_RANGE),
    *(f"pitchAutocorrelation{s}" for s in _WITH_RANGE),
    *(f"pitchWavelet{s}" for s in _WITH_RANGE),
    *(f"centroide{s}" for s in _WITH_RANGE),
    *(f"rollOff{s}" for s in _WITH_RANGE),
    "ganancia",
    *(f"flux{s}" for s in _WITH_RANGE),
    "SNR",
    "SNRMax",
    "zeroXMean",
    "ZCRmin",
    "ZCRmax",
    "ZCRmax - ZCRmin",
    "numWordsMinute",
    "duration",
)


def uc3m_feature_names(n_channels: int, channels: Sequence[str] | None = None) -> list[str]:
    """The UC3M attribute names for ``n_channels`` microphones (33 per channel)."""
    return channel_suffixed(list(CHANNEL_FEATURES), n_channels, channels)


class Uc3mAudio(Extractor):
    """The UC3M contact-microphone statistics; see the module docstring."""

    name: ClassVar[str] = "uc3m-audio"
    description: ClassVar[str] = (
        "33 statistics per contact microphone as in the UC3M touch data sets (44.1 kHz)"
    )
    default_events: ClassVar[str] = "snr"
    samplerates: ClassVar[tuple[float, ...] | None] = (SAMPLERATE,)
    track_window: ClassVar[int | None] = WINDOW_LENGTH
    options: ClassVar[tuple[Option, ...]] = (
        Option("wavelet_pitch", False, flag, "fill pitchWavelet (0 in the published data)"),
    )

    def min_samples(self, samplerate: float) -> int:
        return WINDOW_LENGTH

    def read_span(self, event: Event, samplerate: float) -> tuple[int, int]:
        """Whole windows from the one before the onset's (the flux looks back one window)
        to the one holding the last sample."""
        first = event.onset // WINDOW_LENGTH
        return (first - 1) * WINDOW_LENGTH, math.ceil(event.offset / WINDOW_LENGTH) * WINDOW_LENGTH

    def lookback(self, samplerate: float) -> int:
        return 2 * WINDOW_LENGTH

    def feature_names(self, n_channels: int, channels: Sequence[str] | None = None) -> list[str]:
        return uc3m_feature_names(n_channels, channels)

    def extract(self, y: np.ndarray, *, samplerate: float, detection: Detection) -> Instances:
        track = detection.snr
        if track is None or track.window_length != WINDOW_LENGTH:
            track = snr_track(y, samplerate=samplerate, window_length=WINDOW_LENGTH)
        n_channels, n_windows = track.snr.shape
        if y.shape[0] != n_channels:
            raise FeatureError(f"the SNR track has {n_channels} channels, y has {y.shape[0]}")
        selection = _ActiveWindows.of(detection, track)
        origin = detection.origin
        warnings = [
            self._too_short((start + origin, end + origin), samplerate)
            for start, end in selection.too_short
        ]
        if not selection.events:
            return Instances.empty(len(CHANNEL_FEATURES) * n_channels, warnings)
        windows = y[:, : n_windows * WINDOW_LENGTH].reshape(n_channels, n_windows, WINDOW_LENGTH)
        per_window = self._window_features(windows, track, selection)
        stats = segment_statistics(per_window, lengths=selection.lengths)
        columns = _assemble(stats, selection.duration_windows)
        values = columns.reshape(len(selection.events), n_channels * len(CHANNEL_FEATURES))
        silent = selection.lengths.reshape(len(selection.events), n_channels).sum(axis=1) == 0
        warnings += [
            f"event at {(event.onset + origin) / samplerate:.3f}-"
            f"{(event.offset + origin) / samplerate:.3f} s has no window above the SNR "
            f"threshold on any channel: its {values.shape[1]} features are all 0 (is the "
            "signal clipped, or the noise floor as loud as the touch?)"
            for event, quiet in zip(selection.events, silent, strict=True)
            if quiet
        ]
        spans = np.array(
            [(event.onset, min(event.offset, y.shape[1])) for event in selection.events],
            dtype=np.int64,
        )
        meta = [
            {"channels": list(event.channels), "n_contacts": event.n_contacts}
            for event in selection.events
        ]
        return Instances(values=values, spans=spans, meta=meta, warnings=warnings)

    def _window_features(
        self, windows: np.ndarray, track: SnrTrack, selection: _ActiveWindows
    ) -> np.ndarray:
        """The 9 frame-wise features of every selected window, shape (9, n_selected)."""
        channel, window = selection.channel, selection.window
        n_selected, n_windows = window.size, windows.shape[1]
        # Active windows mostly follow each other, so the window before one is usually
        # another: transform each needed window once and pick both sets from it.
        flat = channel * n_windows + window
        has_previous = window > 0
        needed, where = np.unique(
            np.concatenate([flat, flat[has_previous] - 1]), return_inverse=True
        )
        spectra = np.abs(stft(windows[needed // n_windows, needed % n_windows].T, window="hann"))
        magnitude = spectra[:, where[:n_selected]]
        previous_magnitude = np.zeros_like(magnitude)
        previous_magnitude[:, has_previous] = spectra[:, where[n_selected:]]
        frames = windows[channel, window].T
        frequencies = fft_frequencies(samplerate=SAMPLERATE, n_fft=WINDOW_LENGTH)
        half_rate = SAMPLERATE / 2
        paired = 0.5 * (frames[0::2] + frames[1::2])
        if self.params["wavelet_pitch"]:
            wavelet = pitch_wavelet(frames, samplerate=SAMPLERATE)
        else:
            wavelet = np.zeros(frames.shape[-1])
        return np.stack(
            [
                pitch_fft(magnitude, frequencies=frequencies),
                pitch_autocorrelation(
                    paired, samplerate=half_rate, fmin=half_rate / 31, fmax=half_rate / 2
                ),
                wavelet,
                spectral_centroid(magnitude, frequencies=frequencies),
                spectral_rolloff(magnitude**2, frequencies=frequencies, roll_percent=0.95),
                track.level[channel, window],
                spectral_flux(magnitude, previous=previous_magnitude),
                track.snr[channel, window],
                zero_crossings(frames).astype(np.float64),
            ]
        )


class _ActiveWindows:
    """The active windows of each (event, channel), flattened and grouped contiguously."""

    def __init__(self) -> None:
        self.events: list[Event] = []
        self.too_short: list[tuple[int, int]] = []
        self.channel = np.zeros(0, dtype=np.int64)
        self.window = np.zeros(0, dtype=np.int64)
        self.lengths = np.zeros(0, dtype=np.int64)
        self.duration_windows = np.zeros(0, dtype=np.int64)

    @classmethod
    def of(cls, detection: Detection, track: SnrTrack) -> _ActiveWindows:
        selection = cls()
        n_channels, n_windows = track.snr.shape
        active = track.active
        touch_spans = [
            np.array(
                [(t.first_window, t.last_window) for t in track.touches if t.channel == c],
                dtype=np.int64,
            ).reshape(-1, 2)
            for c in range(n_channels)
        ]
        channels, windows, lengths, durations = [], [], [], []
        for event in detection.events:
            first = event.onset // WINDOW_LENGTH
            last = min(math.ceil(event.offset / WINDOW_LENGTH), n_windows) - 1
            if last < first:
                selection.too_short.append((event.onset, event.offset))
                continue
            selection.events.append(event)
            for c in range(n_channels):
                found = first + np.flatnonzero(active[c, first : last + 1])
                channels.append(np.full(found.size, c))
                windows.append(found)
                lengths.append(found.size)
                durations.append(_duration(touch_spans[c], first, last) if found.size else 0)
        if selection.events:
            selection.channel = np.concatenate(channels).astype(np.int64)
            selection.window = np.concatenate(windows).astype(np.int64)
            selection.lengths = np.array(lengths, dtype=np.int64)
            selection.duration_windows = np.array(durations, dtype=np.int64)
        return selection


def _duration(spans: np.ndarray, first: int, last: int) -> int:
    """Windows from the first touch onset to the last touch end inside [first, last]."""
    overlapping = spans[(spans[:, 0] <= last) & (spans[:, 1] >= first)]
    if overlapping.size == 0:
        return last - first + 1
    return int(min(overlapping[:, 1].max(), last) - max(overlapping[:, 0].min(), first) + 1)


def _assemble(stats: SegmentStatistics, duration_windows: np.ndarray) -> np.ndarray:
    """The 33 columns of every (event, channel) group, shape (n_groups, 33)."""
    mean, low, high, spread = stats.mean, stats.minimum, stats.maximum, stats.range
    (fft, autocorrelation, wavelet, centroid, rolloff, gain, flux, snr, crossings) = range(9)

    def four(row: int) -> list[np.ndarray]:
        return [mean[row], low[row], high[row], spread[row]]

    duration_ms = duration_windows * (1000.0 * WINDOW_LENGTH / SAMPLERATE)
    columns = [
        *four(fft),
        *four(autocorrelation),
        *four(wavelet),
        *four(centroid),
        *four(rolloff),
        mean[gain],
        *four(flux),
        mean[snr],
        high[snr],
        *four(crossings),
        np.zeros_like(duration_ms),
        duration_ms,
    ]
    return np.stack(columns, axis=-1)
