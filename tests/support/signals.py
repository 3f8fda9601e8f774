"""Analytic test signals shared by the feature tests."""

from __future__ import annotations

import numpy as np


def sine(
    frequency: float, *, samplerate: float, n_samples: int, amplitude: float = 1.0
) -> np.ndarray:
    """``amplitude * sin(2 pi f n / samplerate)``, shape (n_samples,)."""
    return amplitude * np.sin(2 * np.pi * frequency * np.arange(n_samples) / samplerate)


def white_noise(n_samples: int, *, seed: int = 0, scale: float = 1.0) -> np.ndarray:
    """Gaussian white noise, shape (n_samples,)."""
    return scale * np.random.default_rng(seed).standard_normal(n_samples)


def click_train(
    rate: float, *, duration: float, samplerate: float, start: float = 0.5, noise: float = 1e-3
) -> tuple[np.ndarray, int]:
    """Clicks (1 ms decaying bursts) every ``1 / rate`` s from ``start``; (signal, n_clicks)."""
    n_samples = int(duration * samplerate)
    y = noise * np.random.default_rng(1).standard_normal(n_samples)
    times = np.arange(start, duration - 0.01, 1.0 / rate)
    burst_length = int(0.001 * samplerate)
    burst = (
        0.5
        * np.exp(-np.arange(burst_length) / (0.2 * burst_length))
        * np.cos(2 * np.pi * 2000 * np.arange(burst_length) / samplerate)
    )
    for time in times:
        start_index = int(time * samplerate)
        y[start_index : start_index + burst_length] += burst
    return y, len(times)
