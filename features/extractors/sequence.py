"""``sequence``: each event kept whole, as a multichannel window for time-series models.

Every event becomes one instance of ``n_channels x length`` values, stored as the columns
``ch1[0] ... ch1[length-1]``, then ``ch2[0] ...`` (the layout ``benchmark.sequence``
reads back, so the window's shape travels with its columns):

* by default, the ``length`` samples (default 256) from the event's onset, whatever the
  event's length, as ``window`` takes them; an event too close to the end of the
  recording is left out with a warning;
* with ``resample=true``, the event from its onset to its offset, brought to ``length``
  steps (:func:`features.resample.to_length`: averaged down, interpolated up).

With ``baseline=B`` (default 0: nothing subtracted), every channel's mean over the ``B``
samples before the onset is subtracted from its window, as ``window`` does.
"""

from __future__ import annotations

from collections.abc import Sequence as CollectionSequence
from typing import ClassVar

import numpy as np

from features.events import Detection, Event
from features.extractors.base import Instances, channel_labels, sequence_names
from features.extractors.window import Window, baselines
from features.options import Option, flag, non_negative_int, positive_int
from features.resample import to_length


class Sequence(Window):
    """Each event's window, channels x steps; see the module docstring."""

    name: ClassVar[str] = "sequence"
    description: ClassVar[str] = (
        "each event as channels x N samples (from the onset, or resampled), for time-series models"
    )
    default_events: ClassVar[str] = "dbscan"
    options: ClassVar[tuple[Option, ...]] = (
        Option("length", 256, positive_int, "steps per channel"),
        Option("baseline", 0, non_negative_int, "samples before the onset averaged as baseline"),
        Option("resample", False, flag, "bring the whole event to 'length' steps"),
    )

    @property
    def resampled(self) -> bool:
        return bool(self.params["resample"])

    def min_samples(self, samplerate: float) -> int:
        return 1 if self.resampled else int(self.params["length"])

    def read_span(self, event: Event, samplerate: float) -> tuple[int, int]:
        if not self.resampled:
            return super().read_span(event, samplerate)
        return event.onset - self.params["baseline"], event.offset

    def feature_names(
        self, n_channels: int, channels: CollectionSequence[str] | None = None
    ) -> list[str]:
        labels = channel_labels(n_channels, channels, prefix="ch")
        return sequence_names(labels, self.params["length"])

    def extract(self, y: np.ndarray, *, samplerate: float, detection: Detection) -> Instances:
        if not self.resampled:
            return super().extract(y, samplerate=samplerate, detection=detection)
        length, baseline = self.params["length"], self.params["baseline"]
        segments, warnings = self._long_enough(y, samplerate=samplerate, detection=detection)
        if not segments:
            return Instances.empty(len(self.feature_names(y.shape[0])), warnings)
        onsets = np.array([event.onset for event, _ in segments], dtype=np.int64)
        windows = np.stack([to_length(segment, length) for _, segment in segments])
        windows -= np.moveaxis(baselines(y, onsets, baseline), 0, 1)[:, :, np.newaxis]
        return Instances(
            values=windows.reshape(len(segments), -1),
            spans=np.array([(e.onset, e.offset) for e, _ in segments], dtype=np.int64),
            meta=[{"channels": list(e.channels), "n_contacts": e.n_contacts} for e, _ in segments],
            warnings=warnings,
        )
