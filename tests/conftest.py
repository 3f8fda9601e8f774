"""Fixtures shared by every test package."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest_plugins = ["tests.support.termination"]


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The tests marked ``slow`` first, each group in its own order: pytest-xdist hands the
    tests out in this order, and a slow test left to the end keeps the whole run waiting for
    one worker."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


def _running_loop() -> asyncio.AbstractEventLoop | None:
    try:
        return asyncio.get_running_loop()
    except RuntimeError:  # none running in this thread
        return None


@pytest.fixture(autouse=True)
def _no_event_loop_left_running() -> Iterator[None]:
    """A test leaves no event loop running in the test process's main thread (one that a
    wider fixture keeps running, a browser's, may run on): a later test's ``asyncio.run``
    would refuse to start ("cannot be called from a running event loop") and fail far from
    the cause."""
    before = _running_loop()
    yield
    left = _running_loop()
    if left is not None and left is not before:
        pytest.fail(f"the test left an event loop running in the main thread: {left!r}")


SHARED_DATASETS = Path(__file__).resolve().parents[1].parent / "shared" / "datasets"


@pytest.fixture(scope="session")
def shared_datasets() -> Path:
    """``../shared/datasets`` beside the repository; skips the test where it is absent."""
    if not (SHARED_DATASETS / "uc3m-touch").is_dir():
        pytest.skip(
            f"needs the reference datasets at {SHARED_DATASETS} "
            "(../shared/datasets beside the repository), which this checkout does not have"
        )
    return SHARED_DATASETS
