"""What a ROS node needs of a ROS middleware: topics in, JSON text out.

The node (``touchbench ros``) is written against :class:`RosTransport`, so that it runs
on ROS 1 (:mod:`drivers.ros1`, rospy from Debian's packages) and a ROS 2 transport
(rclpy) can be added beside it without touching the node: subscribe to a topic of audio
or taxels and iterate its messages (the iteration blocks until the next one), read the
format of the audio from an ``AudioInfo`` topic, publish one ``std_msgs/String`` per
touch.

audio_common's messages are not packaged by Debian; their definitions are here, with the
MD5 sums ROS 1 checks when two nodes connect (a publisher of ``audio_capture`` and our
subscriber must agree on them), so each transport can define the types at run time.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

#: ``audio_common_msgs/AudioData``: bytes of raw PCM (interleaved) or of an MP3 stream.
AUDIO_DATA = ("audio_common_msgs/AudioData", "uint8[] data\n", "f43a8e1b362b75baa741461b46adc7e0")
#: ``audio_common_msgs/AudioInfo``: the format of an ``AudioData`` topic (latched).
AUDIO_INFO = (
    "audio_common_msgs/AudioInfo",
    "uint8 channels\nuint32 sample_rate\nstring sample_format\nuint32 bitrate\n"
    "string coding_format\n",
    "9413d9b7029680d3b1db6ed0ae535f88",
)

#: What a subscription carries: audio (``AudioData``) or taxels (``Float32MultiArray``).
Kind = Literal["audio", "taxels"]


@dataclass(frozen=True)
class AudioFormat:
    """An ``AudioInfo`` message.

    Attributes
    ----------
    channels : int
    samplerate : float
        Hz.
    sample_format : str
        ``S16LE``, ``S32LE`` or ``F32LE`` for raw PCM (upper case); MP3 carries its own.
    coding : str
        ``wave`` (raw PCM) or ``mp3`` (lower case).
    """

    channels: int
    samplerate: float
    sample_format: str
    coding: str


@dataclass(frozen=True)
class Message:
    """One message of a subscribed topic.

    Attributes
    ----------
    data : bytes or ndarray
        Audio: the ``data`` bytes.  Taxels: the values, float32, of shape (n_taxels,)
        for one sample of every taxel, or (n_samples, n_taxels) for a block, as the
        message's ``layout`` (two dimensions, samples outer) says.
    arrived : float
        ``time.perf_counter()`` when the transport handed the message over.
    """

    data: bytes | np.ndarray
    arrived: float


class RosTransport(Protocol):
    """A connection of one node to a ROS graph.

    Methods block (the node has nothing else to do) and are called from one thread;
    ``stop`` may come from a signal's handler and ends the iterations and waits.
    """

    def audio_info(self, topic: str, *, timeout: float) -> AudioFormat | None:
        """The first ``AudioInfo`` on ``topic`` within ``timeout`` seconds, else None."""
        ...

    def subscribe(self, topic: str, kind: Kind) -> Iterator[Message]:
        """Every message of ``topic`` from now on, in order, none dropped; each ``next``
        waits for the next message.  Ends after :meth:`stop`, once the messages received
        before it are taken."""
        ...

    def stop(self) -> None:
        """End the subscriptions (see :meth:`subscribe`) and the wait for ``AudioInfo``.
        Only sets a flag, so a signal's handler may call it."""
        ...

    def advertise(self, topic: str) -> None:
        """Publish ``std_msgs/String`` messages on ``topic`` from now on."""
        ...

    def publish(self, text: str) -> None:
        """One ``std_msgs/String`` on the advertised topic, sent before this returns."""
        ...

    def close(self) -> None:
        """Leave the graph: unsubscribe, unadvertise, end the node."""
        ...
