"""Writing real ROS bags with rosbags' own writers, for the bag reading tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drivers.bags import audio_typestore
from drivers.pcm import SAMPLE_FORMATS

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
) -> Path:
    """A bag at ``path`` (.bag: ROS 1; .mcap or .db3: a ROS 2 bag folder of that storage)
    holding ``samples`` on ``topic`` (and on ``twin_topic`` too, if given); the first
    message, on ``/status``, comes ``audio_delay`` seconds before the audio."""
    store = audio_typestore()
    types = store.types
    ros1 = path.suffix == ".bag"
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    start = 1_700_000_000 * 10**9
    data_type = (
        "audio_common_msgs/msg/AudioDataStamped" if stamped else ("audio_common_msgs/msg/AudioData")
    )
    if ros1:
        from rosbags.rosbag1 import Writer as Writer1

        writer: object = Writer1(path)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = StoragePlugin.MCAP if path.suffix == ".mcap" else StoragePlugin.SQLITE3
        writer = Writer(path.with_suffix(""), version=9, storage_plugin=plugin)
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
                channels=samples.shape[0],
                sample_rate=samplerate,
                sample_format=sample_format,
                bitrate=0,
                coding_format=coding_format,
            )
            bag.write(info, start + 1, serialize(message, "audio_common_msgs/msg/AudioInfo"))
        first = start + round(audio_delay * 1e9)
        for begin in range(0, samples.shape[1] if audio is not None else 0, message_samples):
            chunk = encode(samples[:, begin : begin + message_samples], sample_format)
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
