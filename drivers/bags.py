"""Audio in ROS bags: ROS 1 ``.bag``, ROS 2 ``.mcap`` and ``.db3`` (file or bag folder).

Read with the pure-Python ``rosbags`` library, no ROS install.  The audio is
``audio_common_msgs`` audio: ``AudioData`` (``uint8[] data``) or ``AudioDataStamped``
(a header and an ``AudioData``) carrying raw interleaved PCM, described by an
``AudioInfo`` topic (channels, sample_rate, sample_format ``S16LE``/``S32LE``/``F32LE``,
coding_format ``wave``).  Message types are recognised by their definition, not their
name, so a same-named type of another package is not taken for audio; when a bag does
not carry its definitions, the audio types are registered from their ``.msg`` text.

Times are seconds from the bag's first message (of any topic): a block's time is that of
the first audio message plus its samples so far.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from drivers.errors import DriverError
from drivers.pcm import SAMPLE_FORMATS, decode_pcm
from drivers.source import Block, Source

#: ``.msg`` definitions of the audio_common_msgs types touchbench reads.
AUDIO_MSGS: dict[str, str] = {
    "audio_common_msgs/msg/AudioData": "uint8[] data\n",
    "audio_common_msgs/msg/AudioDataStamped": (
        "std_msgs/Header header\naudio_common_msgs/AudioData audio\n"
    ),
    "audio_common_msgs/msg/AudioInfo": (
        "uint8 channels\nuint32 sample_rate\nstring sample_format\nuint32 bitrate\n"
        "string coding_format\n"
    ),
}
_INFO_FIELDS = {
    "channels": "uint8",
    "sample_rate": "uint32",
    "sample_format": "string",
    "coding_format": "string",
}


def audio_typestore() -> Any:
    """ROS 2 Humble's standard types plus the audio types, from their ``.msg`` text."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types: dict[str, Any] = {}
    for name, text in AUDIO_MSGS.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


