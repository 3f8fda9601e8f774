"""The streaming engine: blocks of samples in, instances out, as events end.

One :class:`FeatureStream` serves a recording read block by block (``extract``), a sound
card (``record``'s live display) and a live model (``live``): a streaming detector
(:mod:`features.event_streams`) says where the events are, a bounded history keeps the
samples (and the SNR track) that events still open may need, and the extractor turns each
final event into its instance from that event's stretch of samples alone.  The instances
are those of :func:`features.events.detect_events` followed by
:meth:`~features.extractors.base.Extractor.extract` on the whole recording; memory
follows the longest event (at most ``max_event`` seconds), not the recording.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence

import numpy as np

from touchbench.features._checks import as_signal
from touchbench.features.errors import FeatureError
from touchbench.features.event_streams import EventStream
from touchbench.features.events import Detection, Event
from touchbench.features.extractors.base import Extractor, Instances
from touchbench.features.history import History
from touchbench.features.snr_stream import SnrStream


class FeatureStream:
    """Instances of a stream of blocks, each returned as soon as its event is final.

    Parameters
    ----------
    extractor : Extractor
        What each event becomes.
    events : EventStream
        Where the events are.
    samplerate : float
        Hz.
    n_channels : int
        Channels of every block.
    channels : sequence of str, optional
        The channels' names, which name the features (``t0_pac1``), if they have names.

    Attributes
    ----------
    feature_names : list of str
        Names of the columns of every returned ``Instances.values``.
    position : int
        Samples received.
    """

    def __init__(
        self,
        extractor: Extractor,
        events: EventStream,
        *,
        samplerate: float,
        n_channels: int,
        channels: Sequence[str] | None = None,
    ) -> None:
        extractor.check_input(samplerate=samplerate, n_channels=n_channels)
        self.extractor = extractor
        self.events = events
        self.samplerate = float(samplerate)
        self.n_channels = n_channels
        self.feature_names = extractor.feature_names(n_channels, channels)
        self.samples = History(n_channels)
        self._pending: deque[Event] = deque()
        window = extractor.track_window
        self._own_track = False
        self.track: SnrStream | None = None
        if window is not None:
            if events.track is not None and events.track.window_length == window:
                self.track = events.track
            else:
                self.track = SnrStream(n_channels, samplerate=samplerate, window_length=window)
                self._own_track = True

    @property
    def position(self) -> int:
        return self.samples.stop

    def feed(self, block: np.ndarray) -> Instances:
        """Take the next samples; the instances of the events they completed.

        Parameters
        ----------
        block : ndarray of shape (n_channels, n_samples)
            Finite samples following the previous block.

        Returns
        -------
        Instances
            Spans in samples from the start of the stream; warnings of the events.
        """
        # C order: sums over a window then run in the order of the whole-recording functions.
        block = np.ascontiguousarray(as_signal(block, name="block", min_samples=0))
        if block.ndim != 2 or block.shape[0] != self.n_channels:
            raise FeatureError(
                f"a block must have shape ({self.n_channels}, n_samples), got {block.shape}"
            )
        self.samples.append(block)
        if self._own_track:
            assert self.track is not None
            self.track.feed(block)
        self._pending.extend(self.events.feed(block))
        return self._extract(final=False)

    def finish(self) -> Instances:
        """The end of the stream: the instances of the events still open (none, with a
        warning, for a stream shorter than one analysis window)."""
        window = self.extractor.min_samples(self.samplerate)
        if self.position < window:
            return Instances.empty(
                len(self.feature_names),
                [
                    f"lasts {self.position} samples, shorter than one "
                    f"'{self.extractor.name}' window of {window}; it was left out"
                ],
            )
        if self._own_track:
            assert self.track is not None
            self.track.finish()
        self._pending.extend(self.events.finish())
        return self._extract(final=True)

    def _extract(self, *, final: bool) -> Instances:
        parts = []
        warnings = self.events.take_warnings()
        while self._pending:
            event = self._pending[0]
            start, stop = self.extractor.read_span(event, self.samplerate)
            start = max(start, 0)
            if not final and not self._available(stop):
                break
            self._pending.popleft()
            parts.append(self._instance(event, start, min(stop, self.position)))
        self._forget()
        instances = Instances.concat(parts, len(self.feature_names))
        instances.warnings = warnings + instances.warnings
        return instances

    def _available(self, stop: int) -> bool:
        if stop > self.position:
            return False
        return self.track is None or self.track.n_windows * self.track.window_length >= stop

    def _instance(self, event: Event, start: int, stop: int) -> Instances:
        piece = self.samples.view(start, stop)
        track = None
        if self.track is not None:
            window = self.track.window_length
            assert start % window == 0, "an extractor with a track reads whole windows"
            last = min(math.ceil(stop / window), self.track.n_windows)
            track = self.track.track(start // window, last)
        local = Event(event.onset - start, event.offset - start, event.channels, event.n_contacts)
        detection = Detection(events=(local,), snr=track, origin=start)
        instances = self.extractor.extract(piece, samplerate=self.samplerate, detection=detection)
        instances.spans = instances.spans + start
        return instances

    def _forget(self) -> None:
        """Drop the samples (and track windows) no event can read any more."""
        keep = self.events.earliest_open() - self.extractor.lookback(self.samplerate)
        for event in self._pending:
            keep = min(keep, self.extractor.read_span(event, self.samplerate)[0])
        keep = max(keep, 0)
        if self.track is not None:
            window = self.track.window_length
            keep -= keep % window
            self.track.discard_before(keep // window)
        self.samples.discard_before(keep)
