"""Predictions compared as a model's answers: the labels exactly, the probabilities to the
last few bits.

A model's probabilities go through BLAS, whose kernels (and so the order of a sum) are
chosen for the CPU at hand: the same stored model on another machine may differ in the
last bit. ``RELATIVE`` is ten thousand times the double's epsilon: far below any change a
wrong model or a lost parameter would make, far above a reordered sum.
"""

from __future__ import annotations

from typing import Any

import pytest

RELATIVE = 1e-12


def assert_same_predictions(found: list[dict[str, Any]], expected: list[dict[str, Any]]) -> None:
    """``found`` are ``expected``: the same instances and labels, and the same
    probabilities (``{target: {class: p}}``) to :data:`RELATIVE`."""
    assert len(found) == len(expected)
    for got, wanted in zip(found, expected, strict=True):
        labels = {key: value for key, value in got.items() if key != "probabilities"}
        assert labels == {key: value for key, value in wanted.items() if key != "probabilities"}
        assert got.keys() == wanted.keys()
        for target, probabilities in wanted.get("probabilities", {}).items():
            assert got["probabilities"][target] == pytest.approx(probabilities, rel=RELATIVE, abs=0)
