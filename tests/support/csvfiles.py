"""CSV time series in the shape real tactile exports have (a BioTac export: ROS stamps
in seconds, jittered, named channels, a comma at the end of every row)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

BIOTAC_CHANNELS = ("tdc", "tac", "pdc", *(f"pac{i}" for i in range(1, 23)))


def write_biotac_csv(
    path: Path,
    samples: np.ndarray,
    *,
    start: float = 1.7e9,
    rate: float = 100.0,
    jitter: float = 0.004,
    seed: int = 0,
    channels: tuple[str, ...] | None = None,
    time_name: str = "timestamp",
    nanoseconds: bool = False,
) -> np.ndarray:
    """Write ``samples`` of shape (n_channels, n) with jittered stamps; return the stamps
    (seconds) written."""
    n_channels, n = samples.shape
    names = channels or BIOTAC_CHANNELS[:n_channels]
    rng = np.random.default_rng(seed)
    times = start + np.arange(n) / rate + rng.uniform(-jitter, jitter, n)
    lines = [",".join((time_name, *names)) + ","]
    for stamp, row in zip(times, samples.T, strict=True):
        written = f"{round(stamp * 1e9)}" if nanoseconds else f"{stamp:.6f}"
        lines.append(",".join([written, *(f"{value:.6g}" for value in row)]) + ",")
    path.write_text("\n".join(lines) + "\n")
    return times
