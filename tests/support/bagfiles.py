"""Writing real ROS bags with rosbags' own writers, for the bag reading tests."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import soundfile

from touchbench.drivers.bag_reader import audio_typestore
from touchbench.drivers.mp3 import frame_length
from touchbench.drivers.pcm import SAMPLE_FORMATS

#: A same-named AudioData of another package (the ROS 2 'audio_common' of mgonzs13).
OTHER_AUDIO_DATA = (
    "float32[] float32_data\nint32[] int32_data\nint16[] int16_data\nint8[] int8_data\n"
    "uint8[] uint8_data\n"
)


def encode(samples: np.ndarray, sample_format: str) -> np.ndarray:
    """(n_channels, n) full-scale samples as interleaved PCM bytes, uint8."""
    dtype, scale = SAMPLE_FORMATS[sample_format]
    frames = samples.T * scale
    if dtype != "<f4":
        frames = np.clip(np.round(frames), np.iinfo(dtype).min, np.iinfo(dtype).max)
    return np.ascontiguousarray(frames.astype(dtype)).view(np.uint8).reshape(-1)


def write_audio_bag(
    path: Path,
    samples: np.ndarray,
    samplerate: int,
    *,
    sample_format: str = "S16LE",
    coding_format: str = "wave",
    stamped: bool = False,
    message_samples: int = 1024,
    topic: str | None = "/audio/audio",
    info_topic: str | None = "/audio/audio_info",
    audio_delay: float = 0.25,
    extra_topic: bool = True,
    with_definitions: bool = True,
    twin_topic: str | None = None,
    payloads: list[bytes] | None = None,
    channels: int | None = None,
) -> Path:
    """A bag at ``path`` (.bag: ROS 1; .mcap or .db3: a ROS 2 bag folder of that storage)
    holding ``samples`` on ``topic`` (and on ``twin_topic`` too, if given); the first
    message, on ``/status``, comes ``audio_delay`` seconds before the audio.  With
    ``payloads`` (encoded audio, e.g. MP3 pieces), those are the messages' data instead,
    one every ``message_samples`` samples, and AudioInfo says ``channels``."""
    store = audio_typestore()
    types = store.types
    ros1 = path.suffix == ".bag"
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    start = 1_700_000_000 * 10**9
    data_type = (
        "audio_common_msgs/msg/AudioDataStamped" if stamped else ("audio_common_msgs/msg/AudioData")
    )
    writer = _writer(path)
    with writer as bag:  # type: ignore[attr-defined]
        audio = None if topic is None else bag.add_connection(topic, data_type, typestore=store)
        twin = None
        if twin_topic is not None:
            twin = bag.add_connection(twin_topic, data_type, typestore=store)
        if extra_topic:
            status = bag.add_connection("/status", "std_msgs/msg/String", typestore=store)
            bag.write(
                status,
                start,
                serialize(types["std_msgs/msg/String"](data="up"), "std_msgs/msg/String"),
            )
        if info_topic is not None:
            info = bag.add_connection(
                info_topic, "audio_common_msgs/msg/AudioInfo", typestore=store
            )
            message = types["audio_common_msgs/msg/AudioInfo"](
                channels=channels or samples.shape[0],
                sample_rate=samplerate,
                sample_format=sample_format,
                bitrate=0,
                coding_format=coding_format,
            )
            bag.write(info, start + 1, serialize(message, "audio_common_msgs/msg/AudioInfo"))
        first = start + round(audio_delay * 1e9)
        chunks = (
            [np.frombuffer(data, dtype=np.uint8) for data in payloads]
            if payloads is not None
            else [
                encode(samples[:, begin : begin + message_samples], sample_format)
                for begin in range(0, samples.shape[1], message_samples)
            ]
        )
        for number, chunk in enumerate(chunks if audio is not None else []):
            begin = number * message_samples
            payload = types["audio_common_msgs/msg/AudioData"](data=chunk)
            stamp = first + round(begin / samplerate * 1e9)
            if stamped:
                header = types["std_msgs/msg/Header"](
                    stamp=types["builtin_interfaces/msg/Time"](
                        sec=stamp // 10**9, nanosec=stamp % 10**9
                    ),
                    frame_id="mic",
                )
                payload = types[data_type](header=header, audio=payload)
            bag.write(audio, stamp, serialize(payload, data_type))
            if twin is not None:
                bag.write(twin, stamp, serialize(payload, data_type))
    if ros1:
        return path
    folder = path.with_suffix("")
    if not with_definitions:  # as an older rosbag2 wrote it: no audio type definitions
        assert path.suffix == ".db3", "only the .db3 storage is rewritten here"
        import sqlite3

        with sqlite3.connect(folder / path.name) as database:
            database.execute(
                "DELETE FROM message_definitions WHERE topic_type LIKE 'audio_common_msgs/%'"
            )
    return folder


def write_other_audio_bag(path: Path) -> Path:
    """A ROS 2 .mcap bag whose topic /audio has a type named
    ``audio_common_msgs/msg/AudioData`` but another package's definition."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg(OTHER_AUDIO_DATA, "audio_common_msgs/msg/AudioData"))
    kind = store.types["audio_common_msgs/msg/AudioData"]
    folder = path.with_suffix("")
    with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as bag:
        audio = bag.add_connection("/audio", "audio_common_msgs/msg/AudioData", typestore=store)
        empty = {
            name: np.zeros(0, dtype=dtype)
            for name, dtype in (
                ("float32_data", np.float32),
                ("int32_data", np.int32),
                ("int8_data", np.int8),
                ("uint8_data", np.uint8),
            )
        }
        message = kind(int16_data=np.zeros(512, dtype=np.int16), **empty)
        bag.write(audio, 1, store.serialize_cdr(message, "audio_common_msgs/msg/AudioData"))
    return folder


