"""``mfcc``: mel-frequency cepstral coefficients, summarised per instance or kept as frames.

Per channel: 30 ms frames with a 10 ms hop (98 frames in 1 s, not centred), periodic
Hann window, power spectrum with ``n_fft`` = the frame length, 40 HTK-mel filters of
unit area from 0 Hz to Nyquist, 14 coefficients (:mod:`features.mel`).  The instance's
features are the mean and the standard deviation (population, ``ddof=0``) of each
coefficient over its frames: ``mfcc1_mean_1 ... mfcc14_mean_1, mfcc1_std_1 ...`` for
channel 1, then channel 2, ....  The frame sequence, shape (n_frames, n_mfcc *
n_channels) in the same channel order, is kept in the instance's metadata under
``"frames"``.

With ``frames=N``, the instance keeps the coefficients frame by frame instead of their
summary, as a sequence for time-series models: each coefficient's track is brought to
``N`` steps (:func:`features.resample.to_length`) and stored as the columns
``mfcc1_1[0] ... mfcc1_1[N-1], mfcc2_1[0] ...`` (coefficient q of channel c is the
sequence channel ``mfccq_c``), the layout ``benchmark.sequence`` reads back.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from touchbench.features.events import Detection
from touchbench.features.extractors.base import (
    Extractor,
    Instances,
    channel_labels,
    channel_suffixed,
    sequence_names,
)
from touchbench.features.framing import frame, power_spectrogram
from touchbench.features.mel import mel_filter_bank, mel_spectrogram, mfcc
from touchbench.features.options import Option, positive_float, positive_int
from touchbench.features.resample import to_length


class Mfcc(Extractor):
    """MFCC mean and standard deviation per coefficient; see the module docstring."""

    name: ClassVar[str] = "mfcc"
    description: ClassVar[str] = (
        "14 MFCCs (40 mel filters, 30 ms / 10 ms): mean and std, or N frames (frames=N)"
    )
    default_events: ClassVar[str] = "none"
    min_samplerate: ClassVar[float] = 2000.0
    options: ClassVar[tuple[Option, ...]] = (
        Option("n_mfcc", 14, positive_int, "coefficients"),
        Option("n_mels", 40, positive_int, "mel filters"),
        Option("frame", 0.030, positive_float, "frame length in seconds"),
        Option("hop", 0.010, positive_float, "hop in seconds"),
        Option("frames", None, positive_int, "keep N frames as a sequence, not mean and std"),
    )

    def frame_length(self, samplerate: float) -> int:
        return max(1, round(self.params["frame"] * samplerate))

    def hop_length(self, samplerate: float) -> int:
        return max(1, round(self.params["hop"] * samplerate))

    def min_samples(self, samplerate: float) -> int:
        return self.frame_length(samplerate)

    def feature_names(self, n_channels: int, channels: Sequence[str] | None = None) -> list[str]:
        count = self.params["n_mfcc"]
        if self.params["frames"] is not None:
            tracks = [
                f"mfcc{q}_{label}"
                for label in channel_labels(n_channels, channels)
                for q in range(1, count + 1)
            ]
            return sequence_names(tracks, self.params["frames"])
        names = [f"mfcc{q}_mean" for q in range(1, count + 1)]
        names += [f"mfcc{q}_std" for q in range(1, count + 1)]
        return channel_suffixed(names, n_channels, channels)

    def sequence_shape(self, n_channels: int) -> tuple[int, int] | None:
        if self.params["frames"] is None:
            return None
        return n_channels * int(self.params["n_mfcc"]), int(self.params["frames"])

    def extract(self, y: np.ndarray, *, samplerate: float, detection: Detection) -> Instances:
        n_channels = y.shape[0]
        frame_length, hop_length = self.frame_length(samplerate), self.hop_length(samplerate)
        filters = mel_filter_bank(
            samplerate=samplerate, n_fft=frame_length, n_mels=self.params["n_mels"]
        )
        rows, spans = [], []
        meta: list[dict[str, Any]] = []
        segments, warnings = self._long_enough(y, samplerate=samplerate, detection=detection)
        for event, segment in segments:
            frames = frame(segment, frame_length=frame_length, hop_length=hop_length)
            power = power_spectrogram(frames, window="hann")
            coefficients = mfcc(
                mel_spectrogram(power, filter_bank=filters), n_mfcc=self.params["n_mfcc"]
            )
            spans.append((event.onset, event.offset))
            if self.params["frames"] is not None:
                rows.append(to_length(coefficients, self.params["frames"]).reshape(-1))
                meta.append({"channels": list(event.channels), "n_contacts": event.n_contacts})
                continue
            summary = np.concatenate(
                [coefficients.mean(axis=-1), coefficients.std(axis=-1)], axis=-1
            )
            rows.append(summary.reshape(-1))
            sequence = np.moveaxis(coefficients, -1, 0).reshape(coefficients.shape[-1], -1)
            meta.append(
                {
                    "channels": list(event.channels),
                    "n_contacts": event.n_contacts,
                    "frames": sequence.tolist(),
                    "frame_hop": hop_length / samplerate,
                }
            )
        if not rows:
            return Instances.empty(len(self.feature_names(n_channels)), warnings)
        return Instances(
            values=np.array(rows),
            spans=np.array(spans, dtype=np.int64),
            meta=meta,
            warnings=warnings,
        )
