"""ROS 1 from Debian's packages inside the venv: only the ROS packages come from there,
and audio_common's messages carry the MD5 sums real audio_common nodes check."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from touchbench.drivers.ros1 import DEBIAN_PACKAGES
from touchbench.drivers.ros_transport import AUDIO_DATA, AUDIO_INFO

pytestmark = pytest.mark.skipif(
    not Path(DEBIAN_PACKAGES, "rospy").is_dir(),
    reason="ROS 1 is not installed (Debian's python3-rospy: scripts/install.sh installs it)",
)

SCRIPT = """
import sys
from touchbench.drivers.ros1 import DEBIAN_PACKAGES, audio_types, import_rospy
import_rospy()
data, info = audio_types()
import numpy, yaml
print(data._md5sum, info._md5sum, data._type, info._type)
print(DEBIAN_PACKAGES in sys.path)
print(numpy.__file__.startswith(DEBIAN_PACKAGES), yaml.__file__.startswith(DEBIAN_PACKAGES))
import rospy
print(rospy.__file__.startswith(DEBIAN_PACKAGES))
try:
    import apt  # a Debian package that is not ROS's stays out of reach
    print("apt reachable")
except ImportError:
    print("apt unreachable")
"""


def test_only_ros_comes_from_debian_and_the_md5_sums_are_audio_commons() -> None:
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    assert out[0].split() == [AUDIO_DATA[2], AUDIO_INFO[2], AUDIO_DATA[0], AUDIO_INFO[0]]
    assert out[0].split()[:2] == [
        "f43a8e1b362b75baa741461b46adc7e0",
        "9413d9b7029680d3b1db6ed0ae535f88",
    ]
    assert out[1:] == ["False", "False False", "True", "apt unreachable"]
