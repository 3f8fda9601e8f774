"""``sequence``: each event kept whole, as a multichannel window for time-series models.

Every event becomes one instance of ``n_channels x length`` values, stored as the columns
``ch1[0] ... ch1[length-1]``, then ``ch2[0] ...`` (the layout ``benchmark.sequence``
reads back, so the window's shape travels with its columns):

* by default, the ``length`` samples (default 256) from the event's onset, whatever the
  event's length, as ``window`` takes them; an event too close to the end of the
  recording is left out with a warning, or with ``pad=true`` padded with its last
  sample;
* with ``resample=true``, the event from its onset to its offset, brought to ``length``
  steps (:func:`features.resample.to_length`: averaged down, interpolated up).

With events ``none`` (each recording, or each segment, is one event) the defaults take
the whole of it: ``length`` is the segment's samples, or without segments the longest
recording's, and ``pad`` is true, so each recording is cut or padded to ``length``
(:meth:`Sequence.fill_defaults` says so in a note).

With ``baseline=B`` (default 0: nothing subtracted), every channel's mean over the ``B``
samples before the onset is subtracted from its window, as ``window`` does.
"""

from __future__ import annotations

from collections.abc import Mapping
from collections.abc import Sequence as CollectionSequence
from typing import Any, ClassVar

import numpy as np

from touchbench.features.errors import FeatureError
from touchbench.features.events import Detection, Event
from touchbench.features.extractors.base import Instances, channel_labels, sequence_names
from touchbench.features.extractors.window import Window, baselines
from touchbench.features.options import Option, flag, non_negative_int, positive_int
from touchbench.features.resample import to_length

#: Steps per channel when events are detected and no length is given.
DEFAULT_LENGTH = 256


class Sequence(Window):
    """Each event's window, channels x steps; see the module docstring."""

    name: ClassVar[str] = "sequence"
    description: ClassVar[str] = (
        "each event as channels x N samples (from the onset, or resampled), for time-series models"
    )
    default_events: ClassVar[str] = "dbscan"
    options: ClassVar[tuple[Option, ...]] = (
        Option(
            "length",
            None,
            positive_int,
            "steps per channel",
            default_text=f"{DEFAULT_LENGTH}; events none: the segment, or the longest recording",
        ),
        Option("baseline", 0, non_negative_int, "samples before the onset averaged as baseline"),
        Option("resample", False, flag, "bring the whole event to 'length' steps"),
        Option(
            "pad",
            None,
            flag,
            "pad an event shorter than 'length' with its last sample (else leave it out)",
            default_text="true with events none, else false",
        ),
    )

    @classmethod
    def needs_longest(
        cls, options: Mapping[str, Any], *, events: str, segment: float | None
    ) -> bool:
        return events == "none" and segment is None and options.get("length") is None

    @classmethod
    def fill_defaults(
        cls,
        options: Mapping[str, Any],
        *,
        samplerate: float,
        events: str,
        segment: float | None,
        longest: int | None = None,
    ) -> tuple[dict[str, Any], list[str]]:
        filled, notes = super().fill_defaults(
            options, samplerate=samplerate, events=events, segment=segment, longest=longest
        )
        whole = events == "none"
        if filled.get("pad") is None:
            filled["pad"] = whole
        if filled.get("length") is not None:
            if whole and segment is None and not filled["resample"]:
                notes.append(
                    f"extractor '{cls.name}': each recording is cut or padded to "
                    f"length={filled['length']} samples"
                )
            return filled, notes
        if not whole:
            filled["length"] = DEFAULT_LENGTH
        elif segment is not None:
            filled["length"] = max(1, round(segment * samplerate))
        elif longest is None:
            raise FeatureError(
                f"extractor '{cls.name}' with events 'none' needs a length (the longest "
                "recording's, or a given one)"
            )
        else:
            filled["length"] = longest
            notes.append(
                f"extractor '{cls.name}': length={longest} samples "
                f"({longest / samplerate:g} s), the longest recording; shorter ones are "
                "padded with their last sample"
            )
        return filled, notes

    @property
    def resampled(self) -> bool:
        return bool(self.params["resample"])

    def pads(self) -> bool:
        return bool(self.params["pad"])

    def min_samples(self, samplerate: float) -> int:
        return 1 if self.resampled or self.pads() else int(self.params["length"])

    def read_span(self, event: Event, samplerate: float) -> tuple[int, int]:
        if not self.resampled:
            return super().read_span(event, samplerate)
        return event.onset - self.params["baseline"], event.offset

    def feature_names(
        self, n_channels: int, channels: CollectionSequence[str] | None = None
    ) -> list[str]:
        if self.params["length"] is None:
            raise FeatureError(
                f"extractor '{self.name}': option 'length' depends on the recordings; "
                "fill it in first (Extractor.fill_defaults)"
            )
        labels = channel_labels(n_channels, channels, prefix="ch")
        return sequence_names(labels, self.params["length"])

    def sequence_shape(self, n_channels: int) -> tuple[int, int] | None:
        return n_channels, int(self.params["length"])

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
