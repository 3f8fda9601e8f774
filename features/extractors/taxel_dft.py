"""``taxel-dft``: DFT features of tactile arrays (sliding vs. slipping), one per window.

Every event (by default the whole recording) is cut into 64-sample windows shifted by
8 samples; each window is one instance.  Per channel, the DFT of the window
(rectangular, unscaled: ``X[k] = sum_n x[n] exp(-2 pi i k n / 64)``) has its bins 0 to
31; the 4 lowest (DC to 3 samplerate/64, about a 50 Hz high-pass at 800 Hz) are
dropped and the real parts of bins 4 to 31 are the 28 features ``dft4_1 ... dft31_1``,
then channel 2, ....
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from features.errors import FeatureError
from features.events import Detection
from features.extractors.base import Extractor, Instances, channel_suffixed
from features.framing import frame, stft
from features.options import Option, positive_int


class TaxelDft(Extractor):
    """Real DFT parts of sliding windows; see the module docstring."""

    name: ClassVar[str] = "taxel-dft"
    description: ClassVar[str] = (
        "real DFT parts of 64-sample windows shifted by 8, 4 lowest bins dropped"
    )
    default_events: ClassVar[str] = "none"
    options: ClassVar[tuple[Option, ...]] = (
        Option("window", 64, positive_int, "samples per DFT window"),
        Option("step", 8, positive_int, "samples between windows"),
        Option("drop", 4, positive_int, "lowest bins dropped"),
    )

    def __init__(self, **options: object) -> None:
        super().__init__(**options)
        if self.params["drop"] >= self.params["window"] // 2:
            raise FeatureError(
                f"option 'drop' of extractor '{self.name}' ({self.params['drop']}) leaves no "
                f"bin of a {self.params['window']}-sample DFT"
            )

    @property
    def bins(self) -> range:
        return range(self.params["drop"], self.params["window"] // 2)

    def min_samples(self, samplerate: float) -> int:
        return int(self.params["window"])

    def feature_names(self, n_channels: int, channels: Sequence[str] | None = None) -> list[str]:
        return channel_suffixed([f"dft{k}" for k in self.bins], n_channels, channels)

    def extract(self, y: np.ndarray, *, samplerate: float, detection: Detection) -> Instances:
        window, step = self.params["window"], self.params["step"]
        bins = self.bins
        blocks, spans, meta = [], [], []
        segments, warnings = self._long_enough(y, samplerate=samplerate, detection=detection)
        for event, segment in segments:
            spectrum = stft(frame(segment, frame_length=window, hop_length=step), window=None)
            real = spectrum.real[:, bins.start : bins.stop, :]
            blocks.append(np.moveaxis(real, -1, 0).reshape(real.shape[-1], -1))
            starts = event.onset + step * np.arange(real.shape[-1])
            spans.append(np.stack([starts, starts + window], axis=1))
            meta += [
                {"channels": list(event.channels), "n_contacts": event.n_contacts}
            ] * real.shape[-1]
        if not blocks:
            return Instances.empty(len(self.feature_names(y.shape[0])), warnings)
        return Instances(
            values=np.concatenate(blocks),
            spans=np.concatenate(spans).astype(np.int64),
            meta=[dict(entry) for entry in meta],
            warnings=warnings,
        )
