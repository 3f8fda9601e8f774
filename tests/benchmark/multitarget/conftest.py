"""Fixtures of the multi-target tests."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.multitarget import META_FACTORIES, three_targets


@pytest.fixture
def tiny() -> tuple[np.ndarray, np.ndarray]:
    return three_targets()


@pytest.fixture(params=sorted(META_FACTORIES))
def meta_id(request: pytest.FixtureRequest) -> str:
    return str(request.param)
