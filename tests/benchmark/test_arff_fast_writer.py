"""Arrow's writer of dense rows writes what the row writer writes, byte for byte.

``VECTORISED_MIN_CELLS`` set to 0 hands every dense block to Arrow; set beyond reach, every
row is written by Python's ``repr``: the two texts must be equal on everything.
"""

from __future__ import annotations

import dataclasses
import io

import numpy as np
import pytest

from tests.support.arff_texts import CANONICAL, random_dataset
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io import arff_writer
from touchbench.benchmark.io.arff import ArffWriter, dumps_arff, loads_arff


def both_texts(dataset: Dataset, monkeypatch: pytest.MonkeyPatch) -> tuple[str, str]:
    """(row writer's text, Arrow writer's text) of ``dataset``."""
    with monkeypatch.context() as patched:
        patched.setattr(arff_writer, "VECTORISED_MIN_CELLS", 1 << 62)
        by_rows = dumps_arff(dataset)
    with monkeypatch.context() as patched:
        patched.setattr(arff_writer, "VECTORISED_MIN_CELLS", 0)
        by_arrow = dumps_arff(dataset)
    return by_rows, by_arrow


def numbers_dataset(values: np.ndarray, *, columns: int = 3) -> Dataset:
    """Numbers in ``columns`` numeric attributes between two nominal ones."""
    rows = -(-values.size // columns)
    numbers = np.resize(values, rows * columns).reshape(rows, columns)
    labels = np.arange(rows) % 2
    attributes = (
        Attribute("g", "nominal", ("tap", "two words"), "nominal"),
        *(Attribute(f"x{j}", "numeric", (), "numeric") for j in range(columns)),
        Attribute("p", "nominal", ("head", "?"), "nominal"),
    )
    table = np.column_stack([labels, numbers, 1 - labels])
    table[::5, 0] = np.nan
    return Dataset(Schema("n", attributes, (0,)), table)


def edges() -> np.ndarray:
    """Doubles around every place where Arrow's notation and Python's differ, and others."""
    values = [0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, -5e-324, 2.2250738585072014e-308]
    values += [1.7976931348623157e308, 2.0**53, 2.0**53 + 2, 0.1, 1 / 3, 123456789.123]
    for edge in (1e-4, 1e-3, 1.0, 1e9, 1e10, 1e15, 1e16, 1e17, 1e21, 1e22):
        for sign in (1.0, -1.0):
            value = sign * edge
            for _ in range(40):
                value = np.nextafter(value, 0.0)
            for _ in range(80):
                values.append(value)
                value = np.nextafter(value, sign * np.inf)
    return np.array(values)


def test_numbers_around_every_change_of_notation_are_written_alike(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    by_rows, by_arrow = both_texts(numbers_dataset(edges()), monkeypatch)
    assert by_arrow == by_rows


def test_random_doubles_of_every_magnitude_are_written_alike(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = np.random.default_rng(7)
    bits = rng.integers(0, 2**64, size=20_000, dtype=np.uint64)
    anything = bits.view(np.float64)  # every exponent, NaNs and subnormals included
    decimals = np.round(10 ** rng.uniform(-7, 18, 20_000), int(rng.integers(0, 8)))
    dataset = numbers_dataset(np.concatenate([anything, decimals, -decimals]), columns=7)
    by_rows, by_arrow = both_texts(dataset, monkeypatch)
    assert by_arrow == by_rows
    back = loads_arff(by_arrow)
    same = back.values[:, 1:-1].ravel()[: anything.size].view(np.uint64)
    finite = ~np.isnan(anything)
    assert np.array_equal(same[finite], bits[finite])  # the text reads back bit for bit


def test_the_data_sets_of_the_reader_tests_are_written_alike(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    written = 0
    for seed in range(300):
        dataset = dataclasses.replace(random_dataset(np.random.default_rng(seed)), sparse=False)
        by_rows, by_arrow = both_texts(dataset, monkeypatch)
        assert by_arrow == by_rows, f"seed {seed}"
        written += dataset.values.size > 0
    assert written > 200  # dates, strings, tricky labels, missing values and weights
    by_rows, by_arrow = both_texts(loads_arff(CANONICAL), monkeypatch)
    assert by_arrow == by_rows == CANONICAL


def test_a_writer_turns_to_arrow_once_it_has_written_enough_cells(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = np.random.default_rng(3)
    dataset = numbers_dataset(np.round(rng.lognormal(3, 2, 3000), 5))
    weights = rng.choice([1.0, 0.5, 2.0], size=dataset.values.shape[0])
    monkeypatch.setattr(arff_writer, "VECTORISED_MIN_CELLS", 500)
    calls: list[int] = []
    text = arff_writer.DenseRows.text
    monkeypatch.setattr(
        arff_writer.DenseRows,
        "text",
        lambda self, values, suffixes=None: (
            calls.append(len(values)) or text(self, values, suffixes)
        ),
    )
    stream = io.StringIO()
    writer = ArffWriter(stream, dataset.schema)
    writer.write_header()
    for first in range(0, dataset.values.shape[0], 70):
        writer.write_block(dataset.values[first : first + 70], weights[first : first + 70])
    assert calls and sum(calls) < dataset.values.shape[0]  # the first blocks by rows
    monkeypatch.setattr(arff_writer, "VECTORISED_MIN_CELLS", 1 << 62)
    expected = dumps_arff(dataclasses.replace(dataset, weights=weights))
    assert stream.getvalue() == expected


def test_a_date_that_cannot_be_written_leaves_its_block_unwritten(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(arff_writer, "VECTORISED_MIN_CELLS", 0)
    schema = Schema(
        "d",
        (Attribute("when", "date", (), "date"), Attribute("c", "nominal", ("a",), "nominal")),
        (1,),
    )
    values = np.zeros((50, 2))
    values[40, 0] = 1e15  # far beyond the year 9999
    stream = io.StringIO()
    writer = ArffWriter(stream, schema)
    with pytest.raises(DataFormatError, match="cannot write"):
        writer.write_block(values)
    assert stream.getvalue() == ""
    assert writer.rows_written == 0


def test_sparse_rows_keep_the_row_writer(monkeypatch: pytest.MonkeyPatch) -> None:
    dataset = loads_arff(
        "@relation s\n@attribute a numeric\n@attribute b {no,yes}\n@data\n{1 yes}\n{0 2.5}\n"
    )
    by_rows, by_arrow = both_texts(dataset, monkeypatch)
    assert by_arrow == by_rows
    assert by_arrow.split("@data\n")[1] == "{1 yes}\n{0 2.5}\n"
