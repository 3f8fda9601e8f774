"""Samples with uneven time stamps brought onto an even grid.

Real robots stamp their samples when a driver gets them, not when the sensor took them:
a BioTac logged at 100 Hz shows steps of 3 to 17 ms.  The extractors assume one sample
every ``1 / rate`` seconds, so :func:`resample_even` interpolates the samples linearly
onto the grid ``t0, t0 + 1/rate, ...`` (from the first stamp to the last) and says how
far the stamps were from even.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drivers.errors import DriverError

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


def resample_even(times: np.ndarray, values: np.ndarray, rate: float) -> tuple[np.ndarray, Jitter]:
    """``values`` stamped at ``times``, linearly interpolated onto an even grid.

    Parameters
    ----------
    times : ndarray of shape (n,)
        Strictly rising stamps in seconds, ``n >= 2``.
    values : ndarray of shape (n, n_channels)
        The samples at those stamps.
    rate : float
        Samples per second of the grid.

    Returns
    -------
    even : ndarray of shape (m, n_channels), float64
        The samples at ``times[0] + k / rate`` for ``k = 0 ... m - 1``, the last grid
        point at or before ``times[-1]`` (``m = floor((times[-1] - times[0]) rate) + 1``);
        column-major (its ``.T`` is C-contiguous).
    jitter : Jitter
        How far ``times`` were from even.

    Raises
    ------
    DriverError
        Fewer than two stamps, stamps that do not rise, or a rate that is not positive.
    """
    times = np.asarray(times, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    if times.ndim != 1 or values.ndim != 2 or values.shape[0] != times.size:
        raise DriverError(
            f"times of shape (n,) and values of shape (n, channels) expected, got "
            f"{times.shape} and {values.shape}"
        )
    if times.size < 2:
        raise DriverError("at least two stamps are needed to resample")
    if not math.isfinite(rate) or rate <= 0:
        raise DriverError(f"the rate must be a positive number of Hz, got {rate!r}")
    steps = np.diff(times)
    if not (steps > 0).all():
        index = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise DriverError(f"stamp {index} ({times[index]:.9g}) does not rise over the one before")
    # A small tolerance: the last stamp on the grid itself must not be lost to rounding.
    count = math.floor((times[-1] - times[0]) * rate + 1e-9) + 1
    grid = times[0] + np.arange(count) / rate
    # One channel at a time, into a channel-major buffer: no temporary of the whole
    # recording, and callers that want (n_channels, m) get it without a copy (``.T``).
    even = np.empty((values.shape[1], count))
    for channel in range(values.shape[1]):
        even[channel] = np.interp(grid, times, values[:, channel])
    return even.T, jitter_of(times)
