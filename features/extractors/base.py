"""What every extractor is: named options, sample-rate rules, feature names, extraction."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from collections.abc import Sequence as CollectionSequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from touchbench.features._checks import as_samplerate
from touchbench.features.errors import FeatureError
from touchbench.features.events import Detection, Event
from touchbench.features.options import Option, resolve_options


@dataclass
class Instances:
    """What an extractor made of one recording.

    Parameters
    ----------
    values : ndarray of shape (n_instances, n_features), float64
        Feature values in the order of :meth:`Extractor.feature_names`.
    spans : ndarray of shape (n_instances, 2), int64
        First sample and one past the last sample each instance describes.
    meta : list of dict
        Per-instance details (contacts, channels, frame sequences...), JSON-compatible.
    warnings : list of str
        Events that gave no instance, and why.
    """

    values: np.ndarray
    spans: np.ndarray
    meta: list[dict[str, Any]]
    warnings: list[str] = field(default_factory=list)

    @classmethod
    def empty(cls, n_features: int, warnings: list[str] | None = None) -> Instances:
        return cls(
            values=np.zeros((0, n_features)),
            spans=np.zeros((0, 2), dtype=np.int64),
            meta=[],
            warnings=warnings or [],
        )

    @classmethod
    def concat(cls, parts: list[Instances], n_features: int) -> Instances:
        """``parts`` one after the other (an empty result of ``n_features`` if none; the
        only part with instances itself, not a copy, if there is one)."""
        if not parts:
            return cls.empty(n_features)
        full = [part for part in parts if part.values.shape[0]]
        if len(full) == 1:
            warnings = [text for part in parts for text in part.warnings]
            return cls(full[0].values, full[0].spans, full[0].meta, warnings)
        return cls(
            values=np.concatenate([part.values for part in parts]),
            spans=np.concatenate([part.spans for part in parts]).astype(np.int64),
            meta=[entry for part in parts for entry in part.meta],
            warnings=[text for part in parts for text in part.warnings],
        )


class Extractor(ABC):
    """A named recipe from samples and events to instances.

    Subclasses set the class attributes and implement :meth:`feature_names` and
    :meth:`extract`; ``__init__`` only parses the options.

    Attributes
    ----------
    name : str
        The ``--extractor`` name.
    description : str
        One line for listings.
    default_events : str
        The event kind used when none is asked for (a key of ``EVENT_KINDS``).
    default_segment : float or None
        Segment seconds for events ``none`` when none is asked for (None: whole file).
    options : tuple of Option
        The options it accepts.
    samplerates : tuple of float or None
        The only sample rates it accepts; ``None`` for any within ``min_samplerate``.
    min_samplerate : float
        The lowest sample rate it accepts (Hz).
    min_channels : int
        The fewest channels it needs.
    track_window : int or None
        Window length of the SNR track :meth:`extract` reads from the detection (a
        stream keeps one for it); ``None`` when it needs none.
    """

    name: ClassVar[str]
    description: ClassVar[str]
    default_events: ClassVar[str]
    default_segment: ClassVar[float | None] = None
    options: ClassVar[tuple[Option, ...]] = ()
    samplerates: ClassVar[tuple[float, ...] | None] = None
    min_samplerate: ClassVar[float] = 0.0
    min_channels: ClassVar[int] = 1
    track_window: ClassVar[int | None] = None

    def __init__(self, **options: Any) -> None:
        self.params = resolve_options(type(self).options, options, owner=f"extractor '{self.name}'")

    @classmethod
    def needs_longest(
        cls, options: Mapping[str, Any], *, events: str, segment: float | None
    ) -> bool:
        """Whether :meth:`fill_defaults` needs the longest recording's length (in samples)
        for these resolved options and event kind."""
        return False

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
        """The resolved ``options`` with the defaults that depend on the recordings filled in,
        and one note for each.

        Parameters
        ----------
        options : mapping
            Every option, resolved (``None`` where not set).
        samplerate : float
            The recordings' sample rate (Hz).
        events : str
            The event kind.
        segment : float or None
            Segment seconds for events ``none``.
        longest : int, optional
            Samples in the longest recording, when :meth:`needs_longest` says so.
        """
        filled, notes = dict(options), []
        for spec in cls.options:
            if spec.at_rate is not None and filled.get(spec.name) is None:
                filled[spec.name] = spec.at_rate(samplerate)
                notes.append(
                    f"extractor '{cls.name}': {spec.name}={filled[spec.name]} at "
                    f"{samplerate:g} Hz ({spec.default_text})"
                )
        return filled, notes

    def check_input(self, *, samplerate: float, n_channels: int) -> None:
        """Raise :class:`FeatureError` unless this extractor can use the recording."""
        samplerate = as_samplerate(samplerate)
        allowed = self.samplerates
        if allowed is not None and not any(abs(samplerate - rate) < 1e-6 for rate in allowed):
            rates = ", ".join(f"{rate:g}" for rate in allowed)
            raise FeatureError(
                f"extractor '{self.name}' needs a sample rate of {rates} Hz, got {samplerate:g} Hz"
            )
        if samplerate < self.min_samplerate:
            raise FeatureError(
                f"extractor '{self.name}' needs a sample rate of at least "
                f"{self.min_samplerate:g} Hz, got {samplerate:g} Hz"
            )
        if n_channels < self.min_channels:
            raise FeatureError(
                f"extractor '{self.name}' needs at least {self.min_channels} channels, "
                f"got {n_channels}"
            )

    def read_span(self, event: Event, samplerate: float) -> tuple[int, int]:
        """Samples ``[start, stop)`` that :meth:`extract` reads for ``event`` (``start`` may
        be negative and ``stop`` past the recording: they are clipped)."""
        return event.onset, event.offset

    def lookback(self, samplerate: float) -> int:
        """The most samples before an onset that :meth:`read_span` ever starts."""
        return 0

    @abstractmethod
    def min_samples(self, samplerate: float) -> int:
        """Samples in one analysis window: the shortest recording or event it can use."""

    @abstractmethod
    def feature_names(
        self, n_channels: int, channels: CollectionSequence[str] | None = None
    ) -> list[str]:
        """Attribute names of the features, in order, for ``n_channels`` channels (named
        ``channels`` when the recording names them: ``t0_pac1``, ``pac1[0]``)."""

    def n_features(self, n_channels: int) -> int:
        """How many features :meth:`feature_names` names, without naming them (a window
        padded to a long ``length`` has millions)."""
        return len(self.feature_names(n_channels))

    def sequence_shape(self, n_channels: int) -> tuple[int, int] | None:
        """``(channels, steps)`` when each instance is a sequence (features named by
        :func:`sequence_names`), else None."""
        return None

    @abstractmethod
    def extract(self, y: np.ndarray, *, samplerate: float, detection: Detection) -> Instances:
        """Instances of the events of one recording.

        Parameters
        ----------
        y : ndarray of shape (n_channels, n_samples)
            Finite samples.
        samplerate : float
            Sample rate in Hz (checked by :meth:`check_input`).
        detection : Detection
            The recording's events.
        """

    def _long_enough(
        self, y: np.ndarray, *, samplerate: float, detection: Detection
    ) -> tuple[list[tuple[Event, np.ndarray]], list[str]]:
        """The events at least one analysis window long, with their samples.

        Parameters
        ----------
        y : ndarray of shape (n_channels, n_samples)
            Finite samples.
        samplerate : float
            Sample rate in Hz.
        detection : Detection
            The recording's events.

        Returns
        -------
        segments : list of (Event, ndarray of shape (n_channels, n_event_samples))
            In event order, each event of at least :meth:`min_samples` samples and its
            samples.
        warnings : list of str
            In event order, one :meth:`_too_short` message per event left out.
        """
        segments: list[tuple[Event, np.ndarray]] = []
        warnings: list[str] = []
        for event in detection.events:
            segment = y[:, event.onset : event.offset]
            if segment.shape[1] < self.min_samples(samplerate):
                span = (event.onset + detection.origin, event.offset + detection.origin)
                warnings.append(self._too_short(span, samplerate))
                continue
            segments.append((event, segment))
        return segments, warnings

    def _too_short(self, event_span: tuple[int, int], samplerate: float) -> str:
        start, end = event_span
        return (
            f"event at {start / samplerate:.3f}-{end / samplerate:.3f} s is shorter than one "
            f"'{self.name}' window ({self.min_samples(samplerate)} samples) and was left out"
        )


def channel_suffixed(
    names: list[str], n_channels: int, channels: CollectionSequence[str] | None = None
) -> list[str]:
    """``name_1 ... name_k`` for channel 1, then channel 2, ... (1-based, the UC3M style),
    or ``name_pac1 ...`` with the channels' own names."""
    return [f"{name}_{label}" for label in channel_labels(n_channels, channels) for name in names]


def channel_labels(
    n_channels: int, channels: CollectionSequence[str] | None = None, *, prefix: str = ""
) -> list[str]:
    """The channels' names, or ``PREFIX1 ... PREFIXn`` without them."""
    if channels:
        if len(channels) != n_channels:
            raise FeatureError(f"{len(channels)} channel names given for {n_channels} channels")
        return list(channels)
    return [f"{prefix}{channel}" for channel in range(1, n_channels + 1)]


def sequence_names(channels: list[str], length: int) -> list[str]:
    """Names of a sequence instance's columns: ``channel[0] ... channel[length-1]`` for
    each channel in turn, the layout ``benchmark.sequence`` reads back."""
    return [f"{channel}[{step}]" for channel in channels for step in range(length)]
