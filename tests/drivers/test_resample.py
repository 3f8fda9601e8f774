from __future__ import annotations

import numpy as np
import pytest

from drivers.errors import DriverError
from drivers.resample import resample_even


def test_a_jittered_sine_comes_back_on_the_even_grid() -> None:
    rate, frequency = 100.0, 2.0
    rng = np.random.default_rng(1)
    # Stamps 10 ms apart jittered by up to +-4 ms, as a driver stamps them on arrival.
    times = 1.7e9 + np.arange(1000) / rate + rng.uniform(-0.004, 0.004, 1000)
    values = np.stack(
        [np.sin(2 * np.pi * frequency * times), np.cos(2 * np.pi * frequency * times)], axis=1
    )
    even, jitter = resample_even(times, values, rate)
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
    even, jitter = resample_even(times, values, 10.0)
    assert np.allclose(even[:, 0], np.arange(7.0))
    assert jitter.gaps == 1
    assert jitter.rate == pytest.approx(10.0)  # the gap does not lower the rate
    assert "1 gap(s)" in jitter.describe()


def test_stamps_must_rise() -> None:
    with pytest.raises(DriverError, match=r"stamp 2 \(0.1\) does not rise"):
        resample_even(np.array([0.0, 0.1, 0.1]), np.zeros((3, 1)), 10.0)
    with pytest.raises(DriverError, match="at least two stamps"):
        resample_even(np.array([0.0]), np.zeros((1, 1)), 10.0)
