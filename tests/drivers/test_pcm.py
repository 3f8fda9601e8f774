"""Interleaved PCM bytes to samples (ROS audio messages, live WebSocket clients)."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.drivers.errors import DriverError
from touchbench.drivers.pcm import decode_pcm


def test_frames_are_deinterleaved_and_scaled_to_full_scale() -> None:
    frames = np.array([[0, -32768], [16384, 32767], [-16384, 1]], dtype="<i2")
    samples = decode_pcm(frames.tobytes(), channels=2, sample_format="S16LE")
    assert samples.shape == (2, 3) and samples.flags.c_contiguous
    assert samples.tolist() == [[0.0, 0.5, -0.5], [-1.0, 32767 / 32768, 1 / 32768]]
    floats = np.array([[0.25, -0.75]], dtype="<f4")
    assert decode_pcm(floats.tobytes(), channels=2, sample_format="F32LE").tolist() == [
        [0.25],
        [-0.75],
    ]
    wide = np.array([[-(2**31)]], dtype="<i4")
    assert decode_pcm(wide.tobytes(), channels=1, sample_format="S32LE").tolist() == [[-1.0]]


@pytest.mark.parametrize(
    ("data", "channels", "sample_format", "message"),
    [
        (b"\x00" * 6, 2, "S16LE", "6 bytes are not whole S16LE frames of 2 channel"),
        (b"\x00" * 4, 1, "U8", "sample format 'U8' is not one of S16LE, S32LE, F32LE"),
    ],
)
def test_bytes_that_are_not_whole_frames_are_refused(
    data: bytes, channels: int, sample_format: str, message: str
) -> None:
    with pytest.raises(DriverError, match=message):
        decode_pcm(data, channels=channels, sample_format=sample_format)
