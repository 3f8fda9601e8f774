"""Uneven stamps onto an even grid: against a known sine, in pieces as whole, and the note."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from touchbench.drivers.errors import DriverError
from touchbench.drivers.resample import (
    EvenResampler,
    jitter_note,
    jitter_of,
    median_rate,
    resample_even,
)


def _stamps(n: int = 2000, seed: int = 0) -> np.ndarray:
    """A 100 Hz sensor's stamps: steps of 3 to 17 ms, from 12.5 s."""
    return 12.5 + np.cumsum(np.random.default_rng(seed).uniform(0.003, 0.017, n))


def test_a_sine_sampled_at_jittered_stamps_comes_back_on_the_grid() -> None:
    times = _stamps()
    frequency = 2.0  # Hz: slow against 100 Hz, as touches on a tactile sensor are
    values = np.stack(
        [np.sin(2 * np.pi * frequency * times), np.cos(2 * np.pi * frequency * times)]
    )
    rate = median_rate(times)
    out = resample_even(times, values, rate)
    grid = times[0] + np.arange(out.shape[1]) / rate
    assert grid[-1] <= times[-1] < grid[-1] + 1 / rate
    # Linear interpolation's error bound: (step^2 / 8) * max|f''| for steps up to 17 ms.
    bound = 0.017**2 / 8 * (2 * np.pi * frequency) ** 2
    assert np.abs(out[0] - np.sin(2 * np.pi * frequency * grid)).max() <= bound
    assert np.abs(out[1] - np.cos(2 * np.pi * frequency * grid)).max() <= bound
    assert out[0, 0] == values[0, 0]  # the grid starts at the first stamp


def test_pieces_give_what_the_whole_gives() -> None:
    times = _stamps(1000, seed=1)
    values = np.random.default_rng(2).normal(size=(3, times.size))
    whole = resample_even(times, values, 80.0)
    resampler = EvenResampler(float(times[0]), 80.0)
    cuts = [0, 1, 2, 97, 98, 500, 999, 1000]
    parts = [resampler.feed(times[a:b], values[:, a:b]) for a, b in itertools.pairwise(cuts)]
    assert np.array_equal(np.concatenate(parts, axis=1), whole)
    assert resampler.produced == whole.shape[1]


def test_times_that_do_not_rise_are_refused() -> None:
    with pytest.raises(DriverError, match="must rise strictly"):
        resample_even(np.array([0.0, 0.01, 0.01]), np.zeros((1, 3)), 100)
    with pytest.raises(DriverError, match="do not match 3 time stamps"):
        resample_even(np.array([0.0, 0.01, 0.02]), np.zeros((1, 2)), 100)
    with pytest.raises(DriverError, match="at least two are needed"):
        median_rate(np.array([1.0]))
    with pytest.raises(DriverError, match="must be positive"):
        EvenResampler(0.0, 0.0)


def test_the_note_says_how_uneven_only_when_it_matters() -> None:
    even = 0.5 + np.arange(100) / 100
    assert jitter_note(even, 100.0, what="stamps of /x") is None
    # Even stamps put on another grid are news too.
    assert jitter_note(even, 50.0, what="stamps of /x") == (
        "stamps of /x are even (100 Hz); resampled onto an even 50 Hz grid by linear interpolation"
    )
    note = jitter_note(_stamps(), 100.0, what="stamps of /biotac")
    assert note is not None
    assert note.startswith("stamps of /biotac are uneven (steps 3")
    assert note.endswith("resampled onto an even 100 Hz grid by linear interpolation")


def test_a_jittered_sine_comes_back_on_the_even_grid() -> None:
    rate, frequency = 100.0, 2.0
    rng = np.random.default_rng(1)
    # Stamps 10 ms apart jittered by up to +-4 ms, as a driver stamps them on arrival.
    times = 1.7e9 + np.arange(1000) / rate + rng.uniform(-0.004, 0.004, 1000)
    values = np.stack(
        [np.sin(2 * np.pi * frequency * times), np.cos(2 * np.pi * frequency * times)], axis=1
    )
    even = resample_even(times, values.T, rate).T
    jitter = jitter_of(times)
    grid = times[0] + np.arange(even.shape[0]) / rate
    assert even.shape == (int(np.floor((times[-1] - times[0]) * rate)) + 1, 2)
    expected = np.stack(
        [np.sin(2 * np.pi * frequency * grid), np.cos(2 * np.pi * frequency * grid)], axis=1
    )
    # Linear interpolation over a step h errs by at most h^2 / 8 max|y''| = (2 pi f h)^2 / 8
    # (0.0064 for the longest step here, 18 ms); plain nearest-sample error would be ~0.1.
    bound = (2 * np.pi * frequency * np.diff(times).max()) ** 2 / 8
    assert np.abs(even - expected).max() <= bound < 0.01
    assert jitter.median_rate == pytest.approx(rate, rel=0.05)
    # The mean of the steps is the precise rate: the jitter of the two ends over 10 s.
    assert jitter.rate == pytest.approx(rate, rel=1e-3)
    assert 1.0 < jitter.std_ms < 4.0 and 4.0 < jitter.max_ms <= 8.0
    assert jitter.gaps == 0


def test_even_stamps_are_kept_and_gaps_are_counted() -> None:
    times = np.array([0.0, 0.1, 0.2, 0.5, 0.6])
    values = np.array([[0.0], [1.0], [2.0], [5.0], [6.0]])
    even = resample_even(times, values.T, 10.0)
    jitter = jitter_of(times)
    assert np.allclose(even[0], np.arange(7.0))
    assert jitter.gaps == 1
    assert jitter.rate == pytest.approx(10.0)  # the gap does not lower the rate
    assert "1 gap(s)" in jitter.describe()
