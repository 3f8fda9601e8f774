"""ROS 1 (rospy) as a :class:`~drivers.ros_transport.RosTransport`.

rospy comes from Debian's packages (``python3-rospy``, ``python3-genpy``, ``ros-core``;
``scripts/install.sh`` installs them): Python 3.11 system packages in
``/usr/lib/python3/dist-packages``, outside touchbench's virtual environment.  Putting
that folder on ``sys.path`` would let every import the venv cannot answer fall through
to Debian's copies, and Debian's numpy or PyYAML, built for the system's interpreter,
would shadow nothing today but answer whatever the venv lacks tomorrow.  Instead
:func:`import_rospy` adds an import finder that answers only for the ROS 1 packages
named in :data:`ROS_PACKAGES`, and only when this module is used: everything else
rospy imports (``yaml``) is the venv's, and no other command sees Debian's folder at
all.  The ROS packages are pure Python, so the venv's interpreter runs them.

``audio_common_msgs`` is not packaged by Debian: its ``AudioData`` and ``AudioInfo`` are
generated at run time with :func:`genpy.dynamic.generate_dynamic` from the definitions
in :mod:`drivers.ros_transport`, whose MD5 sums are checked against the real ones, so an
``audio_capture`` node on the robot connects to ours.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import os
import queue
import sys
import threading
import time
import warnings
from collections.abc import Iterator, Sequence
from types import ModuleType
from typing import Any

import numpy as np

from touchbench.drivers.errors import DriverError
from touchbench.drivers.ros_transport import AUDIO_DATA, AUDIO_INFO, AudioFormat, Kind, Message

#: Where Debian installs its Python packages (ROS 1's among them).
DEBIAN_PACKAGES = "/usr/lib/python3/dist-packages"
#: The top-level packages rospy and its messages need, and nothing else of Debian's.
ROS_PACKAGES = frozenset(
    {
        "rospy",
        "rosgraph",
        "rosgraph_msgs",
        "roslib",
        "rospkg",
        "roscpp",  # its logger services, which rospy serves
        "genpy",
        "genmsg",
        "catkin",
        "catkin_pkg",
        "std_msgs",
    }
)
#: Seconds between two checks of a closed transport while waiting for a message.
POLL = 0.1


class _RosPackages(importlib.abc.MetaPathFinder):
    """Finds the packages of :data:`ROS_PACKAGES` (and only those) in Debian's folder."""

    def __init__(self, folder: str) -> None:
        self.folder = folder

    def find_spec(
        self, fullname: str, path: Sequence[str] | None = None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in ROS_PACKAGES:  # submodules are found through their package
            return None
        return importlib.machinery.PathFinder.find_spec(fullname, [self.folder])


def import_rospy(folder: str = DEBIAN_PACKAGES) -> ModuleType:
    """rospy, from the venv if it has one, else from Debian's packages.

    Raises
    ------
    DriverError
        Neither has it: what to install.
    """
    if not any(isinstance(finder, _RosPackages) for finder in sys.meta_path):
        sys.meta_path.append(_RosPackages(folder))  # after the venv's own finders
    try:
        import rospy
    except ImportError as error:
        raise DriverError(
            f"ROS 1 is not installed ({error}): install Debian's ros-core, python3-rospy and "
            "python3-genpy (scripts/install.sh does)"
        ) from None
    return rospy


def audio_types() -> tuple[type, type]:
    """``AudioData`` and ``AudioInfo`` of audio_common_msgs, as genpy message classes."""
    import_rospy()
    import genpy.dynamic

    classes = []
    for name, definition, md5 in (AUDIO_DATA, AUDIO_INFO):
        made = genpy.dynamic.generate_dynamic(name, definition)[name]
        if made._md5sum != md5:  # would be refused by every real audio_common node
            raise DriverError(f"{name}: generated MD5 {made._md5sum}, ROS's is {md5}")
        classes.append(made)
    return classes[0], classes[1]


def _taxels(message: Any) -> np.ndarray:
    values = np.asarray(message.data, dtype=np.float32)
    dims = message.layout.dim
    if len(dims) == 2 and dims[0].size * dims[1].size == values.size:
        return values.reshape(dims[0].size, dims[1].size)  # a block: samples outer
    return values


class Ros1Transport:
    """A rospy node (anonymous, named ``name_<pid>_<time>``) on the master of
    ``ROS_MASTER_URI``.

    Parameters
    ----------
    name : str
        Base name of the node.
    master_timeout : float
        Seconds to wait for the master before giving up.

    Raises
    ------
    DriverError
        ROS 1 is not installed, or no master answers.
    """

    def __init__(self, name: str = "touchbench", *, master_timeout: float = 3.0) -> None:
        rospy = import_rospy()
        import rosgraph

        uri = rosgraph.get_master_uri()
        deadline = time.monotonic() + master_timeout
        while not rosgraph.is_master_online(uri):
            if time.monotonic() > deadline:
                raise DriverError(
                    f"no ROS master answers at {uri}: start roscore, or set ROS_MASTER_URI"
                )
            time.sleep(0.1)
        # Signals stay ours (the CLI's interrupt handling); rospy's own would end the node
        # from a handler without letting the command publish its last touches.
        rospy.init_node(name, anonymous=True, disable_signals=True)
        self._rospy = rospy
        self._audio_data, self._audio_info = audio_types()
        from std_msgs.msg import Float32MultiArray, String

        self._string = String
        self._taxel_type = Float32MultiArray
        self._publisher: Any = None
        self._subscribers: list[Any] = []
        self._stopped = threading.Event()
        self._closed = False

    def audio_info(self, topic: str, *, timeout: float) -> AudioFormat | None:
        got: queue.Queue[Any] = queue.Queue()
        subscriber = self._rospy.Subscriber(topic, self._audio_info, got.put)
        deadline = time.monotonic() + timeout
        try:
            while True:
                try:
                    info = got.get(timeout=min(POLL, max(0.0, deadline - time.monotonic())))
                    break
                except queue.Empty:
                    if self._stopped.is_set() or time.monotonic() >= deadline:
                        return None
        finally:
            subscriber.unregister()
        return AudioFormat(
            channels=int(info.channels),
            samplerate=float(info.sample_rate),
            sample_format=str(info.sample_format).strip().upper(),
            coding=str(info.coding_format).strip().lower(),
        )

    def subscribe(self, topic: str, kind: Kind) -> Iterator[Message]:
        received: queue.Queue[Message] = queue.Queue()  # unbounded: no message dropped

        if kind == "audio":

            def take(message: Any) -> None:
                received.put(Message(bytes(message.data), time.perf_counter()))

            data_class = self._audio_data
        else:

            def take(message: Any) -> None:
                received.put(Message(_taxels(message), time.perf_counter()))

            data_class = self._taxel_type
        # rospy's own queue unbounded too; tcp_nodelay: each message leaves at once.
        self._subscribers.append(self._rospy.Subscriber(topic, data_class, take, tcp_nodelay=True))
        return self._messages(received)

    def _messages(self, received: queue.Queue[Message]) -> Iterator[Message]:
        while not self._stopped.is_set() and not self._rospy.is_shutdown():
            try:
                yield received.get(timeout=POLL)
            except queue.Empty:
                continue
        # What came before the stop is still processed; what comes after (a microphone
        # never stops) is not waited for.
        for _ in range(received.qsize()):
            yield received.get_nowait()

    def stop(self) -> None:
        self._stopped.set()

    def advertise(self, topic: str) -> None:
        with warnings.catch_warnings():
            # Without queue_size rospy publishes synchronously, which is what we want (a
            # touch is on the wire when publish returns), and warns that we did so.
            warnings.simplefilter("ignore", SyntaxWarning)
            self._publisher = self._rospy.Publisher(topic, self._string, tcp_nodelay=True)

    def publish(self, text: str) -> None:
        if self._publisher is None:
            raise DriverError("publish before advertise")
        self._publisher.publish(self._string(data=text))

    def wait_for_subscribers(self, count: int = 1, *, timeout: float) -> bool:
        """True once ``count`` nodes subscribe to the advertised topic (for tests and
        tools that must not publish into the void)."""
        deadline = time.monotonic() + timeout
        while self._publisher.get_num_connections() < count:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.01)
        return True

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._stopped.set()
        for subscriber in self._subscribers:
            subscriber.unregister()
        if self._publisher is not None:
            self._publisher.unregister()
        self._rospy.signal_shutdown("touchbench ros stopped")


def master_environment(port: int, log_dir: str) -> dict[str, str]:
    """Environment variables for a node of a master on ``127.0.0.1:port`` (tests, perf)."""
    return {
        **os.environ,
        "ROS_MASTER_URI": f"http://127.0.0.1:{port}",
        "ROS_HOSTNAME": "127.0.0.1",
        "ROS_LOG_DIR": log_dir,
        "ROS_HOME": log_dir,
    }
