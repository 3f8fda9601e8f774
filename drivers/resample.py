"""Samples at uneven times onto an even grid: what ROS stamps and logged time columns need.

Real stamps jitter (a 100 Hz sensor's messages arrive 3 to 17 ms apart), while every
extractor assumes one sample every ``1 / rate`` seconds.  :func:`resample_even` puts
samples taken at rising ``times`` onto the grid ``times[0] + k / rate`` by linear
interpolation between the two samples around each grid time;
:class:`EvenResampler` does the same block by block, for sources read as a stream, and
gives the same values.  :func:`median_rate` and :func:`jitter_note` say what the stamps
were, for a note to the user; :func:`jitter_of` measures them (:class:`Jitter`: the
precise mean rate, the jitter, the gaps).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from touchbench.drivers.errors import DriverError
from touchbench.drivers.limits import ReadLimits

#: Steps within this fraction of the median step count as even (no note).
EVEN = 0.01


def median_rate(times: np.ndarray) -> float:
    """Samples per second from the median step of rising ``times`` (seconds).

    Raises
    ------
    DriverError
        Fewer than two times, or a median step that is not positive.
    """
    if times.size < 2:
        raise DriverError(f"{times.size} time stamp(s) give no rate; at least two are needed")
    step = float(np.median(np.diff(times)))
    if not step > 0:
        raise DriverError("the time stamps do not rise (their median step is not positive)")
    return 1.0 / step


def resample_even(times: np.ndarray, values: np.ndarray, rate: float) -> np.ndarray:
    """``values`` sampled at ``times`` onto an even grid starting at ``times[0]``.

    Parameters
    ----------
    times : ndarray of shape (n,)
        Seconds, strictly rising.
    values : ndarray of shape (n_channels, n)
        Samples of every channel at ``times``.
    rate : float
        Samples per second of the grid.

    Returns
    -------
    ndarray of shape (n_channels, m), float64
        Linear interpolation at ``times[0] + k / rate`` for ``k = 0 .. m - 1``, where
        the last grid time is the last one not after ``times[-1]``.

    Raises
    ------
    DriverError
        Times that do not rise, or shapes that disagree.
    """
    if times.size == 0:
        return np.zeros((values.shape[0], 0))
    return EvenResampler(float(times[0]), rate).feed(times, values)


def check_grid(
    times: np.ndarray,
    rate: float,
    n_channels: int,
    limits: ReadLimits,
    *,
    at: Callable[[int], str],
    before: str,
) -> None:
    """Refuse to put rising ``times`` onto a grid at ``rate`` when it would fill one gap
    with more than ``limits.gap_samples`` samples or hold more than ``limits.cells``
    values: checked before any of it is made, so that the work follows the number of
    stamps, not what they say.

    Parameters
    ----------
    times : ndarray of shape (n,)
        Seconds, strictly rising.
    rate : float
        The grid's samples per second.
    n_channels : int
    limits : ReadLimits
    at : callable
        ``at(index)``: where the stamp ``times[index]`` is, as the message's start
        (``"take.csv:4: column 'time' jumps"``).
    before : str
        What the stamp before it is called (``"the line before"``).

    Raises
    ------
    DriverError
        One line naming the longest gap, where it is and how many samples it would make.
    """
    if times.size < 2:
        return
    steps = np.diff(times)
    index = int(np.argmax(steps))
    gap = float(steps[index])
    where = f"{at(index + 1)} {gap:.6g} s over {before}: resampling at {rate:.6g} Hz"
    if gap * rate > limits.gap_samples:
        raise DriverError(
            f"{where} would fill that gap with {gap * rate:,.0f} samples, more than the "
            f"{limits.gap_samples:,} allowed{limits.raised_by('gap_samples')}; split the "
            "recording at the gap"
        )
    total = int(np.floor((times[-1] - times[0]) * rate + 1e-9)) + 1
    if total * n_channels > limits.cells:
        raise DriverError(
            f"{where} would make {total:,} samples x {n_channels:,} channel(s) of "
            f"{times.size:,} stamps, more than the {limits.cells:,} values a recording may "
            f"hold{limits.raised_by('cells')}"
        )


class EvenResampler:
    """:func:`resample_even` fed in consecutive pieces, with the same result.

    Parameters
    ----------
    start : float
        The grid's first time (the first sample's time).
    rate : float
        Samples per second of the grid.
    """

    def __init__(self, start: float, rate: float) -> None:
        if not rate > 0:
            raise DriverError(f"the resampling rate must be positive, got {rate!r}")
        self.start = start
        self.rate = rate
        self.produced = 0  # grid points given so far
        self._last_time: float | None = None
        self._last_values: np.ndarray | None = None

    def feed(self, times: np.ndarray, values: np.ndarray) -> np.ndarray:
        """The grid points up to ``times[-1]`` not given yet.

        Parameters
        ----------
        times : ndarray of shape (n,)
            Seconds, strictly rising, after the times fed before.
        values : ndarray of shape (n_channels, n)

        Returns
        -------
        ndarray of shape (n_channels, k), float64
        """
        times = np.asarray(times, dtype=np.float64)
        values = np.asarray(values, dtype=np.float64)
        if values.ndim != 2 or values.shape[1] != times.size:
            raise DriverError(f"{values.shape} values do not match {times.size} time stamps")
        if times.size == 0:
            return np.zeros((values.shape[0], 0))
        if self._last_time is not None and self._last_values is not None:
            times = np.concatenate([[self._last_time], times])
            values = np.concatenate([self._last_values, values], axis=1)
        if np.any(np.diff(times) <= 0):
            raise DriverError("the time stamps must rise strictly to be resampled")
        self._last_time, self._last_values = float(times[-1]), values[:, -1:].copy()
        end = int(np.floor((times[-1] - self.start) * self.rate + 1e-9)) + 1
        grid = self.start + np.arange(self.produced, end) / self.rate
        self.produced = max(self.produced, end)
        out = np.empty((values.shape[0], grid.size))
        for channel in range(values.shape[0]):  # np.interp is one-dimensional
            out[channel] = np.interp(grid, times, values[channel])
        return out


def jitter_note(times: np.ndarray, rate: float, *, what: str) -> str | None:
    """One line on uneven ``times`` and the grid they were put on; None when even.

    Parameters
    ----------
    times : ndarray of shape (n,)
        Seconds, rising.
    rate : float
        The grid's samples per second.
    what : str
        What the stamps are, e.g. ``"stamps of /biotac"``.
    """
    if times.size < 2:
        return None
    steps = np.diff(times)
    median = float(np.median(steps))
    low, high = float(steps.min()), float(steps.max())
    grid = f"resampled onto an even {rate:.4g} Hz grid by linear interpolation"
    if high - low <= EVEN * median:
        if abs(median * rate - 1.0) <= EVEN:
            return None
        return f"{what} are even ({1 / median:.4g} Hz); {grid}"
    return (
        f"{what} are uneven (steps {low * 1e3:.3g} to {high * 1e3:.3g} ms, median "
        f"{median * 1e3:.3g} ms, {1 / median:.4g} Hz); {grid}"
    )


#: A step longer than this many median steps counts as a gap (a sample lost: jitter alone
#: stretches a step by less than one step).
GAP_STEPS = 1.9


@dataclass(frozen=True)
class Jitter:
    """How uneven the stamps were.

    Parameters
    ----------
    median_rate : float
        ``1 / median step`` in Hz.
    rate : float
        ``1 / mean step`` over the steps that are not gaps, in Hz: the rate the stamps
        suggest.  Far more precise than the median under jitter (the steps' errors cancel
        in their sum: at 100 Hz, jitter of +-3 ms moves the median rate by about 1 % over
        600 samples, the mean rate by under 0.1 %), and not lowered by lost samples.
    std_ms : float
        Standard deviation of the steps from their median, in milliseconds.
    max_ms : float
        Largest distance of one step from the median step, in milliseconds.
    gaps : int
        Steps longer than :data:`GAP_STEPS` median steps (samples lost or late).
    """

    median_rate: float
    rate: float
    std_ms: float
    max_ms: float
    gaps: int

    def describe(self) -> str:
        """One line: the median rate, the jitter and the gaps."""
        text = (
            f"stamps at {self.rate:.6g} Hz jitter by {self.std_ms:.3g} ms "
            f"(standard deviation; at most {self.max_ms:.3g} ms)"
        )
        if self.gaps:
            text += f", with {self.gaps} gap(s) longer than {GAP_STEPS:g} steps"
        return text


def jitter_of(times: np.ndarray) -> Jitter:
    """The :class:`Jitter` of rising stamps ``times`` of shape (n,), n >= 2, in seconds."""
    steps = np.diff(np.asarray(times, dtype=np.float64))
    median = float(np.median(steps))
    deviation = steps - median
    regular = steps[steps <= GAP_STEPS * median]
    return Jitter(
        median_rate=1.0 / median,
        rate=1.0 / float(regular.mean()),
        std_ms=1000.0 * float(np.sqrt(np.mean(deviation**2))),
        max_ms=1000.0 * float(np.abs(deviation).max()),
        gaps=int(np.count_nonzero(steps > GAP_STEPS * median)),
    )
