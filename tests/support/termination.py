"""A pytest plugin: SIGTERM ends the session as Ctrl-C does, so fixtures still tear down.

Without it, ``kill PID`` (a CI timeout, a closed terminal) ends pytest at once and every
fixture-owned process (a test's uvicorn service, its dask cluster, job workers) started in a
session of its own keeps running.  Loaded by ``tests/conftest.py``.
"""

from __future__ import annotations

import signal
from types import FrameType

import pytest


def _interrupt(signum: int, frame: FrameType | None) -> None:
    raise KeyboardInterrupt(f"pytest received signal {signal.Signals(signum).name}")


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config: pytest.Config) -> None:
    signal.signal(signal.SIGTERM, _interrupt)
