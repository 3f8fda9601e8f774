"""Live sources on ROS topics: the audio of an ``AudioData`` topic, the taxels of a
``Float32MultiArray`` topic, through any :class:`~drivers.ros_transport.RosTransport`.

Times are seconds from the first message (samples counted, not stamps: a topic of
samples at a fixed rate); a block's ``arrived`` is when the message that completed it
arrived, so a touch's latency counts from the end of its audio message.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from touchbench.drivers.errors import DriverError
from touchbench.drivers.mp3 import Mp3Decoder
from touchbench.drivers.pcm import SAMPLE_FORMATS, decode_pcm
from touchbench.drivers.ros_transport import AudioFormat, Message, RosTransport
from touchbench.drivers.source import Block, Source

#: Decoded samples per block of live MP3 audio (one MPEG-1 Layer III frame).
MP3_LIVE_BLOCK = 1152


def info_topic_of(audio_topic: str) -> str:
    """Where audio_capture publishes the format of ``audio_topic``: ``audio_info`` beside
    it (``/audio/audio`` -> ``/audio/audio_info``, ``/audio`` -> ``/audio_info``)."""
    namespace = audio_topic.rstrip("/").rsplit("/", 1)[0]
    return f"{namespace}/audio_info"


class RosAudioSource(Source):
    """The audio of an ``audio_common_msgs/AudioData`` topic.

    Parameters
    ----------
    transport : RosTransport
    topic : str
    info_topic : str
        The ``AudioInfo`` topic, read when ``sample_format`` is not given.
    samplerate, channels : optional
        Of raw PCM given without ``AudioInfo``; with it, they must agree.
    sample_format : str, optional
        ``S16LE``, ``S32LE``, ``F32LE`` or ``MP3``: the format is given, not read from
        ``AudioInfo`` (MP3 carries its own rate and channels).
    info_timeout : float
        Seconds to wait for ``AudioInfo`` (audio_capture latches it: it comes at once).

    Raises
    ------
    DriverError
        No ``AudioInfo`` and no format given, a format other than raw PCM or MP3, or
        options that disagree with ``AudioInfo``.
    """

    def __init__(
        self,
        transport: RosTransport,
        topic: str,
        *,
        info_topic: str,
        samplerate: float | None = None,
        channels: int | None = None,
        sample_format: str | None = None,
        info_timeout: float = 5.0,
    ) -> None:
        self.name = f"ROS topic '{topic}'"
        self._transport = transport
        self._topic = topic
        self.notes: list[str] = []
        given = AudioFormat(
            channels=channels or 0,
            samplerate=samplerate or 0.0,
            sample_format=(sample_format or "").upper(),
            coding="mp3" if (sample_format or "").upper() == "MP3" else "wave",
        )
        if sample_format is None:
            info = transport.audio_info(info_topic, timeout=info_timeout)
            if info is None:
                raise DriverError(
                    f"no AudioInfo on '{info_topic}' within {info_timeout:g} s, so the format "
                    f"of '{topic}' is unknown: give its sample format (S16LE, S32LE, F32LE "
                    "or MP3), and its rate and channels if not the model's"
                )
            self._agree(info, given, f"AudioInfo on '{info_topic}'")
            given = info
            self.notes.append(
                f"format from '{info_topic}': {info.coding} {info.sample_format} "
                f"{info.channels} channel(s) at {info.samplerate:g} Hz"
            )
        self.coding = given.coding
        if self.coding not in ("wave", "mp3"):
            raise DriverError(
                f"'{topic}' carries {self.coding or '?'}-coded audio; touchbench reads raw "
                "PCM (coding_format wave) and MP3"
            )
        if self.coding == "wave" and given.sample_format not in SAMPLE_FORMATS:
            raise DriverError(
                f"sample format '{given.sample_format}' of '{topic}' is not one of "
                f"{', '.join([*SAMPLE_FORMATS, 'MP3'])}"
            )
        self.sample_format = given.sample_format if self.coding == "wave" else None
        self._messages = transport.subscribe(topic, "audio")
        self._arrived = 0.0
        self._mp3: Mp3Decoder | None = None
        if self.coding == "mp3":
            # Opening reads the first frames: it waits for the first messages.
            self._mp3 = Mp3Decoder(self._chunks, name=self.name, unbounded=True)
            decoded = AudioFormat(self._mp3.n_channels, self._mp3.samplerate, "", "mp3")
            self._agree(decoded, given, "its MP3 frames")
            self.samplerate, self.n_channels = self._mp3.samplerate, self._mp3.n_channels
            return
        if given.samplerate <= 0 or given.channels < 1:
            raise DriverError(
                f"raw PCM on '{topic}' needs its sample rate and channel count "
                f"(have {given.samplerate:g} Hz, {given.channels} channel(s))"
            )
        self.samplerate, self.n_channels = float(given.samplerate), int(given.channels)

    def _agree(self, found: AudioFormat, given: AudioFormat, where: str) -> None:
        pairs = (
            ("sample rate", found.samplerate, given.samplerate),
            ("channels", found.channels, given.channels),
        )
        for what, have, wanted in pairs:
            if wanted and abs(float(have) - float(wanted)) > 1e-6:
                raise DriverError(
                    f"{where} gives {what} {have:g} for '{self._topic}', but {wanted:g} was given"
                )

    def _chunks(self) -> Iterator[bytes]:
        for message in self._messages:
            self._arrived = message.arrived
            assert isinstance(message.data, bytes)
            yield message.data

    def blocks(self) -> Iterator[Block]:
        position = 0
        if self._mp3 is not None:
            for samples in self._mp3.blocks(MP3_LIVE_BLOCK):
                yield Block(samples, position / self.samplerate, arrived=self._arrived)
                position += samples.shape[1]
            return
        assert self.sample_format is not None
        for number, message in enumerate(self._messages, 1):
            assert isinstance(message.data, bytes)
            try:
                samples = decode_pcm(
                    message.data, channels=self.n_channels, sample_format=self.sample_format
                )
            except DriverError as error:
                raise DriverError(f"{self.name}: message {number}: {error}") from None
            yield Block(samples, position / self.samplerate, arrived=message.arrived)
            position += samples.shape[1]

    def close(self) -> None:
        if self._mp3 is not None:
            self._mp3.close()


class RosTaxelSource(Source):
    """The taxels of a ``std_msgs/Float32MultiArray`` topic at a fixed rate.

    Each message is one sample of every taxel (``data`` of n_taxels values, no layout or
    one dimension), or a block of samples (a layout of two dimensions: samples, then
    taxels).

    Parameters
    ----------
    transport : RosTransport
    topic : str
    samplerate : float
        Samples per second the topic carries (messages per second for one sample each).
    channels : int
        Taxels of every sample.
    """

    def __init__(
        self, transport: RosTransport, topic: str, *, samplerate: float, channels: int
    ) -> None:
        if samplerate <= 0 or channels < 1:
            raise DriverError(
                f"taxels on '{topic}' need a rate and a taxel count "
                f"(have {samplerate:g} Hz, {channels})"
            )
        self.name = f"ROS topic '{topic}'"
        self.samplerate, self.n_channels = float(samplerate), int(channels)
        self._messages: Iterator[Message] = transport.subscribe(topic, "taxels")

    def blocks(self) -> Iterator[Block]:
        position = 0
        for number, message in enumerate(self._messages, 1):
            values = np.asarray(message.data, dtype=np.float64)
            samples = values.reshape(-1, 1) if values.ndim == 1 else values.T
            if samples.shape[0] != self.n_channels or not np.isfinite(samples).all():
                raise DriverError(
                    f"{self.name}: message {number} holds {samples.shape[0]} taxel value(s) "
                    f"per sample, not {self.n_channels} finite ones"
                )
            yield Block(np.ascontiguousarray(samples), position / self.samplerate, message.arrived)
            position += samples.shape[1]

    def close(self) -> None:
        pass
