"""The store on SQLite and PostgreSQL: round trips, deduplication, names, atomicity."""

from __future__ import annotations

import contextlib
import json
import sqlite3
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sqlalchemy import func, select

from tests.support.stores import alembic
from tests.support.synthetic import small_dataset
from touchbench.app.errors import AppError, NotFoundError
from touchbench.app.store import datasets as store_datasets
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import (
    add_dataset,
    dataset_digest,
    delete_dataset,
    find_dataset,
    load_dataset,
)
from touchbench.app.store.listing import COLUMNS, count_datasets, list_datasets
from touchbench.app.store.reading import SQLiteFile, sqlite_file
from touchbench.app.store.tables import DatasetRow, InstanceBlockRow, InstanceRow


def count_rows(store: Store) -> tuple[int, int, int]:
    """Data sets, instances in blocks of values, and instances with a group or metadata."""
    with store.session() as session:
        return (
            session.scalar(select(func.count()).select_from(DatasetRow)) or 0,
            session.scalar(select(func.coalesce(func.sum(InstanceBlockRow.n_rows), 0))) or 0,
            session.scalar(select(func.count()).select_from(InstanceRow)) or 0,
        )


def test_round_trip_keeps_values_missing_weights_groups_and_meta(store: Store) -> None:
    data = small_dataset()
    data.weights = np.linspace(0.5, 2.0, data.n_instances)
    data.groups = np.array([f"session-{i // 3}" for i in range(data.n_instances)], dtype=object)
    data.meta = [{"source": "a.wav", "start": float(i), "end": i + 0.5} for i in range(7)]
    info, created = add_dataset(store, data, sha256=dataset_digest(data), source_name="a.arff")
    assert created
    assert (info.name, info.n_instances, info.n_features, info.targets) == (
        "touch",
        7,
        4,
        ["gesture"],
    )
    assert count_rows(store) == (1, 7, 7)
    loaded = load_dataset(store, info.id)
    assert loaded.equals(data)
    assert list(loaded.groups) == list(data.groups)  # type: ignore[arg-type]
    assert loaded.meta == data.meta
    assert np.isnan(loaded.values[2, 1]) and np.isnan(loaded.values[4, 0])


def test_same_content_is_stored_once(store: Store) -> None:
    data = small_dataset()
    first, created_first = add_dataset(store, data, sha256="a" * 64)
    second, created_second = add_dataset(store, data, sha256="a" * 64, name="other")
    assert created_first and not created_second
    assert second.id == first.id
    assert count_rows(store) == (1, 7, 0)


def test_default_names_are_made_unique_and_explicit_clashes_refused(store: Store) -> None:
    one, _ = add_dataset(store, small_dataset(), sha256="1" * 64)
    two, _ = add_dataset(store, small_dataset(), sha256="2" * 64)
    assert (one.name, two.name) == ("touch", "touch-2")
    with pytest.raises(AppError, match="already exists"):
        add_dataset(store, small_dataset(), sha256="3" * 64, name="touch")
    with pytest.raises(AppError, match="cannot be a number"):
        add_dataset(store, small_dataset(), sha256="4" * 64, name="12")
    assert count_rows(store) == (2, 14, 0)


def test_find_by_name_or_id_and_delete(store: Store) -> None:
    info, _ = add_dataset(store, small_dataset(), sha256="1" * 64, name="mini")
    assert find_dataset(store, "mini").id == info.id
    assert find_dataset(store, str(info.id)).name == "mini"
    with pytest.raises(NotFoundError, match=r"no dataset 'maggie'.*mini"):
        find_dataset(store, "maggie")
    assert delete_dataset(store, "mini").id == info.id
    assert list_datasets(store) == []
    assert count_rows(store) == (0, 0, 0)