def mp3_stream(samples: np.ndarray, samplerate: int, *, variable: bool = False) -> bytes:
    """``samples`` (n_channels, n) as the MP3 bytes audio_capture streams: libsndfile's
    MP3 without its first frame, the Xing/Info header a file has and a stream has not."""
    buffer = io.BytesIO()
    with soundfile.SoundFile(
        buffer,
        "w",
        samplerate,
        samples.shape[0],
        format="MP3",
        subtype="MPEG_LAYER_III",
        bitrate_mode="VARIABLE" if variable else "CONSTANT",
        compression_level=0.5,
    ) as mp3:
        mp3.write(samples.T)
    data = buffer.getvalue()
    header = data[:64]
    assert b"Xing" in header or b"Info" in header, "libsndfile wrote no Xing/Info frame"
    return data[frame_length(data[:4]) or 0 :]


def pieces(data: bytes, size: int) -> list[bytes]:
    """``data`` cut into messages of ``size`` bytes (the last one shorter)."""
    return [data[begin : begin + size] for begin in range(0, len(data), size)]


#: A BioTac-like message of a package of our own: a header, numbers, arrays, a string.
BIOTAC_TYPE = "touchbench_test_msgs/msg/BioTacLike"
BIOTAC_MSG = (
    "std_msgs/Header header\nuint16 pdc\nuint16 tdc\nint16[22] pac\nuint16[19] electrodes\n"
    "string sensor\n"
)


def write_fields_bag(
    path: Path,
    *,
    msgtype: str,
    messages: list[dict],
    received: np.ndarray,
    topic: str = "/sensor",
    definition: str | None = None,
) -> Path:
    """A bag whose ``topic`` holds ``messages`` of ``msgtype`` (keyword values; a
    ``stamp`` entry in ns becomes the header's stamp), received at ``received`` (seconds
    after the bag's first message, on ``/status``, at 0)."""
    store = audio_typestore()
    if definition is not None:
        from rosbags.typesys import get_types_from_msg

        store.register(get_types_from_msg(definition, msgtype))
    types = store.types
    ros1 = path.suffix == ".bag"
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    start = 1_700_000_000 * 10**9
    writer = _writer(path)
    with writer as bag:  # type: ignore[attr-defined]
        status = bag.add_connection("/status", "std_msgs/msg/String", typestore=store)
        bag.write(
            status, start, serialize(types["std_msgs/msg/String"](data="up"), "std_msgs/msg/String")
        )
        connection = bag.add_connection(topic, msgtype, typestore=store)
        for values, seconds in zip(messages, received, strict=True):
            values = dict(values)
            if "stamp" in values:
                stamp = int(values.pop("stamp"))
                values["header"] = types["std_msgs/msg/Header"](
                    stamp=types["builtin_interfaces/msg/Time"](
                        sec=stamp // 10**9, nanosec=stamp % 10**9
                    ),
                    frame_id="finger",
                )
            message = types[msgtype](**values)
            bag.write(connection, start + round(seconds * 1e9), serialize(message, msgtype))
    return path if ros1 else path.with_suffix("")


def float_array(values: np.ndarray) -> dict:
    """Keyword values of a ``std_msgs/msg/Float32MultiArray`` holding ``values``."""
    from rosbags.typesys.stores.ros2_humble import (
        std_msgs__msg__MultiArrayDimension as Dimension,
    )
    from rosbags.typesys.stores.ros2_humble import std_msgs__msg__MultiArrayLayout as Layout

    layout = Layout(
        dim=[Dimension(label="taxels", size=values.size, stride=values.size)], data_offset=0
    )
    return {"layout": layout, "data": np.asarray(values, dtype=np.float32)}


def _writer(path: Path) -> object:
    if path.suffix == ".bag":
        from rosbags.rosbag1 import Writer as Writer1

        return Writer1(path)
    from rosbags.rosbag2 import StoragePlugin, Writer

    plugin = StoragePlugin.MCAP if path.suffix == ".mcap" else StoragePlugin.SQLITE3
    return Writer(path.with_suffix(""), version=9, storage_plugin=plugin)
