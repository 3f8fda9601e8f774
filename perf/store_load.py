"""Import and load times of a 100 000 x 100 data set in the store, SQLite and PostgreSQL.

Load times are the best of three. Side by side in the same run: ``numpy.save`` and
``numpy.load`` of the same matrix on the same disk, the floor any store is measured
against (ratio = store seconds / numpy seconds).

    .venv/bin/python perf/store_load.py [--rows 100000] [--columns 100] [--postgres URL]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import uuid
from pathlib import Path

import numpy as np
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from app.store.database import Store
from app.store.datasets import add_dataset, dataset_digest, load_dataset
from benchmark.dataset import Attribute, Dataset, Schema

REPEATS = 3  # load times are the best of this many


def make_dataset(rows: int, columns: int) -> Dataset:
    rng = np.random.default_rng(0)
    attributes = [Attribute(f"f{i}", "numeric") for i in range(columns - 1)]
    attributes.append(Attribute("class", "nominal", ("a", "b", "c")))
    values = rng.normal(size=(rows, columns))
    values[:, -1] = rng.integers(0, 3, rows)
    features = values[:, :-1]
    features[rng.random(features.shape) < 0.01] = np.nan  # sprinkle missing values
    schema = Schema("perf", tuple(attributes), (columns - 1,))
    return Dataset(schema=schema, values=values)


def measure(url: str, dataset: Dataset) -> tuple[float, float]:
    store = Store(url)
    start = time.perf_counter()
    info, _ = add_dataset(store, dataset, sha256=dataset_digest(dataset))
    imported = time.perf_counter() - start
    loading = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        loaded = load_dataset(store, info.id)
        loading = min(loading, time.perf_counter() - start)
    assert loaded.equals(dataset), "the store changed the data"
    store.dispose()
    return imported, loading


def numpy_floor(folder: Path, dataset: Dataset) -> tuple[float, float]:
    path = folder / "floor.npy"
    start = time.perf_counter()
    np.save(path, dataset.values)
    saved = time.perf_counter() - start
    loading = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        np.load(path)
        loading = min(loading, time.perf_counter() - start)
    return saved, loading


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=100_000)
    parser.add_argument("--columns", type=int, default=100)
    parser.add_argument(
        "--postgres", default="postgresql+psycopg://postgres:postgres@127.0.0.1:5432/test"
    )
    args = parser.parse_args()
    dataset = make_dataset(args.rows, args.columns)
    print(f"data set: {args.rows} instances x {args.columns} attributes")
    with tempfile.TemporaryDirectory() as folder:
        save, load = numpy_floor(Path(folder), dataset)
        print(f"{'backend':<12}{'import s':>10}{'load s':>10}{'load / numpy.load':>20}")
        print(f"{'numpy .npy':<12}{save:>10.3f}{load:>10.3f}{1.0:>20.1f}")
        results = {"sqlite": measure(f"sqlite:///{folder}/perf.db", dataset)}
        admin = create_engine(args.postgres, isolation_level="AUTOCOMMIT")
        name = f"touchbench_perf_{uuid.uuid4().hex[:8]}"
        try:
            with admin.connect() as connection:
                connection.execute(text(f'CREATE DATABASE "{name}"'))
        except Exception as error:
            print(f"postgresql: skipped ({str(error).splitlines()[0]})")
        else:
            url = make_url(args.postgres).set(database=name).render_as_string(hide_password=False)
            try:
                results["postgresql"] = measure(url, dataset)
            finally:
                with admin.connect() as connection:
                    connection.execute(text(f'DROP DATABASE "{name}" WITH (FORCE)'))
        for backend, (imported, loading) in results.items():
            print(f"{backend:<12}{imported:>10.3f}{loading:>10.3f}{loading / load:>20.1f}")


if __name__ == "__main__":
    main()
