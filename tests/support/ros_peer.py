"""The other side of ``touchbench ros`` in tests and perf: a ROS 1 node, in a process of
its own (rospy allows one node per process), that publishes a recording as
``audio_common_msgs/AudioData`` (raw PCM, optionally described by a latched
``AudioInfo``) or as ``std_msgs/Float32MultiArray`` taxels, and prints every
``std_msgs/String`` it hears on the touch topic.

Run as ``python -m tests.support.ros_peer SAMPLES.npy ...`` with ROS_MASTER_URI set.
SAMPLES.npy holds (n_channels, n_samples) float samples.  Stdout, JSON lines:
``{"connected": true}`` once the node under test listens and talks to us,
``{"sent": [t, ...]}`` after the last message (``time.perf_counter()`` when each publish
returned), ``{"touch": {...}, "received": t}`` per message heard.  Closing stdin ends it.
"""

from __future__ import annotations

import argparse
import json
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from touchbench.drivers.pcm import SAMPLE_FORMATS
from touchbench.drivers.ros1 import audio_types, import_rospy, master_environment

_print_lock = threading.Lock()


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@contextmanager
def rosmaster(log_dir: str, *, patience: float) -> Iterator[dict[str, str]]:
    """A rosmaster of our own on a free port; yields the environment of its nodes."""
    port = free_port()
    env = master_environment(port, log_dir)
    master = subprocess.Popen(
        ["rosmaster", "--core", "-p", str(port)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + patience
        while True:
            with socket.socket() as probe:
                if probe.connect_ex(("127.0.0.1", port)) == 0:
                    break
            if master.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError("rosmaster did not start")
            time.sleep(0.05)
        yield env
    finally:
        master.send_signal(signal.SIGINT)
        try:
            master.wait(10)
        except subprocess.TimeoutExpired:
            master.kill()
            master.wait()


class Peer:
    """This module run as a process, and the lines it prints.

    Attributes
    ----------
    touches : list of dict
        ``{"touch": ..., "received": t}`` lines, as read by :meth:`until`.
    sent : list of float
        When each message was published, once the last was.
    """

    def __init__(self, env: dict[str, str], *args: str, patience: float) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "tests.support.ros_peer", *args],
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        self.patience = patience
        self.lines: queue.Queue[dict[str, Any]] = queue.Queue()
        self.touches: list[dict[str, Any]] = []
        self.sent: list[float] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.put(json.loads(line))

    def until(self, done: Callable[[], bool]) -> None:
        """Read lines until ``done()`` holds.

        Raises
        ------
        queue.Empty
            Nothing more came for ``patience`` seconds.
        """
        while not done():
            line = self.lines.get(timeout=self.patience)
            if "touch" in line:
                self.touches.append(line)
            if "sent" in line:
                self.sent = line["sent"]

    def close(self) -> None:
        if self.process.poll() is None:
            assert self.process.stdin is not None
            self.process.stdin.close()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def say(line: dict[str, Any]) -> None:
    with _print_lock:
        sys.stdout.write(json.dumps(line) + "\n")
        sys.stdout.flush()


def payloads(samples: np.ndarray, args: argparse.Namespace) -> list[Any]:
    """The messages' data: PCM bytes per chunk, or taxel arrays per chunk."""
    chunks = [samples[:, i : i + args.chunk] for i in range(0, samples.shape[1], args.chunk)]
    if args.taxels:
        return [np.ascontiguousarray(chunk.T, dtype=np.float32) for chunk in chunks]
    dtype, scale = SAMPLE_FORMATS[args.format]
    out = []
    for chunk in chunks:
        frames = chunk.T * (scale if dtype != "<f4" else 1.0)
        if dtype != "<f4":
            frames = np.clip(np.round(frames), -scale, scale - 1)
        out.append(np.ascontiguousarray(frames, dtype=dtype).tobytes())
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("samples")
    parser.add_argument("--topic", default="/audio")
    parser.add_argument("--touch-topic", default="/touch")
    parser.add_argument("--format", default="F32LE")
    parser.add_argument("--samplerate", type=float, default=44100.0)
    parser.add_argument("--chunk", type=int, default=512)
    parser.add_argument("--info", default=None, help="Latch an AudioInfo on this topic.")
    parser.add_argument("--taxels", action="store_true", help="Float32MultiArray blocks.")
    parser.add_argument("--pace", action="store_true", help="In real time.")
    args = parser.parse_args()
    samples = np.load(args.samples)

    rospy = import_rospy()
    from std_msgs.msg import Float32MultiArray, MultiArrayDimension, String

    audio_data, audio_info = audio_types()
    rospy.init_node("peer", anonymous=True, disable_signals=True)
    subscriber = rospy.Subscriber(
        args.touch_topic,
        String,
        lambda message: say({"touch": json.loads(message.data), "received": time.perf_counter()}),
        tcp_nodelay=True,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SyntaxWarning)  # synchronous publishing, on purpose
        kind = Float32MultiArray if args.taxels else audio_data
        publisher = rospy.Publisher(args.topic, kind, tcp_nodelay=True)
    if args.info:
        latched = rospy.Publisher(args.info, audio_info, latch=True, queue_size=1)
        latched.publish(
            audio_info(
                channels=samples.shape[0],
                sample_rate=int(args.samplerate),
                sample_format=args.format,
                bitrate=0,
                coding_format="wave",
            )
        )
    while publisher.get_num_connections() < 1 or subscriber.get_num_connections() < 1:
        time.sleep(0.01)
    say({"connected": True})
    messages = []
    lengths = [
        min(args.chunk, samples.shape[1] - i) for i in range(0, samples.shape[1], args.chunk)
    ]
    for data, length in zip(payloads(samples, args), lengths, strict=True):
        if args.taxels:
            layout = [
                MultiArrayDimension(label="samples", size=data.shape[0], stride=data.size),
                MultiArrayDimension(label="taxels", size=data.shape[1], stride=data.shape[1]),
            ]
            message = Float32MultiArray(data=data.ravel().tolist())
            message.layout.dim = layout
            messages.append((message, length))
        else:
            messages.append((audio_data(data=data), length))
    sent = []
    start = time.perf_counter()
    position = 0
    for message, length in messages:
        position += length
        if args.pace:  # a message is due once its last sample has been "recorded"
            time.sleep(max(0.0, start + position / args.samplerate - time.perf_counter()))
        publisher.publish(message)
        sent.append(time.perf_counter())
    say({"sent": sent})
    sys.stdin.read()  # until the test is done listening
    rospy.signal_shutdown("done")


if __name__ == "__main__":
    main()
