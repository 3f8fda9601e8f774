"""The sound card driver's refusals (PortAudio is queried; no device is opened)."""

from __future__ import annotations

import pytest

from touchbench.drivers.errors import DriverError
from touchbench.drivers.sound import find_device


def test_an_unknown_device_points_to_the_listing_not_a_command() -> None:
    with pytest.raises(DriverError) as error:
        find_device("no-such-card")
    assert str(error.value) == (
        "no capture device 'no-such-card' (the device listing shows those PortAudio sees)"
    )