class RosbagSource(Source):
    """The audio of one topic of a ROS bag, one block per message.

    Parameters
    ----------
    path : str or Path
        ``.bag`` (ROS 1), ``.mcap`` / ``.db3`` or a ROS 2 bag folder.
    topic : str, optional
        The audio topic; needed when the bag has several.

    Attributes
    ----------
    start_time : float
        Seconds from the bag's first message to the first audio message.
    sample_format : str
    """

    def __init__(self, path: str | Path, *, topic: str | None = None) -> None:
        from rosbags.highlevel import AnyReader

        self.path = Path(path)
        self.name = str(path)
        try:
            self._reader = AnyReader([self.path], default_typestore=audio_typestore())
            self._reader.open()
        except Exception as error:  # rosbags raises many kinds for damaged files
            raise DriverError(f"{path}: cannot read as a ROS bag: {_reason(error)}") from None
        _register_missing(self._reader.typestore)
        try:
            self._connection = self._audio_connection(topic)
            self._read_info()
        except BaseException:
            self.close()
            raise

    def _audio_connection(self, topic: str | None) -> Any:
        connections = self._reader.connections
        audio = [c for c in connections if self._kind(c.msgtype) in ("data", "stamped")]
        listing = ", ".join(f"{c.topic} ({c.msgtype})" for c in connections) or "none"
        if topic is None:
            topics = sorted({c.topic for c in audio})
            if not topics:
                raise DriverError(
                    f"{self.name}: no audio topic (audio_common_msgs AudioData or "
                    f"AudioDataStamped with 'uint8[] data'); its topics: {listing}"
                )
            if len(topics) > 1:
                raise DriverError(
                    f"{self.name}: several audio topics ({', '.join(topics)}); choose one "
                    "as `topic`"
                )
            topic = topics[0]
        chosen = [c for c in connections if c.topic == topic]
        if not chosen:
            raise DriverError(
                f"{self.name}: no topic '{topic}'; audio topics: "
                f"{', '.join(sorted({c.topic for c in audio})) or 'none'}"
            )
        found = [c for c in chosen if c in audio]
        if not found:
            fields = ", ".join(name for name, _ in self._fields(chosen[0].msgtype))
            raise DriverError(
                f"{self.name}: topic '{topic}' is {chosen[0].msgtype} with fields ({fields}), "
                "not audio_common_msgs audio (AudioData 'uint8[] data', or AudioDataStamped)"
            )
        return found[0]

    def _read_info(self) -> None:
        infos = [c for c in self._reader.connections if self._kind(c.msgtype) == "info"]
        if len(infos) > 1:
            namespace = self._connection.topic.rsplit("/", 1)[0]
            near = [c for c in infos if c.topic.rsplit("/", 1)[0] == namespace]
            infos = near if len(near) == 1 else infos
        if not infos:
            raise DriverError(
                f"{self.name}: no AudioInfo topic, so the sample rate, channels and sample "
                "format of the audio are unknown; record the audio_info topic with the audio"
            )
        if len(infos) > 1:
            raise DriverError(
                f"{self.name}: several AudioInfo topics ({', '.join(c.topic for c in infos)}) "
                f"and none beside '{self._connection.topic}'"
            )
        try:
            message = next(iter(self._reader.messages(connections=infos)), None)
            if message is None:
                raise DriverError(f"{self.name}: the AudioInfo topic {infos[0].topic} is empty")
            info: Any = self._reader.deserialize(message[2], infos[0].msgtype)
            first = next(iter(self._reader.messages(connections=[self._connection])), None)
        except DriverError:
            raise
        except Exception as error:
            raise DriverError(f"{self.name}: cannot read the ROS bag: {_reason(error)}") from None
        coding = str(info.coding_format).strip().lower()
        if coding != "wave":
            raise DriverError(
                f"{self.name}: topic '{self._connection.topic}' carries "
                f"{info.coding_format or '?'}-coded audio; touchbench reads raw PCM only "
                "(coding_format wave): record with audio_capture's format:=wave"
            )
        sample_format = str(info.sample_format).strip().upper()
        if sample_format not in SAMPLE_FORMATS:
            raise DriverError(
                f"{self.name}: sample_format '{info.sample_format}' is not one of "
                f"{', '.join(SAMPLE_FORMATS)}"
            )
        if int(info.channels) < 1 or int(info.sample_rate) < 1:
            raise DriverError(
                f"{self.name}: AudioInfo gives {info.channels} channels at {info.sample_rate} Hz"
            )
        if first is None:
            raise DriverError(
                f"{self.name}: the audio topic '{self._connection.topic}' has no messages"
            )
        self.sample_format = sample_format
        self.n_channels = int(info.channels)
        self.samplerate = float(info.sample_rate)
        self.start_time = (first[1] - self._reader.start_time) / 1e9

    def blocks(self) -> Iterator[Block]:
        stamped = self._kind(self._connection.msgtype) == "stamped"
        position = 0
        try:
            for number, (_, _, raw) in enumerate(
                self._reader.messages(connections=[self._connection]), 1
            ):
                message: Any = self._reader.deserialize(raw, self._connection.msgtype)
                data = np.asarray((message.audio if stamped else message).data, dtype=np.uint8)
                try:
                    samples = decode_pcm(
                        data, channels=self.n_channels, sample_format=self.sample_format
                    )
                except DriverError as error:
                    raise DriverError(
                        f"{self.name}: message {number} on '{self._connection.topic}': {error}"
                    ) from None
                yield Block(samples, self.start_time + position / self.samplerate)
                position += samples.shape[1]
        except DriverError:
            raise
        except Exception as error:
            raise DriverError(
                f"{self.name}: cannot read the ROS bag after {position} samples "
                f"(truncated or damaged?): {_reason(error)}"
            ) from None

    def close(self) -> None:
        reader = getattr(self, "_reader", None)
        if reader is not None and reader.stack is not None:
            reader.close()

    def _fields(self, msgtype: str) -> list[tuple[str, Any]]:
        definition = self._reader.typestore.fielddefs.get(msgtype)
        return list(definition[1]) if definition else []

    def _kind(self, msgtype: str) -> str | None:
        """``data``, ``stamped`` or ``info`` by the type's definition; None otherwise."""
        fields = dict(self._fields(msgtype))
        if list(fields) == ["data"] and _is_byte_sequence(fields["data"]):
            return "data"
        if list(fields) == ["header", "audio"] and fields["audio"][0].name == "NAME":
            return "stamped" if self._kind(fields["audio"][1]) == "data" else None
        base = {
            name: spec[1][0]
            for name, spec in fields.items()
            if spec[0].name == "BASE" and isinstance(spec[1], tuple)
        }
        if all(base.get(name) == kind for name, kind in _INFO_FIELDS.items()):
            return "info"
        return None


def _register_missing(store: Any) -> None:
    """Register the audio types (and the types they use) that the bag does not define."""
    ours = audio_typestore().fielddefs
    needed = [*AUDIO_MSGS, "std_msgs/msg/Header", "builtin_interfaces/msg/Time"]
    missing = {name: ours[name] for name in needed if name not in store.fielddefs}
    if missing:
        store.register(missing)


def _is_byte_sequence(spec: Any) -> bool:
    kind, details = spec
    if kind.name not in ("SEQUENCE", "ARRAY"):
        return False
    inner = details[0]
    return bool(inner[0].name == "BASE" and inner[1][0] in ("uint8", "char", "byte"))


def _reason(error: BaseException) -> str:
    text = " ".join(str(error).split()) or type(error).__name__
    return text[:200]
