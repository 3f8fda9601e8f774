"""Importing data files into the store: ARFF or CSV, targets chosen, content deduplicated."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Literal

from app.errors import AppError
from app.store.database import Store
from app.store.datasets import DatasetInfo, add_dataset, content_digest
from benchmark.dataset import Dataset
from benchmark.errors import DataFormatError
from benchmark.io.arff import loads_arff, read_arff
from benchmark.io.csv import read_csv

FileFormat = Literal["arff", "csv"]


def parse_targets(text: str | None) -> int | list[str] | None:
    """``"2"`` -> 2 (first two), ``"-2"`` -> -2 (last two), ``"a,b"`` -> names."""
    if text is None or not text.strip():
        return None
    stripped = text.strip()
    if stripped.lstrip("-").isdigit():
        return int(stripped)
    return [name.strip() for name in stripped.split(",") if name.strip()]


def guess_format(path: Path) -> FileFormat:
    return "csv" if path.suffix.lower() in {".csv", ".tsv", ".txt"} else "arff"


def import_file(
    store: Store,
    path: Path,
    *,
    name: str | None = None,
    targets: int | Sequence[str] | None = None,
    file_format: FileFormat | None = None,
) -> tuple[DatasetInfo, bool]:
    """Read ``path`` and store it; a file whose bytes are stored already is not stored twice.

    Returns
    -------
    info : DatasetInfo
    created : bool
        ``False`` when the same content was stored before (``info`` is that data set).
    """
    if not path.exists():
        raise DataFormatError("no such file", source=str(path))
    if path.is_dir():
        raise DataFormatError("is a folder, not a data file", source=str(path))
    try:
        content = path.read_bytes()
    except OSError as error:
        raise AppError(f"{path}: cannot read: {error.strerror}") from None
    chosen = file_format or guess_format(path)
    if chosen == "csv":
        dataset = read_csv(path, targets=targets)
    else:
        dataset = loads_arff(content, source=str(path), targets=targets)
    return add_dataset(
        store, dataset, sha256=content_digest(content), name=name, source_name=path.name
    )


def read_data_file(path: Path, file_format: FileFormat | None = None) -> Dataset:
    """An ARFF or CSV file read into memory (for prediction; nothing is stored)."""
    if not path.exists():
        raise DataFormatError("no such file", source=str(path))
    if not path.is_file():
        raise DataFormatError("is not a regular file", source=str(path))
    if (file_format or guess_format(path)) == "csv":
        return read_csv(path, targets=None)
    return read_arff(path)
