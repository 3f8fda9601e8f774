"""Opening a ROS bag and naming its topics: what the audio and the numeric-field readers share.

A bag is read with the pure-Python ``rosbags`` library (no ROS install): ROS 1 ``.bag``,
ROS 2 ``.mcap`` and ``.db3`` files or bag folders.  Message types are those the bag
carries (their definitions are in the bag: rosbags builds its type store from them);
types a bag uses without carrying them (older rosbag2) come from ROS 2 Humble's standard
types and the audio types of :data:`AUDIO_MSGS`.
"""

from __future__ import annotations

# Imports inside functions: rosbags loads only when a bag is read, so that commands that
# never read one start without it.
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from touchbench.drivers.errors import DriverError

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

#: Topics named in a message that lists a bag's topics.
SHOWN_TOPICS = 6


def audio_typestore() -> Any:
    """ROS 2 Humble's standard types plus the audio types, from their ``.msg`` text."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types: dict[str, Any] = {}
    for name, text in AUDIO_MSGS.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def open_bag(path: Path) -> Any:
    """An open ``rosbags.highlevel.AnyReader`` of the bag at ``path``.

    Raises
    ------
    DriverError
        The file is not a bag rosbags can read (damaged, truncated, another format).
    """
    from rosbags.highlevel import AnyReader

    try:
        reader = AnyReader([path], default_typestore=audio_typestore())
        reader.open()
    except Exception as error:  # rosbags raises many kinds for damaged files
        raise DriverError(f"{path}: cannot read as a ROS bag: {reason(error)}") from None
    _register_missing(reader.typestore)
    return reader


def close_bag(reader: Any) -> None:
    """Close ``reader`` if it is open (safe to call twice)."""
    if reader is not None and reader.stack is not None:
        reader.close()


def topic_listing(connections: list[Any]) -> str:
    """``/a (pkg/msg/A), /b (pkg/msg/B) and 3 more``: a few topics with their types."""
    topics = sorted({(c.topic, c.msgtype) for c in connections})
    shown = ", ".join(f"{topic} ({msgtype})" for topic, msgtype in topics[:SHOWN_TOPICS])
    more = len(topics) - SHOWN_TOPICS
    return (shown + (f" and {more} more" if more > 0 else "")) or "none"


def field_specs(reader: Any, msgtype: str) -> list[tuple[str, Any]]:
    """``[(name, (node type, details)), ...]`` of ``msgtype`` in the bag's type store."""
    definition = reader.typestore.fielddefs.get(msgtype)
    return list(definition[1]) if definition else []


def raw_messages(reader: Any, connection: Any, *, name: str) -> Iterator[tuple[int, bytes]]:
    """``(receive time in ns, serialized message)`` of one connection, in order.

    Raises
    ------
    DriverError
        The bag cannot be read on (truncated or damaged), naming how far it got.
    """
    count = 0
    try:
        for _, stamp, raw in reader.messages(connections=[connection]):
            yield stamp, raw
            count += 1
    except DriverError:
        raise
    except Exception as error:
        raise DriverError(
            f"{name}: cannot read the ROS bag after {count} message(s) on "
            f"'{connection.topic}' (truncated or damaged?): {reason(error)}"
        ) from None


def reason(error: BaseException) -> str:
    """An error of a library underneath, in one short line."""
    text = " ".join(str(error).split()) or type(error).__name__
    return text[:200]


def _register_missing(store: Any) -> None:
    """Register the audio types (and the types they use) that the bag does not define."""
    ours = audio_typestore().fielddefs
    needed = [*AUDIO_MSGS, "std_msgs/msg/Header", "builtin_interfaces/msg/Time"]
    missing = {name: ours[name] for name in needed if name not in store.fielddefs}
    if missing:
        store.register(missing)
