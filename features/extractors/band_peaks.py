"""``band-peaks``: an actively oscillated rigid link with an accelerometer (3200 Hz, 1 s).

For each instance (by default each second of the recording):

* ``theta = atan(RMS(vertical) / RMS(horizontal))`` in radians, where the vertical axis
  is one channel (option ``vertical``, 1-based, default the last) and the horizontal
  acceleration is the vector of every other channel,
  ``RMS(horizontal) = sqrt(sum_h RMS(h)**2)``; the raw samples are used, as recorded.
* For every band (option ``bands``, default 0-120, 500-550 and 825-925 Hz): the
  frequency of the highest peak of the vertical axis' amplitude spectrum in the band and
  its prominence as ``scipy.signal.peak_prominences`` defines it
  (:func:`features.spectral.band_peak`).  The spectrum is that of the mean-removed,
  Hann-windowed instance, scaled to the amplitude of a sinusoid
  (``2 |X| / sum(window)``), with a resolution of ``samplerate / n_samples``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from touchbench.features.errors import FeatureError
from touchbench.features.events import Detection
from touchbench.features.extractors.base import Extractor, Instances
from touchbench.features.framing import fft_frequencies, window_function
from touchbench.features.options import Option, frequency_bands, positive_int
from touchbench.features.spectral import band_peak
from touchbench.features.temporal import rms

DEFAULT_BANDS: tuple[tuple[float, float], ...] = ((0.0, 120.0), (500.0, 550.0), (825.0, 925.0))


class BandPeaks(Extractor):
    """Tilt angle and band peak frequencies/prominences; see the module docstring."""

    name: ClassVar[str] = "band-peaks"
    description: ClassVar[str] = (
        "accelerometer tilt angle and spectral peaks in frequency bands (3200 Hz, 1 s)"
    )
    default_events: ClassVar[str] = "none"
    default_segment: ClassVar[float | None] = 1.0
    min_channels: ClassVar[int] = 2
    options: ClassVar[tuple[Option, ...]] = (
        Option("bands", DEFAULT_BANDS, frequency_bands, "bands in Hz, e.g. 0-120,500-550"),
        Option("vertical", None, positive_int, "1-based channel of the vertical axis (last)"),
    )

    @property
    def bands(self) -> tuple[tuple[float, float], ...]:
        return tuple(self.params["bands"])

    def check_input(self, *, samplerate: float, n_channels: int) -> None:
        super().check_input(samplerate=samplerate, n_channels=n_channels)
        highest = max(high for _, high in self.bands)
        if samplerate / 2 < highest:
            raise FeatureError(
                f"extractor '{self.name}' needs a sample rate of at least {2 * highest:g} Hz "
                f"for its band up to {highest:g} Hz, got {samplerate:g} Hz"
            )
        vertical = self.params["vertical"]
        if vertical is not None and vertical > n_channels:
            raise FeatureError(
                f"option 'vertical' of extractor '{self.name}' is channel {vertical}, "
                f"but the recording has {n_channels} channels"
            )

    def min_samples(self, samplerate: float) -> int:
        narrowest = min(high - low for low, high in self.bands)
        return max(3, math.ceil(samplerate / narrowest))

    def feature_names(self, n_channels: int, channels: Sequence[str] | None = None) -> list[str]:
        names = ["theta"]
        for low, high in self.bands:
            names += [f"peakFrequency_{low:g}_{high:g}", f"peakProminence_{low:g}_{high:g}"]
        return names

    def extract(self, y: np.ndarray, *, samplerate: float, detection: Detection) -> Instances:
        n_channels = y.shape[0]
        vertical = (self.params["vertical"] or n_channels) - 1
        horizontal = [c for c in range(n_channels) if c != vertical]
        rows, spans, meta = [], [], []
        segments, warnings = self._long_enough(y, samplerate=samplerate, detection=detection)
        for event, segment in segments:
            level = rms(segment[:, :, np.newaxis])[:, 0]
            theta = math.atan2(level[vertical], float(np.sqrt(np.sum(level[horizontal] ** 2))))
            spectrum, frequencies = _amplitude_spectrum(segment[vertical], samplerate)
            row = [theta]
            for band in self.bands:
                frequency, prominence = band_peak(spectrum, frequencies=frequencies, band=band)
                row += [float(frequency), float(prominence)]
            rows.append(row)
            spans.append((event.onset, event.offset))
            meta.append({"channels": list(event.channels), "n_contacts": event.n_contacts})
        if not rows:
            return Instances.empty(len(self.feature_names(n_channels)), warnings)
        return Instances(
            values=np.array(rows, dtype=np.float64),
            spans=np.array(spans, dtype=np.int64),
            meta=meta,
            warnings=warnings,
        )


def _amplitude_spectrum(x: np.ndarray, samplerate: float) -> tuple[np.ndarray, np.ndarray]:
    """Amplitude spectrum (n_bins,) of the mean-removed, Hann-windowed ``x``, and its bins."""
    weights = window_function("hann", x.shape[0])
    assert weights is not None
    spectrum = np.abs(np.fft.rfft((x - x.mean()) * weights)) * (2.0 / weights.sum())
    return spectrum, fft_frequencies(samplerate=samplerate, n_fft=x.shape[0])
