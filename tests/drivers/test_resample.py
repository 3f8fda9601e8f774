"""Uneven stamps onto an even grid: against a known sine, in pieces as whole, and the note."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from drivers.errors import DriverError
from drivers.resample import EvenResampler, jitter_note, median_rate, resample_even


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