def test_a_failure_while_importing_leaves_nothing_behind(
    store: Store, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(store_datasets, "_INSERT_BATCH", 2)
    real_write = store_datasets._write_block
    calls = {"n": 0}

    def failing_write(*args: Any) -> None:
        calls["n"] += 1
        if calls["n"] == 3:
            raise RuntimeError("disk full")
        real_write(*args)

    monkeypatch.setattr(store_datasets, "_write_block", failing_write)
    with pytest.raises(RuntimeError, match="disk full"):
        add_dataset(store, small_dataset(), sha256="f" * 64)
    assert calls["n"] == 3
    assert count_rows(store) == (0, 0, 0)


def test_the_listing_reads_columns_of_the_datasets_table_with_their_types(
    store: Store,
) -> None:
    orm_columns = DatasetRow.__table__.columns
    assert set(COLUMNS) <= set(orm_columns.keys())
    added, _ = add_dataset(store, small_dataset(), sha256="1" * 64, name="mini")
    (listed,) = list_datasets(store)
    assert listed == added  # as the ORM reads the row
    assert (listed.name, listed.n_instances, listed.targets) == ("mini", 7, ["gesture"])
    assert listed.created_at.tzinfo is not None
    assert count_datasets(store) == 1
    if store.url.startswith("sqlite:///"):  # the CLI's read without SQLAlchemy
        assert sqlite_file(store.url) is not None
        assert list_datasets(sqlite_file(store.url)) == [listed]


def test_reopening_a_store_keeps_its_data(store_url: str) -> None:
    first = Store(store_url)
    add_dataset(first, small_dataset(), sha256="1" * 64)
    first.dispose()
    again = Store(store_url)
    assert [d.name for d in list_datasets(again)] == ["touch"]
    again.dispose()


def test_an_unusable_url_is_a_clear_error(tmp_path: object) -> None:
    with pytest.raises(AppError, match="not a database URL"):
        Store("nonsense")
    with pytest.raises(AppError, match="folder does not exist"):
        Store("sqlite:////no/such/folder/touchbench.db")


def test_head_revision_constant_matches_the_migrations() -> None:
    from alembic.config import Config
    from alembic.script import ScriptDirectory

    from touchbench.app.store.database import MIGRATIONS
    from touchbench.app.store.reading import HEAD_REVISION

    config = Config()
    config.set_main_option("script_location", str(MIGRATIONS))
    assert ScriptDirectory.from_config(config).get_current_head() == HEAD_REVISION


def test_a_fresh_store_is_migrated_to_head(store: Store) -> None:
    from touchbench.app.store.reading import HEAD_REVISION

    assert store.revision() == HEAD_REVISION


def test_instances_stored_one_a_row_move_into_blocks_and_back(store_url: str) -> None:
    """A store of revision 0003 (one row per instance) migrates to blocks; downgraded, it has
    its rows back as they were."""
    from sqlalchemy import create_engine, text

    data = small_dataset(n=3000)
    data.weights = np.where(np.arange(3000) % 7 == 0, 0.5, 1.0)
    rows = [
        {
            "id": 1,
            "position": i,
            "data": data.values[i].astype("<f8").tobytes(),
            "weight": 0.5 if i % 7 == 0 else None,
            "group_id": "s1" if i == 5 else None,
            "meta": '{"source": "a.wav"}' if i == 9 else None,
        }
        for i in range(3000)
    ]
    engine = create_engine(store_url)
    with engine.begin() as connection:
        alembic(connection, "upgrade", "0003")
        connection.execute(
            text(
                "INSERT INTO datasets (id, name, relation, schema, target_names, n_instances, "
                "n_attributes, sparse, sha256, created_at) VALUES (1, 'old', :relation, "
                ":schema, '[\"gesture\"]', 3000, 5, false, 'x', '2026-01-01')"
            ),
            {"relation": data.schema.relation, "schema": json.dumps(data.schema.to_json())},
        )
        connection.execute(
            text(
                "INSERT INTO instances (dataset_id, position, data, weight, group_id, meta) "
                "VALUES (:id, :position, :data, :weight, :group_id, :meta)"
            ),
            rows,
        )
    store = Store(store_url)
    try:
        assert count_rows(store) == (1, 3000, 2)
        loaded = load_dataset(store, "old")
        assert loaded.values.tobytes() == data.values.tobytes()
        assert loaded.weights is not None and loaded.weights.tobytes() == data.weights.tobytes()
        assert loaded.groups is not None and loaded.groups[5] == "s1"
        assert loaded.meta is not None and loaded.meta[9] == {"source": "a.wav"}
    finally:
        store.dispose()
    with engine.begin() as connection:
        alembic(connection, "downgrade", "0003")
        back = connection.execute(
            text("SELECT position, data, weight, group_id FROM instances ORDER BY position")
        ).all()
    engine.dispose()
    # A weight left out meant 1; a block with weights gives each instance its own.
    assert [tuple(row) for row in back] == [
        (r["position"], r["data"], r["weight"] or 1.0, r["group_id"]) for r in rows
    ]


def test_stored_blocks_are_written_the_cheap_way(store: Store) -> None:
    """New SQLite stores have 64 KiB pages; PostgreSQL keeps blocks out of line, uncompressed."""
    from sqlalchemy import text

    with store.engine.connect() as connection:
        if connection.dialect.name == "sqlite":
            assert connection.execute(text("PRAGMA page_size")).scalar() == 65536
        else:
            storage = connection.execute(
                text(
                    "SELECT attname, attstorage FROM pg_attribute WHERE attrelid = "
                    "'instance_blocks'::regclass AND attname IN ('data', 'weights') "
                    "ORDER BY attname"
                )
            ).all()
            assert [tuple(row) for row in storage] == [("data", "e"), ("weights", "e")]


def test_a_block_changed_outside_touchbench_is_refused_saying_so(store: Store) -> None:
    data = small_dataset()
    stored, _ = add_dataset(store, data, sha256=dataset_digest(data), name="touch")
    with store.session() as session:
        session.execute(
            InstanceBlockRow.__table__.update()
            .where(InstanceBlockRow.dataset_id == stored.id)
            .values(data=b"\x00" * 12)
        )
    with pytest.raises(AppError, match=r"holds 12 bytes where 5 attributes need 280"):
        load_dataset(store, "touch")


def test_only_a_store_at_the_newest_revision_is_read_without_sqlalchemy(tmp_path: Path) -> None:
    """Whatever is not a plain SQLite store at the head revision is left to Store, which
    creates, migrates or refuses it."""
    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    assert sqlite_file(url) is None  # not there yet
    Store(url).dispose()
    assert sqlite_file(url) == SQLiteFile(path)
    for other in (f"{url}?timeout=5", "sqlite://", "sqlite:///:memory:", f"sqlite:///{tmp_path}"):
        assert sqlite_file(other) is None, other
    with contextlib.closing(sqlite3.connect(path)) as connection, connection:
        connection.execute("UPDATE alembic_version SET version_num = '0001'")
    assert sqlite_file(url) is None  # a migration is due
    (tmp_path / "other.db").write_bytes(b"not a database, but not empty either")
    assert sqlite_file(f"sqlite:///{tmp_path / 'other.db'}") is None
