"""Fixtures shared by every test package."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest_plugins = ["tests.support.termination"]


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The tests marked ``slow`` first, each group in its own order: pytest-xdist hands the
    tests out in this order, and a slow test left to the end keeps the whole run waiting for
    one worker."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


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
