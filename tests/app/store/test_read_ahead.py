"""An import whose blocks are parsed by threads ahead of the store (benchmark/io/read_ahead.py):
a failure on either side, mid-import, is one line and leaves nothing in the store, and no
thread is left running; on SQLite and PostgreSQL."""

from __future__ import annotations

import functools
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sqlalchemy import func, select

import touchbench.app.services.datasets as services
import touchbench.app.store.datasets as store_datasets
import touchbench.benchmark.io.arff_reader as arff_reader
from tests.support.cli_runner import run_cli
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.app.store.listing import list_datasets
from touchbench.app.store.tables import InstanceBlockRow
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.arff import read_arff

HEADER = (
    "@relation 'plain: -C 1'\n@attribute g {tap,slap}\n"
    "@attribute x numeric\n@attribute y numeric\n@data\n"
)
ROWS = 3000


@pytest.fixture
def plain_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A file of plain rows that the import reads in some 20 blocks, each parsed by Arrow
    in a thread ahead of the store."""
    rng = np.random.default_rng(5)
    values = rng.lognormal(2, 1, size=(ROWS, 2))
    body = "".join(
        f"{'tap' if i % 3 else 'slap'},{x!r},{y!r}\n" for i, (x, y) in enumerate(values.tolist())
    )
    path = tmp_path / "plain.arff"
    path.write_text(HEADER + body, encoding="utf-8")
    monkeypatch.setattr(
        services, "open_arff", functools.partial(arff_reader.open_arff, block_bytes=4096)
    )
    monkeypatch.setattr(arff_reader, "VECTORISED_MIN_BYTES", 0)
    return path


def _stored_blocks(store_url: str) -> int:
    store = Store(store_url)
    try:
        assert list_datasets(store) == []
        with store.session() as session:
            return int(session.scalar(select(func.count()).select_from(InstanceBlockRow)) or 0)
    finally:
        store.dispose()


def _read_ahead_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name.startswith("read-ahead")]


def test_blocks_parsed_ahead_are_stored_as_the_exact_reader_reads_them(
    capsys: pytest.CaptureFixture[str], store_url: str, plain_file: Path
) -> None:
    parsed: list[str] = []
    real_read = arff_reader.read_plain_block

    def watched(*args: Any, **kwargs: Any) -> Any:
        parsed.append(threading.current_thread().name)
        return real_read(*args, **kwargs)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(arff_reader, "read_plain_block", watched)
        result = run_cli(capsys, store_url, "import", str(plain_file), "--json")
    assert result.code == 0, result.err
    assert len(parsed) > 10 and all(name.startswith("read-ahead") for name in parsed)
    store = Store(store_url)
    stored = load_dataset(store, result.json()["id"])
    store.dispose()
    exact = read_arff(plain_file, parser="tokenizer")
    assert stored.values.tobytes() == exact.values.tobytes()
    assert _read_ahead_threads() == []


def test_a_failure_while_a_block_is_parsed_ahead_is_one_line_and_stores_nothing(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    plain_file: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    real_read = arff_reader.read_plain_block
    calls = {"n": 0}
    lock = threading.Lock()

    def failing(*args: Any, **kwargs: Any) -> Any:
        with lock:
            calls["n"] += 1
            broken = calls["n"] == 8
        if broken:
            raise DataFormatError("a block that cannot be read", source="plain.arff")
        return real_read(*args, **kwargs)

    monkeypatch.setattr(arff_reader, "read_plain_block", failing)
    result = run_cli(capsys, store_url, "import", str(plain_file))
    assert result.code == 2
    assert result.err.strip().splitlines() == [
        "touchbench: error: plain.arff: a block that cannot be read"
    ]
    assert _stored_blocks(store_url) == 0
    assert _read_ahead_threads() == []


def test_a_failure_of_the_store_while_blocks_are_parsed_ahead_stores_nothing(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    plain_file: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    real_write = store_datasets._write_block
    calls = {"n": 0}

    def failing_write(*args: Any) -> None:
        calls["n"] += 1
        if calls["n"] == 5:
            raise OSError(28, "No space left on device")
        real_write(*args)

    monkeypatch.setattr(store_datasets, "_write_block", failing_write)
    result = run_cli(capsys, store_url, "import", str(plain_file))
    assert result.code == 1
    assert result.err.strip().splitlines() == [
        "touchbench: unexpected error: OSError: [Errno 28] No space left on device "
        "(set TOUCHBENCH_DEBUG=1 for the traceback)"
    ]
    assert calls["n"] == 5
    assert _stored_blocks(store_url) == 0
    assert _read_ahead_threads() == []
