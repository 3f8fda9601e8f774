"""``window``: raw values after a contact onset (BioTac-style events).

For every event, every channel's ``length`` samples (default 25) from the onset, minus
the mean of the ``baseline`` samples (default 3) just before the onset:
``t0_1 ... t24_1`` for channel 1, then channel 2, ....  An onset with fewer samples
before it uses those there are, and an onset at sample 0 is its own baseline.  An event
too close to the end of the recording for ``length`` samples is left out with a
warning.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from touchbench.features.events import Detection, Event
from touchbench.features.extractors.base import Extractor, Instances, channel_suffixed
from touchbench.features.options import Option, positive_int


class Window(Extractor):
    """Baseline-subtracted samples after each onset; see the module docstring."""

    name: ClassVar[str] = "window"
    description: ClassVar[str] = "raw values of N samples from the onset minus the baseline"
    default_events: ClassVar[str] = "dbscan"
    options: ClassVar[tuple[Option, ...]] = (
        Option("length", 25, positive_int, "samples from the onset"),
        Option("baseline", 3, positive_int, "samples before the onset averaged as baseline"),
    )

    def min_samples(self, samplerate: float) -> int:
        return int(self.params["length"])

    def read_span(self, event: Event, samplerate: float) -> tuple[int, int]:
        onset = event.onset
        return onset - self.params["baseline"], max(event.offset, onset + self.params["length"])

    def lookback(self, samplerate: float) -> int:
        return int(self.params["baseline"])

    def feature_names(self, n_channels: int, channels: Sequence[str] | None = None) -> list[str]:
        names = [f"t{i}" for i in range(self.params["length"])]
        return channel_suffixed(names, n_channels, channels)

    def n_features(self, n_channels: int) -> int:
        if self.params["length"] is None:  # a sequence's, not filled in yet: say so
            return super().n_features(n_channels)
        return n_channels * int(self.params["length"])

    def pads(self) -> bool:
        """Whether an event too close to the end is padded with the last sample (else it
        is left out)."""
        return False

    def extract(self, y: np.ndarray, *, samplerate: float, detection: Detection) -> Instances:
        length, baseline = self.params["length"], self.params["baseline"]
        n_samples = y.shape[1]
        onsets = np.array([event.onset for event in detection.events], dtype=np.int64)
        fits = onsets + length <= n_samples
        if self.pads():
            fits = onsets < n_samples
        warnings = [
            f"event at {(onset + detection.origin) / samplerate:.3f} s leaves fewer than "
            f"{length} samples before the end of the recording and was left out"
            for onset in onsets[~fits]
        ]
        onsets = onsets[fits]
        kept = [event for event, ok in zip(detection.events, fits, strict=True) if ok]
        if onsets.size == 0:
            return Instances.empty(len(self.feature_names(y.shape[0])), warnings)
        # Indices past the end repeat the last sample: the padding of pads().
        after = y[:, np.minimum(onsets[:, np.newaxis] + np.arange(length), n_samples - 1)]
        reference = baselines(y, onsets, baseline)
        values = after - reference[:, :, np.newaxis]
        return Instances(
            values=np.moveaxis(values, 0, 1).reshape(onsets.size, -1),
            spans=np.stack([onsets, np.minimum(onsets + length, n_samples)], axis=1),
            meta=[{"channels": list(e.channels), "n_contacts": e.n_contacts} for e in kept],
            warnings=warnings,
        )


def baselines(y: np.ndarray, onsets: np.ndarray, baseline: int) -> np.ndarray:
    """Mean of up to ``baseline`` samples before each onset, shape (n_channels, n_onsets).

    An onset with fewer samples before it uses those there are, an onset at sample 0 is
    its own baseline, and ``baseline`` 0 gives zeros (nothing to subtract).
    """
    if baseline == 0:
        return np.zeros((y.shape[0], onsets.size))
    before = onsets[:, np.newaxis] - baseline + np.arange(baseline)
    there = before >= 0
    values = np.where(there, y[:, np.maximum(before, 0)], 0.0)
    counts = there.sum(axis=1)
    means = values.sum(axis=-1) / np.maximum(counts, 1)
    at_start = counts == 0
    means[:, at_start] = y[:, onsets[at_start]]
    return means
