"""Imports at the same time, on SQLite and PostgreSQL: one name, one winner, clear losers."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tests.support.synthetic import TOUCH_ARFF
from touchbench.app.errors import AppError
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import DatasetInMemory, add_dataset_stream
from touchbench.app.store.listing import list_datasets
from touchbench.benchmark.dataset import Attribute, Dataset, InstanceBlock, Schema

REPOSITORY = Path(__file__).resolve().parents[3]


def tiny(seed: int) -> Dataset:
    schema = Schema(
        "tiny",
        (Attribute("x", "numeric"), Attribute("c", "nominal", ("a", "b"))),
        (1,),
    )
    values = np.column_stack([np.arange(4.0) + seed, np.arange(4) % 2])
    return Dataset(schema, values)


@dataclass
class PausedSource:
    """Instances that wait for ``go`` after their first block: an import kept open."""

    dataset: Dataset
    started: threading.Event = field(default_factory=threading.Event)
    go: threading.Event = field(default_factory=threading.Event)

    @property
    def schema(self) -> Schema:
        return self.dataset.schema

    @property
    def sparse(self) -> bool:
        return False

    def blocks(self) -> Iterator[InstanceBlock]:
        yield InstanceBlock(self.dataset.values[:2])
        self.started.set()
        assert self.go.wait(30)
        yield InstanceBlock(self.dataset.values[2:])


def race(store_url: str, name: str | None) -> tuple[object, object, list[str]]:
    """A first import held open while a second one with other content starts."""
    first_store, second_store = Store(store_url), Store(store_url)
    paused = PausedSource(tiny(0))
    outcomes: dict[str, object] = {}

    def first() -> None:
        outcomes["first"] = add_dataset_stream(
            first_store, paused, sha256="1" * 64, name=name, default="tiny"
        )

    def second() -> None:
        try:
            outcomes["second"] = add_dataset_stream(
                second_store, DatasetInMemory(tiny(1)), sha256="2" * 64, name=name, default="tiny"
            )
        except AppError as error:
            outcomes["second"] = error

    one = threading.Thread(target=first)
    one.start()
    assert paused.started.wait(30)
    two = threading.Thread(target=second)
    two.start()
    two.join(0.5)  # the second import now waits on the first one's uncommitted row
    paused.go.set()
    one.join(60)
    two.join(60)
    names = [info.name for info in list_datasets(first_store)]
    first_store.dispose()
    second_store.dispose()
    return outcomes["first"], outcomes["second"], names


def test_a_name_taken_by_an_import_still_running_is_a_clear_error(store_url: str) -> None:
    first, second, names = race(store_url, "robot1")
    assert first[1] is True  # type: ignore[index]
    assert isinstance(second, AppError)
    assert "a dataset named 'robot1' already exists" in str(second)
    assert names == ["robot1"]


def test_a_default_name_taken_meanwhile_is_chosen_again(store_url: str) -> None:
    first, second, names = race(store_url, None)
    assert first[0].name == "tiny"  # type: ignore[index]
    assert second[0].name == "tiny-2" and second[1] is True  # type: ignore[index]
    assert names == ["tiny", "tiny-2"]


def test_four_processes_import_under_one_name_and_exactly_one_wins(
    store_url: str, tmp_path: Path
) -> None:
    rows = "".join(f"tap, head, {i}, {i % 7}, left\n" for i in range(20_000))
    files = []
    for i in range(4):
        path = tmp_path / f"touch{i}.arff"
        path.write_text(TOUCH_ARFF + rows + f"% copy {i}\n", encoding="utf-8")
        files.append(path)
    Store(store_url).dispose()  # migrated once: this test is about imports, not migrations
    environment = {**os.environ, "PYTHONPATH": str(REPOSITORY)}
    command = [sys.executable, "-m", "touchbench.app.cli.main", "--db", store_url, "import"]
    processes = [
        subprocess.Popen(
            [*command, str(path), "--name", "robot1"],
            cwd=tmp_path,
            env=environment,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for path in files
    ]
    results = [(p.wait(120), *p.communicate()) for p in processes]
    assert sorted(code for code, _, _ in results) == [0, 2, 2, 2], results
    for code, _out, err in results:
        if code == 2:
            (line,) = err.strip().splitlines()
            assert line.startswith("touchbench: error: a dataset named 'robot1' already exists")
    store = Store(store_url)
    stored = list_datasets(store)
    store.dispose()
    assert [(info.name, info.n_instances) for info in stored] == [("robot1", 20_004)]
