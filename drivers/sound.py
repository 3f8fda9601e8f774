"""Capture from a sound card through PortAudio (``sounddevice``).

:class:`SoundDeviceSource` opens an input stream whose audio callback copies each block
into a bounded queue; the consumer takes them from there.  When the consumer falls
behind and the queue is full, the block is dropped and counted in ``overflows`` (as are
PortAudio's own input overflows): never silently.  A missing PortAudio library, a device
that does not exist and a sample rate or channel count the device refuses are each one
:class:`~drivers.errors.DriverError` line that says what to do.
"""

from __future__ import annotations

import contextlib
import os
import queue
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from touchbench.drivers.errors import DriverError
from touchbench.drivers.source import Block, Source

_END = None
#: sample format -> full scale
_SCALES = {"int16": 32768.0, "int32": 2147483648.0, "float32": 1.0}


@dataclass(frozen=True)
class Device:
    """A capture device as PortAudio lists it."""

    index: int
    name: str
    input_channels: int
    default_samplerate: float
    hostapi: str

    def to_json(self) -> dict[str, Any]:
        return {
            "index": self.index,
            "name": self.name,
            "input_channels": self.input_channels,
            "default_samplerate": self.default_samplerate,
            "hostapi": self.hostapi,
        }


def portaudio() -> Any:
    """The ``sounddevice`` module, or a :class:`DriverError` naming the missing library."""
    try:
        with _quiet_stderr():
            import sounddevice
    except OSError as error:  # sounddevice raises OSError when libportaudio is absent
        raise DriverError(
            f"PortAudio is not installed ({error}); on Debian/Ubuntu: apt-get install libportaudio2"
        ) from None
    return sounddevice


def list_devices() -> list[Device]:
    """Every device with at least one input channel."""
    sd = portaudio()
    with _quiet_stderr():
        devices = sd.query_devices()
        apis = sd.query_hostapis()
    return [
        Device(
            index=int(device["index"]),
            name=str(device["name"]),
            input_channels=int(device["max_input_channels"]),
            default_samplerate=float(device["default_samplerate"]),
            hostapi=str(apis[device["hostapi"]]["name"]),
        )
        for device in devices
        if device["max_input_channels"] > 0
    ]


def find_device(device: str | int) -> Device:
    """The input device with index ``device`` (a number) or whose name contains it."""
    sd = portaudio()
    key: str | int = int(device) if isinstance(device, str) and device.isdigit() else device
    try:
        with _quiet_stderr():
            found = sd.query_devices(key, "input")
    except ValueError:
        raise DriverError(
            f"no capture device '{device}' (the device listing shows those PortAudio sees)"
        ) from None
    return next(d for d in list_devices() if d.index == int(found["index"]))


class SoundDeviceSource(Source):
    """Multichannel capture from a sound card.

    Parameters
    ----------
    device : str or int
        Device index, or (part of) its name.
    samplerate : float, optional
        Hz; the device's default if not given.
    channels : int, optional
        Input channels; all the device has if not given.
    block_length : int
        Samples per block handed from the audio callback.
    queue_seconds : float
        Audio the queue holds before blocks are dropped (and counted).
    seconds : float, optional
        Stop after this much audio; run until closed otherwise.
    sample_format : {"int16", "int32", "float32"}
        What PortAudio delivers (scaled to full scale -1 to 1 here); 16-bit by default,
        the format every sound card has.
    """

    def __init__(
        self,
        device: str | int,
        *,
        samplerate: float | None = None,
        channels: int | None = None,
        block_length: int = 1024,
        queue_seconds: float = 5.0,
        seconds: float | None = None,
        sample_format: str = "int16",
    ) -> None:
        if sample_format not in _SCALES:
            raise DriverError(
                f"sample_format must be one of {', '.join(_SCALES)}, got '{sample_format}'"
            )
        self.sample_format = sample_format
        sd = portaudio()
        found = find_device(device)
        self.device = found
        self.samplerate = float(samplerate or found.default_samplerate)
        self.n_channels = int(channels or found.input_channels)
        self.name = f"device {found.index} ({found.name})"
        if block_length < 1:
            raise DriverError(f"block_length must be at least 1, got {block_length}")
        self.block_length = block_length
        self.limit = None if seconds is None else round(seconds * self.samplerate)
        try:
            with _quiet_stderr():
                sd.check_input_settings(
                    device=found.index,
                    channels=self.n_channels,
                    samplerate=self.samplerate,
                    dtype=sample_format,
                )
        except sd.PortAudioError as error:
            raise DriverError(
                f"{self.name} refuses {self.n_channels} channel(s) at {self.samplerate:g} Hz "
                f"({error.args[0]}); it has {found.input_channels} input channels and "
                f"defaults to {found.default_samplerate:g} Hz"
            ) from None
        depth = max(2, round(queue_seconds * self.samplerate / block_length))
        self._queue: queue.Queue[tuple[np.ndarray, float] | None] = queue.Queue(maxsize=depth)
        self.dropped = 0  # blocks the consumer was too slow for (queue full)
        self.xruns = 0  # callbacks whose input PortAudio reports as overflowed
        self._received = 0  # frames the callback was handed within the take
        self._lock = threading.Lock()
        self._stream: Any = None
        self._sd = sd

    @property
    def overflows(self) -> int:  # type: ignore[override]
        """Blocks lost: dropped from a full queue, or reported lost by PortAudio."""
        return self.dropped + self.xruns

    def _callback(self, data: np.ndarray, frames: int, when: Any, status: Any) -> None:
        # past the take's end the stream runs on until it is closed: what it then delivers,
        # or loses, was never asked for and counts for nothing
        if self.limit is not None and self._received >= self.limit:
            return
        self._received += frames
        if status.input_overflow:
            with self._lock:
                self.xruns += 1
        try:
            block = np.ascontiguousarray(data.T, dtype=np.float64) / _SCALES[self.sample_format]
            self._queue.put_nowait((block, time.perf_counter()))
        except queue.Full:
            with self._lock:
                self.dropped += 1

    def _open(self) -> None:
        try:
            with _quiet_stderr():
                self._stream = self._sd.InputStream(
                    device=self.device.index,
                    channels=self.n_channels,
                    samplerate=self.samplerate,
                    blocksize=self.block_length,
                    dtype=self.sample_format,
                    callback=self._callback,
                )
                self._stream.start()
        except self._sd.PortAudioError as error:
            raise DriverError(f"{self.name}: cannot start capture: {error.args[0]}") from None

    def blocks(self) -> Iterator[Block]:
        if self._stream is None:
            self._open()
        position = 0
        while self.limit is None or position < self.limit:
            try:
                item = self._queue.get(timeout=max(1.0, 20 * self.block_length / self.samplerate))
            except queue.Empty:
                if self._stream is None or not self._stream.active:
                    return
                continue
            if item is _END:
                return
            samples, arrived = item
            if self.limit is not None:
                samples = samples[:, : self.limit - position]
            yield Block(samples, position / self.samplerate, arrived=arrived)
            position += samples.shape[1]

    def close(self) -> None:
        stream, self._stream = self._stream, None
        if stream is not None:
            with contextlib.suppress(Exception), _quiet_stderr():
                stream.abort()
                stream.close()


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    """Silence what ALSA and PortAudio print on the C library's stderr while probing:
    their failures come back as exceptions, which are worded here in one line."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no real stderr (embedded, tests): nothing to silence
        yield
        return
    try:
        with open(os.devnull, "w") as sink:
            os.dup2(sink.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
