"""The SNR tracker of :mod:`features.snr`, fed block by block.

:class:`SnrStream` gives the same levels, noise floors and touches as
:func:`features.snr.snr_track` on the whole recording, whatever the block sizes, while
keeping only the windows the caller still needs (:meth:`SnrStream.discard_before`).
A window's noise floor is known as soon as the window is complete; a touch is known
when its hangover has passed (or the stream ends).  The first floor is the median
level of the first ``initial`` seconds, so nothing is decided before those windows
have arrived.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from touchbench.features._checks import as_positive_int, as_samplerate
from touchbench.features.framing import frame
from touchbench.features.history import History
from touchbench.features.snr import SnrTrack, Touch, follow_floor, tracking_windows
from touchbench.features.temporal import rms


@dataclass
class _ChannelState:
    """One channel's floor and, during a touch, its onset, limit and last loud window."""

    floor: float
    onset: int | None = None
    limit: float = 0.0
    last_loud: int = 0


class SnrStream:
    """Incremental :func:`~features.snr.snr_track` over blocks of (n_channels, n) samples.

    Parameters
    ----------
    n_channels : int
        Channels of every block.
    samplerate, window_length, threshold, hangover, smoothing, initial, noise_min
        As :func:`features.snr.snr_track`.

    Attributes
    ----------
    n_windows : int
        Windows decided so far (level and noise floor known).
    level, noise : History
        Per-window RMS and noise floor, shape (n_channels, windows kept).
    touches : list of Touch
        Ended touches not yet discarded, in the order they ended.
    """

    def __init__(
        self,
        n_channels: int,
        *,
        samplerate: float,
        window_length: int = 256,
        threshold: float = 10.0,
        hangover: float = 0.5,
        smoothing: float = 0.05,
        initial: float = 0.1,
        noise_min: float = 1e-5,
    ) -> None:
        self.samplerate = as_samplerate(samplerate)
        self.window_length = as_positive_int(window_length, name="window_length")
        self.hangover_windows, self.initial_windows = tracking_windows(
            samplerate=self.samplerate,
            window_length=self.window_length,
            threshold=threshold,
            hangover=hangover,
            smoothing=smoothing,
            initial=initial,
            noise_min=noise_min,
        )
        self.threshold = float(threshold)
        self.smoothing = float(smoothing)
        self.noise_min = float(noise_min)
        self.n_channels = n_channels
        self.level = History(n_channels)
        self.noise = History(n_channels)
        self.touches: list[Touch] = []
        self.n_windows = 0
        self._rest = np.zeros((n_channels, 0))
        self._waiting: list[np.ndarray] = []
        self._states: list[_ChannelState] | None = None

    def feed(self, block: np.ndarray) -> list[Touch]:
        """Take the next samples, shape (n_channels, n); the touches that ended in them."""
        samples = np.concatenate([self._rest, block], axis=1) if self._rest.size else block
        count = samples.shape[1] // self.window_length
        whole = samples[:, : count * self.window_length]
        self._rest = samples[:, count * self.window_length :].copy()
        if count == 0:
            return self._take(np.zeros((self.n_channels, 0)))
        length = self.window_length
        return self._take(rms(frame(whole, frame_length=length, hop_length=length)))

    def finish(self) -> list[Touch]:
        """End of the stream: start the floor from what there is; close open touches."""
        ended = self._start_floor() if self._states is None and self._waiting else []
        if self._states is None:
            return ended
        closing = []
        for channel, state in enumerate(self._states):
            if state.onset is not None:
                closing.append(Touch(channel, state.onset, self.n_windows - 1))
                state.onset = None
        self.touches += closing
        return ended + closing

    def open_onsets(self) -> list[tuple[int, int]]:
        """``(channel, onset window)`` of every touch still going on."""
        if self._states is None:
            return []
        return [(c, s.onset) for c, s in enumerate(self._states) if s.onset is not None]

    def track(self, first: int, stop: int) -> SnrTrack:
        """The windows ``[first, stop)`` as an :class:`SnrTrack` whose window 0 is ``first``.

        Touches that overlap them are included, shifted; one still going on ends at the
        last decided window.
        """
        level = self.level.view(first, stop)
        noise = self.noise.view(first, stop)
        spans = [(t.channel, t.first_window, t.last_window) for t in self.touches]
        spans += [(c, onset, self.n_windows - 1) for c, onset in self.open_onsets()]
        touches = tuple(
            sorted(
                (
                    Touch(channel=c, first_window=begin - first, last_window=end - first)
                    for c, begin, end in spans
                    if end >= first and begin < stop
                ),
                key=lambda t: (t.first_window, t.channel),
            )
        )
        return SnrTrack(
            snr=level / noise,
            noise=noise.copy(),
            level=level.copy(),
            touches=touches,
            threshold=self.threshold,
            window_length=self.window_length,
        )

    def discard_before(self, window: int) -> None:
        """Forget the windows (and ended touches) before ``window``."""
        self.level.discard_before(window)
        self.noise.discard_before(window)
        self.touches = [t for t in self.touches if t.last_window >= window]

    def _start_floor(self) -> list[Touch]:
        levels = np.concatenate(self._waiting, axis=1)
        self._waiting = []
        floors = np.median(levels[:, : self.initial_windows], axis=1)
        self._states = [_ChannelState(floor=max(float(f), self.noise_min)) for f in floors]
        return self._decide(levels)

    def _take(self, levels: np.ndarray) -> list[Touch]:
        if self._states is None:
            self._waiting.append(levels)
            if sum(part.shape[1] for part in self._waiting) < self.initial_windows:
                return []
            return self._start_floor()
        return self._decide(levels)

    def _decide(self, levels: np.ndarray) -> list[Touch]:
        assert self._states is not None
        noise = np.empty_like(levels)
        ended: list[Touch] = []
        for channel, state in enumerate(self._states):
            ended += self._follow(channel, state, levels[channel], noise[channel])
        self.level.append(levels)
        self.noise.append(noise)
        self.n_windows += levels.shape[1]
        self.touches += ended
        return ended

    def _follow(
        self, channel: int, state: _ChannelState, levels: np.ndarray, noise_out: np.ndarray
    ) -> list[Touch]:
        """One channel's new windows: fill ``noise_out``, return the touches that ended."""
        base, count = self.n_windows, levels.shape[0]
        ended = []
        i = 0
        while i < count:
            if state.onset is None:
                after = follow_floor(
                    levels[i:],
                    floor=state.floor,
                    smoothing=self.smoothing,
                    noise_min=self.noise_min,
                )
                before = np.concatenate([[state.floor], after[:-1]])
                loud = np.flatnonzero(levels[i:] > self.threshold * before)
                if loud.size == 0:
                    noise_out[i:] = before
                    state.floor = float(after[-1])
                    break
                k = int(loud[0])
                noise_out[i : i + k + 1] = before[: k + 1]
                state.floor = float(before[k])
                state.onset = state.last_loud = base + i + k
                state.limit = state.floor * self.threshold
                i += k + 1
                continue
            noise_out[i:] = state.floor
            marks = np.concatenate(
                [[state.last_loud], base + i + np.flatnonzero(levels[i:] > state.limit)]
            )
            long_gaps = np.flatnonzero(np.diff(marks) - 1 >= self.hangover_windows)
            if long_gaps.size:
                end = int(marks[long_gaps[0]]) + self.hangover_windows
            elif base + count - 1 - int(marks[-1]) >= self.hangover_windows:
                end = int(marks[-1]) + self.hangover_windows
            else:
                state.last_loud = int(marks[-1])
                break
            ended.append(Touch(channel=channel, first_window=state.onset, last_window=end))
            state.onset = None
            i = end - base + 1
        return ended
