"""Small benchmark problems made in the test."""

from __future__ import annotations

import numpy as np

from touchbench.benchmark.dataset import Attribute, Dataset, Schema


def make_problem(
    values: list[list[float]], targets: tuple[int, ...] = (0,), weights=None
) -> Dataset:
    attributes = (
        Attribute("gesture", "nominal", ("tap", "slap")),
        Attribute("note", "string", ("x",)),
        Attribute("colour", "nominal", ("red", "green", "blue")),
        Attribute("level", "numeric", (), "numeric"),
        Attribute("when", "date", (), "date"),
    )
    return Dataset(Schema("r", attributes, targets), np.array(values, float), weights=weights)
