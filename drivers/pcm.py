"""Raw interleaved PCM bytes to blocks of samples: what ROS audio messages and a live
WebSocket client send."""

from __future__ import annotations

import numpy as np

from touchbench.drivers.errors import DriverError

#: sample_format -> (numpy dtype, full scale); the names of audio_common's AudioInfo.
SAMPLE_FORMATS: dict[str, tuple[str, float]] = {
    "S16LE": ("<i2", 32768.0),
    "S32LE": ("<i4", 2147483648.0),
    "F32LE": ("<f4", 1.0),
}


def decode_pcm(data: bytes | np.ndarray, *, channels: int, sample_format: str) -> np.ndarray:
    """Interleaved little-endian PCM as samples in full-scale units.

    Parameters
    ----------
    data : bytes or ndarray of uint8
        Frames of ``channels`` samples each, interleaved.
    channels : int
        Samples per frame.
    sample_format : {"S16LE", "S32LE", "F32LE"}

    Returns
    -------
    ndarray of shape (channels, n_frames), float64, C order
        Integers divided by their full scale (32768, 2**31), floats as they are.

    Raises
    ------
    DriverError
        An unknown format, or bytes that are not a whole number of frames.
    """
    if sample_format not in SAMPLE_FORMATS:
        raise DriverError(
            f"sample format '{sample_format}' is not one of {', '.join(SAMPLE_FORMATS)}"
        )
    dtype, scale = SAMPLE_FORMATS[sample_format]
    raw = np.frombuffer(data, dtype=np.uint8) if isinstance(data, bytes) else data
    width = np.dtype(dtype).itemsize * channels
    if channels < 1 or raw.size % width:
        raise DriverError(
            f"{raw.size} bytes are not whole {sample_format} frames of {channels} channel(s)"
        )
    frames = raw.view(dtype).reshape(-1, channels)
    return np.ascontiguousarray(frames.T, dtype=np.float64) / scale
