"""``taxel-dft``: DFT features of tactile arrays (sliding vs. slipping), one per window.

Every event (by default the whole recording) is cut into ``window``-sample windows
(default 64) shifted by ``step`` samples (default 8); each window is one instance.  Per
channel, the DFT of the window (rectangular, unscaled:
``X[k] = sum_n x[n] exp(-2 pi i k n / window)``) has its bins 0 to ``window / 2 - 1``;
the ``drop`` lowest are dropped and the real parts of the others are the features
``dft4_1 ... dft31_1``, then channel 2, ....

The published values are for BioTacs at 750-800 Hz: 64-sample windows, step 8, the 4
lowest bins dropped (DC to ``3 samplerate / 64``: a high-pass at ``samplerate / 16``,
about 50 Hz, that keeps the slip vibrations and removes the slow pressure changes).
``window`` and ``step`` are kept at every rate (the window's 32 bins are the features;
step 8 keeps 7/8 overlap).  The default ``drop`` follows the rate
(:func:`default_drop`): 4 from 400 Hz up, as published; below, ``samplerate / 16`` is
under 25 Hz and would take the slip signal itself (at 100 Hz, whose Nyquist frequency
is 50 Hz, the 4 bins are the band below 6.25 Hz where most of a 100 Hz sensor's slip
signal lies; rf on slip direction goes from 0.49 to 0.63 with one bin dropped), so
only the DC bin (the static pressure) is dropped.  ``drop=0`` keeps every bin.

Extraction memory: the windows are transformed a batch at a time
(:data:`WINDOWS_PER_BATCH`), so the temporary spectra stay bounded whatever the
recording's length; the features themselves are what is kept.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from touchbench.features.errors import FeatureError
from touchbench.features.events import Detection
from touchbench.features.extractors.base import Extractor, Instances, channel_suffixed
from touchbench.features.framing import frame, frame_count, stft
from touchbench.features.options import Option, non_negative_int, positive_int

#: Below this rate only the DC bin is dropped by default (see the module docstring).
FULL_DROP_RATE = 400.0
#: Windows transformed at once (6 MB of complex spectra for 44 channels of 64 samples).
WINDOWS_PER_BATCH = 256


class TaxelDft(Extractor):
    """Real DFT parts of sliding windows; see the module docstring."""

    name: ClassVar[str] = "taxel-dft"
    description: ClassVar[str] = (
        "real DFT parts of 64-sample windows shifted by 8, the lowest bins dropped "
        "(4 from 400 Hz up, else 1)"
    )
    default_events: ClassVar[str] = "none"
    options: ClassVar[tuple[Option, ...]] = (
        Option("window", 64, positive_int, "samples per DFT window"),
        Option("step", 8, positive_int, "samples between windows"),
        Option(
            "drop",
            None,
            non_negative_int,
            "lowest DFT bins dropped (0: keep the DC bin too)",
            at_rate=lambda samplerate: default_drop(samplerate),
            default_text="4 from 400 Hz up (as published), else 1 (DC only)",
        ),
    )

    def __init__(self, **options: object) -> None:
        super().__init__(**options)
        if self.params["drop"] is not None and self.params["drop"] >= self.params["window"] // 2:
            raise FeatureError(
                f"option 'drop' of extractor '{self.name}' ({self.params['drop']}) leaves no "
                f"bin of a {self.params['window']}-sample DFT"
            )

    @property
    def bins(self) -> range:
        drop = self.params["drop"]
        if drop is None:
            raise FeatureError(
                f"extractor '{self.name}': option 'drop' depends on the sample rate; "
                "fill it in first (Extractor.fill_defaults)"
            )
        return range(drop, self.params["window"] // 2)

    def min_samples(self, samplerate: float) -> int:
        return int(self.params["window"])

    def feature_names(self, n_channels: int, channels: Sequence[str] | None = None) -> list[str]:
        return channel_suffixed([f"dft{k}" for k in self.bins], n_channels, channels)

    def extract(self, y: np.ndarray, *, samplerate: float, detection: Detection) -> Instances:
        window, step = self.params["window"], self.params["step"]
        bins = self.bins
        segments, warnings = self._long_enough(y, samplerate=samplerate, detection=detection)
        counts = [
            frame_count(segment.shape[1], frame_length=window, hop_length=step)
            for _, segment in segments
        ]
        # Every window's features written in place, a batch of windows at a time: the
        # complex spectra of all windows at once would be 2.4 times the features.
        values = np.empty((sum(counts), y.shape[0] * len(bins)))
        spans, meta, row = [], [], 0
        for (event, segment), count in zip(segments, counts, strict=True):
            frames = frame(segment, frame_length=window, hop_length=step)
            for first in range(0, count, WINDOWS_PER_BATCH):
                last = min(first + WINDOWS_PER_BATCH, count)
                real = stft(frames[..., first:last], window=None).real[:, bins.start : bins.stop]
                batch = np.moveaxis(real, -1, 0).reshape(last - first, -1)
                values[row + first : row + last] = batch
            row += count
            starts = event.onset + step * np.arange(count)
            spans.append(np.stack([starts, starts + window], axis=1))
            meta += [
                {"channels": list(event.channels), "n_contacts": event.n_contacts}
                for _ in range(count)
            ]
        if not spans:
            return Instances.empty(len(self.feature_names(y.shape[0])), warnings)
        return Instances(
            values=values,
            spans=np.concatenate(spans).astype(np.int64),
            meta=meta,
            warnings=warnings,
        )


def default_drop(samplerate: float) -> int:
    """Bins dropped by default at ``samplerate`` Hz: 4 from :data:`FULL_DROP_RATE` up, else
    1 (the module docstring says why)."""
    return 4 if samplerate >= FULL_DROP_RATE else 1
