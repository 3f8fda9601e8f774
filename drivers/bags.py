"""Signals in ROS bags: ROS 1 ``.bag``, ROS 2 ``.mcap`` and ``.db3`` (file or bag folder).

:func:`open_bag_source` picks what to read from a bag: the audio of an audio topic
(:class:`RosbagSource`, here), or the numeric fields of any other topic as channels
(:class:`drivers.bag_fields.BagFieldsSource`).

The audio is ``audio_common_msgs`` audio: ``AudioData`` (``uint8[] data``) or
``AudioDataStamped`` (a header and an ``AudioData``), recognised by their definition, not
their name, so a same-named type of another package is not taken for audio.  Its bytes
are

* raw interleaved PCM described by an ``AudioInfo`` topic (``coding_format`` ``wave``);
* MP3 (``coding_format`` ``mp3``, audio_capture's default), decoded as a stream
  (:mod:`drivers.mp3`); MP3 carries its own rate and channels, so a bag without
  ``AudioInfo`` (older audio_capture) is read too: its first bytes are recognised as MP3;
* raw PCM without ``AudioInfo``, when ``samplerate``, ``channels`` and ``sample_format``
  are given.

Times are seconds from the bag's first message (of any topic): a block's time is that of
the first audio message plus its samples so far.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from touchbench.drivers.bag_fields import BagFieldsSource
from touchbench.drivers.bag_reader import (
    close_bag,
    field_specs,
    open_bag,
    raw_messages,
    reason,
    topic_listing,
)
from touchbench.drivers.errors import DriverError
from touchbench.drivers.limits import ReadLimits
from touchbench.drivers.mp3 import Mp3Decoder, looks_like_mp3
from touchbench.drivers.pcm import SAMPLE_FORMATS, decode_pcm
from touchbench.drivers.source import Block, Source

_INFO_FIELDS = {
    "channels": "uint8",
    "sample_rate": "uint32",
    "sample_format": "string",
    "coding_format": "string",
}
#: What ``samplerate``, ``channels`` and ``sample_format`` must all give for raw PCM.
PCM_OPTIONS = ("samplerate", "channels", "sample_format")
#: Decoded samples per block of MP3 audio.
MP3_BLOCK = 16384


def open_bag_source(
    path: str | Path,
    *,
    topic: str | None = None,
    fields: Sequence[str] | None = None,
    samplerate: float | None = None,
    channels: int | None = None,
    sample_format: str | None = None,
    limits: ReadLimits | None = None,
) -> Source:
    """The source a bag holds: audio, or the numeric fields of a topic.

    Parameters
    ----------
    path : str or Path
        ``.bag`` (ROS 1), ``.mcap`` / ``.db3`` or a ROS 2 bag folder.
    topic : str, optional
        The topic to read; needed when the bag has several audio topics, or to read a
        topic that is not audio.
    fields : sequence of str, optional
        Numeric fields of ``topic`` to read as channels (see
        :class:`~drivers.bag_fields.BagFieldsSource`); a topic that is not audio is read
        for its numeric fields even without them.
    samplerate : float, optional
        Audio: raw PCM's rate without ``AudioInfo`` (must agree with the bag otherwise).
        Fields: the even grid's rate (default: the median rate of the stamps).
    channels, sample_format : optional
        Raw PCM without ``AudioInfo``: channels per frame, ``S16LE``/``S32LE``/``F32LE``.
    limits : ReadLimits, optional
        The bounds of putting fields on an even grid (:func:`drivers.resample.check_grid`).
    """
    name = str(path)
    reader = open_bag(Path(path))
    try:
        connections = reader.connections
        audio = [c for c in connections if audio_kind(reader, c.msgtype) in ("data", "stamped")]
        if topic is None:
            if fields:
                raise DriverError(f"{name}: `fields` needs the `topic` they belong to")
            return RosbagSource(
                reader,
                _only_audio(audio, connections, name),
                name=name,
                samplerate=samplerate,
                channels=channels,
                sample_format=sample_format,
            )
        chosen = [c for c in connections if c.topic == topic]
        if not chosen:
            raise DriverError(
                f"{name}: no topic '{topic}'; its topics: {topic_listing(connections)}"
            )
        found = [c for c in chosen if c in audio]
        if found and not fields:
            return RosbagSource(
                reader,
                found[0],
                name=name,
                samplerate=samplerate,
                channels=channels,
                sample_format=sample_format,
            )
        audio_only = {"channels": channels, "sample_format": sample_format}
        given = [option for option, value in audio_only.items() if value is not None]
        if given:
            raise DriverError(
                f"{name}: `{given[0]}` applies to audio, and topic '{topic}' is read for its "
                "numeric fields"
            )
        return BagFieldsSource(
            reader, chosen[0], name=name, fields=fields, samplerate=samplerate, limits=limits
        )
    except BaseException:
        close_bag(reader)
        raise


def _only_audio(audio: list[Any], connections: list[Any], name: str) -> Any:
    topics = sorted({c.topic for c in audio})
    if not topics:
        raise DriverError(
            f"{name}: no audio topic (audio_common_msgs AudioData or AudioDataStamped with "
            f"'uint8[] data'); its topics: {topic_listing(connections)}; choose one as "
            "`topic` to read its numeric fields"
        )
    if len(topics) > 1:
        raise DriverError(
            f"{name}: several audio topics ({', '.join(topics)}); choose one as `topic`"
        )
    return audio[0]


class RosbagSource(Source):
    """The audio of one topic of a ROS bag, block by block.

    Made by :func:`open_bag_source`, which gives it the open bag (it closes it).

    Attributes
    ----------
    start_time : float
        Seconds from the bag's first message to the first audio message.
    coding : {"wave", "mp3"}
    sample_format : str or None
        The PCM sample format (None for MP3).
    notes : list of str
        How the audio's format was found, when no ``AudioInfo`` said it.
    """

    def __init__(
        self,
        reader: Any,
        connection: Any,
        *,
        name: str,
        samplerate: float | None = None,
        channels: int | None = None,
        sample_format: str | None = None,
    ) -> None:
        self._reader = reader
        self._connection = connection
        self.name = name
        self.notes: list[str] = []
        self._mp3: Mp3Decoder | None = None
        self.coding = "wave"
        self.sample_format: str | None = None
        self._stamped = audio_kind(reader, connection.msgtype) == "stamped"
        try:
            first = next(raw_messages(reader, connection, name=name), None)
            if first is None:
                raise DriverError(f"{name}: the audio topic '{connection.topic}' has no messages")
            self.start_time = (first[0] - reader.start_time) / 1e9
            given = {"samplerate": samplerate, "channels": channels, "sample_format": sample_format}
            info = self._read_info()
            if info is None:
                self._without_info(given, self._data(first[1]))
            else:
                self._from_info(info, given)
        except BaseException:
            self.close()
            raise

    def _read_info(self) -> Any | None:
        """The bag's AudioInfo message (the one beside the audio topic if several)."""
        reader, topic = self._reader, self._connection.topic
        infos = [c for c in reader.connections if audio_kind(reader, c.msgtype) == "info"]
        if len(infos) > 1:
            namespace = topic.rsplit("/", 1)[0]
            near = [c for c in infos if c.topic.rsplit("/", 1)[0] == namespace]
            infos = near if len(near) == 1 else infos
        if not infos:
            return None
        if len(infos) > 1:
            raise DriverError(
                f"{self.name}: several AudioInfo topics ({', '.join(c.topic for c in infos)}) "
                f"and none beside '{topic}'"
            )
        message = next(raw_messages(reader, infos[0], name=self.name), None)
        if message is None:
            return None
        try:
            return reader.deserialize(message[1], infos[0].msgtype)
        except Exception as error:
            raise DriverError(f"{self.name}: cannot read its AudioInfo: {reason(error)}") from None

    def _from_info(self, info: Any, given: dict[str, Any]) -> None:
        coding = str(info.coding_format).strip().lower()
        if coding == "mp3":
            self._open_mp3(given)
            return
        if coding != "wave":
            raise DriverError(
                f"{self.name}: topic '{self._connection.topic}' carries "
                f"{info.coding_format or '?'}-coded audio; touchbench reads raw PCM "
                "(coding_format wave) and MP3"
            )
        rate, count = float(info.sample_rate), int(info.channels)
        sample_format = str(info.sample_format).strip().upper()
        if count < 1 or rate <= 0:
            raise DriverError(
                f"{self.name}: AudioInfo gives {info.channels} channels at {info.sample_rate} Hz"
            )
        found = {"samplerate": rate, "channels": count, "sample_format": sample_format}
        self._agree(found, given, "its AudioInfo")
        self._set_pcm(rate, count, sample_format)

    def _without_info(self, given: dict[str, Any], first: bytes) -> None:
        if looks_like_mp3(first):
            self._open_mp3(given)
            self.notes.append(
                f"no AudioInfo topic; '{self._connection.topic}' read as MP3 "
                f"({self.samplerate:g} Hz, {self.n_channels} channel(s), from the MP3 frames)"
            )
            return
        missing = [option for option in PCM_OPTIONS if given[option] is None]
        if missing:
            raise DriverError(
                f"{self.name}: no AudioInfo topic and the audio of '{self._connection.topic}' "
                "is not MP3, so its format is unknown: give "
                + ", ".join(f"`{option}`" for option in missing)
                + " of the raw PCM"
            )
        self._set_pcm(
            float(given["samplerate"]), int(given["channels"]), str(given["sample_format"])
        )

    def _open_mp3(self, given: dict[str, Any]) -> None:
        if given["sample_format"] is not None:
            raise DriverError(
                f"{self.name}: '{self._connection.topic}' holds MP3 audio, not raw PCM of "
                f"sample format {given['sample_format']}: leave `sample_format` out"
            )
        self._mp3 = Mp3Decoder(self._chunks, name=f"{self.name} '{self._connection.topic}'")
        found = {"samplerate": self._mp3.samplerate, "channels": self._mp3.n_channels}
        self._agree(found, given, "its MP3 frames")
        self.coding, self.sample_format = "mp3", None
        self.samplerate, self.n_channels = self._mp3.samplerate, self._mp3.n_channels

    def _set_pcm(self, samplerate: float, channels: int, sample_format: str) -> None:
        if sample_format not in SAMPLE_FORMATS:
            raise DriverError(
                f"{self.name}: sample_format '{sample_format}' is not one of "
                f"{', '.join(SAMPLE_FORMATS)}"
            )
        self.coding, self.sample_format = "wave", sample_format
        self.samplerate, self.n_channels = samplerate, channels

    def _agree(self, found: dict[str, Any], given: dict[str, Any], source: str) -> None:
        for option, value in found.items():
            wanted = given.get(option)
            if wanted is None:
                continue
            if isinstance(value, str):
                same = str(wanted).strip().upper() == value
            else:
                same = abs(float(wanted) - float(value)) <= 1e-6
            if not same:
                raise DriverError(
                    f"{self.name}: {source} give {option} {_shown(value)}, but `{option}` "
                    f"{_shown(wanted)} was given"
                )

    def _data(self, raw: bytes) -> bytes:
        message: Any = self._reader.deserialize(raw, self._connection.msgtype)
        return bytes(np.asarray((message.audio if self._stamped else message).data, np.uint8))

    def _chunks(self) -> Iterator[bytes]:
        for _, raw in raw_messages(self._reader, self._connection, name=self.name):
            yield self._data(raw)

    def blocks(self) -> Iterator[Block]:
        if self._mp3 is not None:
            position = 0
            for samples in self._mp3.blocks(MP3_BLOCK):
                yield Block(samples, self.start_time + position / self.samplerate)
                position += samples.shape[1]
            return
        assert self.sample_format is not None
        position = 0
        for number, data in enumerate(self._chunks(), 1):
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

    def close(self) -> None:
        if self._mp3 is not None:
            self._mp3.close()
        close_bag(self._reader)


def audio_kind(reader: Any, msgtype: str) -> str | None:
    """``data``, ``stamped`` or ``info`` by the type's definition; None otherwise."""
    fields = dict(field_specs(reader, msgtype))
    if list(fields) == ["data"] and _is_byte_sequence(fields["data"]):
        return "data"
    if list(fields) == ["header", "audio"] and fields["audio"][0].name == "NAME":
        return "stamped" if audio_kind(reader, fields["audio"][1]) == "data" else None
    base = {
        name: spec[1][0]
        for name, spec in fields.items()
        if spec[0].name == "BASE" and isinstance(spec[1], tuple)
    }
    if all(base.get(name) == kind for name, kind in _INFO_FIELDS.items()):
        return "info"
    return None


def _shown(value: Any) -> str:
    return f"{value:g}" if isinstance(value, int | float) else str(value)


def _is_byte_sequence(spec: Any) -> bool:
    kind, details = spec
    if kind.name not in ("SEQUENCE", "ARRAY"):
        return False
    inner = details[0]
    return bool(inner[0].name == "BASE" and inner[1][0] in ("uint8", "char", "byte"))
