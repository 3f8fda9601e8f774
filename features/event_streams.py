"""Event detection block by block: the detectors of :mod:`features.events`, streaming.

Each stream takes consecutive blocks of shape (n_channels, n) and returns the events
that are final, in time order, with the same onsets, offsets, channels and contact
counts as the whole-recording detector (:func:`features.events.detect_events`).  An
event is never longer than ``max_event`` seconds: a longer one is cut there, with a
warning, and what follows is the next event, so that memory stays bounded on a
recording that never goes quiet.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.signal import sosfilt, sosfilt_zi

from touchbench.features._checks import as_samplerate
from touchbench.features.errors import FeatureError
from touchbench.features.events import EVENT_KINDS, Event, dbscan_events, dbscan_filter, runs
from touchbench.features.options import resolve_options
from touchbench.features.snr import Touch
from touchbench.features.snr_stream import SnrStream

#: Longest event in seconds unless asked otherwise.
DEFAULT_MAX_EVENT = 60.0


class EventStream(ABC):
    """A detector fed block by block.

    Attributes
    ----------
    position : int
        Samples received.
    track : SnrStream or None
        The SNR track the detector keeps, when it keeps one.
    """

    track: SnrStream | None = None

    def __init__(self, n_channels: int, *, samplerate: float, max_event: float) -> None:
        self.n_channels = n_channels
        self.samplerate = as_samplerate(samplerate)
        if not (isinstance(max_event, int | float) and math.isfinite(max_event)) or max_event <= 0:
            raise FeatureError(f"max_event must be a positive number of seconds, got {max_event}")
        self.max_samples = max(1, round(max_event * self.samplerate))
        self.position = 0
        self._warnings: list[str] = []

    def feed(self, block: np.ndarray) -> list[Event]:
        """The events that became final with ``block`` (n_channels, n)."""
        block = np.ascontiguousarray(block, dtype=np.float64)
        self.position += block.shape[1]
        return self._feed(block)

    @abstractmethod
    def _feed(self, block: np.ndarray) -> list[Event]: ...

    @abstractmethod
    def finish(self) -> list[Event]:
        """The events left at the end of the stream."""

    @abstractmethod
    def earliest_open(self) -> int:
        """The first sample an event not yet returned can start at."""

    def take_warnings(self) -> list[str]:
        """Warnings since the last call (cut events, left-out remainders)."""
        warnings, self._warnings = self._warnings, []
        return warnings

    def _cut_warning(self, onset: int) -> None:
        self._warnings.append(
            f"event at {onset / self.samplerate:.3f} s lasted longer than max_event "
            f"({self.max_samples / self.samplerate:g} s) and was cut there"
        )


class SnrEvents(EventStream):
    """:func:`features.events.detect_snr`, streaming."""

    def __init__(
        self,
        n_channels: int,
        *,
        samplerate: float,
        max_event: float = DEFAULT_MAX_EVENT,
        window_length: int = 256,
        threshold: float = 10.0,
        hangover: float = 0.5,
        smoothing: float = 0.05,
        initial: float = 0.1,
        noise_min: float = 1e-5,
        contact_gap: float = 0.05,
    ) -> None:
        super().__init__(n_channels, samplerate=samplerate, max_event=max_event)
        self.track = SnrStream(
            n_channels,
            samplerate=samplerate,
            window_length=window_length,
            threshold=threshold,
            hangover=hangover,
            smoothing=smoothing,
            initial=initial,
            noise_min=noise_min,
        )
        self._gap_windows = int(contact_gap * self.samplerate / self.track.window_length)
        self._max_windows = max(1, self.max_samples // self.track.window_length)
        self._ended: list[Touch] = []
        self._cut = 0  # windows before this belong to events already returned

    def _feed(self, block: np.ndarray) -> list[Event]:
        assert self.track is not None
        self._ended += self.track.feed(block)
        return self._events()

    def finish(self) -> list[Event]:
        assert self.track is not None
        self._ended += self.track.finish()
        return self._events()

    def earliest_open(self) -> int:
        assert self.track is not None
        starts = [t.first_window for t in self._ended]
        starts += [onset for _, onset in self.track.open_onsets()]
        first = min(starts) if starts else self.track.n_windows
        return max(first, self._cut) * self.track.window_length

    def _events(self) -> list[Event]:
        """Merge ended touches into events as in the whole-recording detector; an event is
        final once no touch still going on overlaps it, or once it reaches max_event."""
        assert self.track is not None
        events: list[Event] = []
        while True:
            cut = self._cut
            self._ended.sort(key=lambda t: (max(t.first_window, cut), t.channel))
            opens = [max(onset, cut) for _, onset in self.track.open_onsets()]
            if not self._ended and not opens:
                return events
            complete, starts = False, list(opens)
            if self._ended:
                first = max(self._ended[0].first_window, cut)
                last = first - 1
                for touch in self._ended:
                    if max(touch.first_window, cut) > last >= first:
                        break
                    last = max(last, touch.last_window)
                complete = not any(onset <= last for onset in opens)
                starts.append(first)
            if not complete:
                first, last = min(starts), self.track.n_windows - 1
            if last - first + 1 > self._max_windows:
                last = first + self._max_windows - 1
                self._cut_warning(first * self.track.window_length)
            elif not complete:
                return events
            events.append(self._event(first, last))
            self._cut = last + 1
            self._ended = [t for t in self._ended if t.last_window >= self._cut]

    def _event(self, first: int, last: int) -> Event:
        """The event of windows ``[first, last]``: its channels and contacts."""
        assert self.track is not None
        spans = [(t.channel, t.first_window, t.last_window) for t in self.track.touches]
        spans += [(c, onset, self.track.n_windows - 1) for c, onset in self.track.open_onsets()]
        channels = sorted({c for c, begin, end in spans if begin <= last and end >= first})
        level = self.track.level.view(first, last + 1)
        noise = self.track.noise.view(first, last + 1)
        active = np.flatnonzero((level / noise > self.track.threshold).any(axis=0))
        contacts = 1 + int(np.count_nonzero(np.diff(active) > self._gap_windows + 1))
        window = self.track.window_length
        return Event(first * window, (last + 1) * window, tuple(channels), contacts)


class NoneEvents(EventStream):
    """:func:`features.events.detect_none`, streaming: segments, or the whole stream."""

    def __init__(
        self,
        n_channels: int,
        *,
        samplerate: float,
        max_event: float = DEFAULT_MAX_EVENT,
        segment: float | None = None,
    ) -> None:
        super().__init__(n_channels, samplerate=samplerate, max_event=max_event)
        self.segment = segment
        if segment is None:
            self.length = self.max_samples
        else:
            self.length = round(segment * self.samplerate)
            if segment <= 0 or self.length < 1:
                raise FeatureError(f"segment must be a positive number of seconds, got {segment}")
            if self.length > self.max_samples:
                raise FeatureError(
                    f"segment ({segment:g} s) is longer than max_event "
                    f"({self.max_samples / self.samplerate:g} s); raise max_event"
                )
        self._next = 0  # onset of the next event

    def _feed(self, block: np.ndarray) -> list[Event]:
        events = []
        while self.position - self._next >= self.length and (
            self.segment is not None or self.position > self._next + self.length
        ):
            events.append(self._take(self._next + self.length))
            if self.segment is None:
                self._cut_warning(events[-1].onset)
        return events

    def finish(self) -> list[Event]:
        channels = tuple(range(self.n_channels))
        if self.segment is None:
            if self.position > self._next or self._next == 0:
                return [Event(self._next, self.position, channels)]
            return []
        if self._next == 0:
            raise FeatureError(
                f"the recording lasts {self.position / self.samplerate:g} s, shorter than one "
                f"segment of {self.segment:g} s"
            )
        if self.position > self._next:
            self._warnings.append(
                f"the last {(self.position - self._next) / self.samplerate:g} s are shorter "
                "than a segment and were left out"
            )
        return []

    def earliest_open(self) -> int:
        return self._next

    def _take(self, offset: int) -> Event:
        event = Event(self._next, offset, tuple(range(self.n_channels)))
        self._next = offset
        return event


class DbscanEvents(EventStream):
    """:func:`features.events.detect_dbscan`, streaming.

    The high-pass filter carries its state from block to block; the robust scale of
    each channel is that of its first ``initial`` seconds; a group of detections is
    clustered once no later detection can reach it (``eps`` seconds of quiet).
    """

    def __init__(
        self,
        n_channels: int,
        *,
        samplerate: float,
        max_event: float = DEFAULT_MAX_EVENT,
        cutoff: float = 1.0,
        threshold: float = 5.0,
        eps: float = 0.1,
        min_samples: int = 3,
        initial: float = 1.0,
    ) -> None:
        super().__init__(n_channels, samplerate=samplerate, max_event=max_event)
        self.sos = dbscan_filter(self.samplerate, cutoff)
        self.threshold = threshold
        self.radius = eps * self.samplerate
        self.min_samples = min_samples
        self.initial_samples = max(1, round(initial * self.samplerate))
        self._state: np.ndarray | None = None
        self._scale: np.ndarray | None = None
        self._waiting: list[np.ndarray] = []  # filtered samples before the scale is known
        self._filtered_until = 0  # samples whose threshold test is done
        self._open = np.full(n_channels, -1, dtype=np.int64)  # start of a run still going on
        self._runs: list[tuple[int, int, int]] = []  # (channel, start, stop) not clustered

    def _feed(self, block: np.ndarray) -> list[Event]:
        if self._state is None:
            self._state = sosfilt_zi(self.sos)[:, np.newaxis, :] * block[np.newaxis, :, :1]
        filtered, self._state = sosfilt(self.sos, block, axis=-1, zi=self._state)
        if self._scale is None:
            self._waiting.append(filtered)
            if sum(part.shape[1] for part in self._waiting) < self.initial_samples:
                return []
            filtered = self._start_scale()
        return self._detect(filtered, final=False)

    def finish(self) -> list[Event]:
        events = []
        if self._scale is None and self._waiting:
            events += self._detect(self._start_scale(), final=False)
        return events + self._detect(np.zeros((self.n_channels, 0)), final=True)

    def earliest_open(self) -> int:
        starts = [start for _, start, _ in self._runs]
        starts += [int(s) for s in self._open if s >= 0]
        return min(starts) if starts else self._filtered_until

    def _start_scale(self) -> np.ndarray:
        filtered = np.concatenate(self._waiting, axis=1)
        self._waiting = []
        head = filtered[:, : self.initial_samples]
        self._scale = np.median(np.abs(head), axis=-1) / 0.6745
        return filtered

    def _detect(self, filtered: np.ndarray, *, final: bool) -> list[Event]:
        assert self._scale is not None or filtered.size == 0
        origin = self._filtered_until
        if filtered.shape[1]:
            assert self._scale is not None
            limit = self.threshold * np.maximum(self._scale, np.finfo(float).tiny)
            above = np.abs(filtered) > limit[:, np.newaxis]
            carried = self._open >= 0
            above_padded = np.concatenate([carried[:, np.newaxis], above], axis=1)
            channel, start, stop = runs(above_padded)
            start = np.where(start == 0, self._open[channel] - origin + 1, start)
            self._open[:] = -1
            for c, begin, end in zip(channel, start + origin - 1, stop + origin - 1, strict=True):
                if end == origin + filtered.shape[1] and not final:
                    self._open[c] = begin
                else:
                    self._runs.append((int(c), int(begin), int(end)))
        self._filtered_until = origin + filtered.shape[1]
        if final:
            for c in np.flatnonzero(self._open >= 0):
                self._runs.append((int(c), int(self._open[c]), self._filtered_until))
            self._open[:] = -1
        return self._cluster(final=final)

    def _cluster(self, *, final: bool) -> list[Event]:
        """Cluster the runs no later detection can reach; cut a group at max_event."""
        events: list[Event] = []
        while True:
            open_channels = np.flatnonzero(self._open >= 0)
            starts = [begin for _, begin, _ in self._runs]
            starts += [int(self._open[c]) for c in open_channels]
            if not starts:
                return events
            cut = min(starts) + self.max_samples
            if cut < self._filtered_until:
                self._cut_warning(min(starts))
                events += self._flush_before(cut)
                continue
            if not final:
                last_stop = max((end for _, _, end in self._runs), default=self._filtered_until)
                reachable = self._filtered_until - (last_stop - 1) <= self.radius
                if open_channels.size or reachable:
                    return events
            return events + self._flush_before(self._filtered_until + 1)

    def _flush_before(self, cut: int) -> list[Event]:
        """Cluster the runs (or their parts) before sample ``cut``; the rest goes on."""
        found, kept = [], []
        for channel, begin, end in self._runs:
            if begin >= cut:
                kept.append((channel, begin, end))
                continue
            found.append((channel, begin, min(end, cut)))
            if end > cut:
                kept.append((channel, cut, end))
        for going in np.flatnonzero(self._open >= 0):
            if self._open[going] < cut:
                found.append((int(going), int(self._open[going]), cut))
                self._open[going] = cut
        self._runs = kept
        ordered = sorted(found)  # by channel, then start: the whole-recording order
        return dbscan_events(
            np.array([r[0] for r in ordered], dtype=np.int64),
            np.array([r[1] for r in ordered], dtype=np.int64),
            np.array([r[2] for r in ordered], dtype=np.int64),
            radius=self.radius,
            min_samples=self.min_samples,
        )


_STREAMS: dict[str, type[EventStream]] = {
    "snr": SnrEvents,
    "dbscan": DbscanEvents,
    "none": NoneEvents,
}


def open_event_stream(
    kind: str,
    n_channels: int,
    *,
    samplerate: float,
    segment: float | None = None,
    options: Mapping[str, Any] | None = None,
    max_event: float = DEFAULT_MAX_EVENT,
) -> EventStream:
    """The streaming detector called ``kind`` with ``options`` (see :data:`EVENT_KINDS`)."""
    if kind not in EVENT_KINDS:
        raise FeatureError(f"unknown event detection '{kind}' (known: {', '.join(EVENT_KINDS)})")
    parsed = resolve_options(EVENT_KINDS[kind].options, options or {}, owner=f"events '{kind}'")
    if kind == "none":
        return NoneEvents(n_channels, samplerate=samplerate, max_event=max_event, segment=segment)
    if segment is not None:
        raise FeatureError(f"a segment length only applies to events 'none', not '{kind}'")
    return _STREAMS[kind](n_channels, samplerate=samplerate, max_event=max_event, **parsed)
