"""Models in the store: artifacts apart from the small columns, the version query, the
migration that moved them (0004 -> 0005 and back)."""

from __future__ import annotations

import hashlib
import os
from typing import Any

import pytest
from sqlalchemy import create_engine, func, select, text

from tests.support.stores import alembic
from touchbench.app.errors import NotFoundError
from touchbench.app.store.aliases import rollback_alias
from touchbench.app.store.database import Store
from touchbench.app.store.exports import load_export
from touchbench.app.store.model_refs import model_version
from touchbench.app.store.models import (
    delete_model,
    get_model,
    list_models,
    load_artifact,
    rename_model,
    save_model,
)
from touchbench.app.store.tables import ModelArtifactRow


def _add(store: Store, name: str, artifact: bytes) -> int:
    info = save_model(
        store,
        classifier="nb",
        params={},
        schema={"relation": "r", "attributes": []},
        targets=["gesture"],
        artifact=artifact,
        name=name,
    )
    return info.id


def _artifacts(store: Store) -> int:
    with store.session() as session:
        return int(session.scalar(select(func.count()).select_from(ModelArtifactRow)) or 0)


def test_the_version_follows_renames_and_deletes_by_name_and_by_id(store: Store) -> None:
    artifact = os.urandom(3_000_000)  # far beyond a page: an artifact in overflow pages
    model_id = _add(store, "big", artifact)
    digest = hashlib.sha256(artifact).hexdigest()
    assert model_version(store, "big") == (model_id, digest, "big@1", None)
    assert model_version(store, str(model_id)) == (model_id, digest, "big@1", None)
    assert model_version(store, model_id) == (model_id, digest, "big@1", None)
    rename_model(store, "big", "large")
    assert model_version(store, model_id) == (model_id, digest, "large@1", None)
    with pytest.raises(NotFoundError, match="no model 'big'"):
        model_version(store, "big")
    assert load_artifact(store, "large")[1] == artifact
    delete_model(store, "large")
    with pytest.raises(NotFoundError):
        model_version(store, model_id)
    assert _artifacts(store) == 0


def test_a_name_that_looks_like_another_models_id_finds_the_name_first(store: Store) -> None:
    first = _add(store, "first", b"one")
    second = _add(store, str(first + 100) + "x", b"two")
    assert model_version(store, str(first))[0] == first
    assert model_version(store, str(first + 100) + "x")[0] == second


def test_artifacts_move_to_their_own_table_and_back(store_url: str) -> None:
    """A store of revision 0004 (artifacts inside ``models``) keeps every model's bytes
    through the upgrade to 0005 and the downgrade."""
    url = store_url.replace("postgresql://", "postgresql+psycopg://", 1)
    blobs = {1: os.urandom(200_000), 2: b"small"}
    engine = create_engine(url)
    with engine.begin() as connection:
        alembic(connection, "upgrade", "0004")
        for model_id, blob in blobs.items():
            connection.execute(
                text(
                    "INSERT INTO models (id, name, classifier, params, schema, targets, "
                    "artifact, sha256, size_bytes, created_at, format) VALUES (:id, :name, "
                    "'nb', '{}', '{\"relation\": \"r\", \"attributes\": []}', '[\"g\"]', :a, "
                    ":s, :n, '2026-01-01', 'skops')"
                ),
                {
                    "id": model_id,
                    "name": f"m{model_id}",
                    "a": blob,
                    "s": hashlib.sha256(blob).hexdigest(),
                    "n": len(blob),
                },
            )
    store = Store(store_url)
    try:
        for model_id, blob in blobs.items():
            assert load_artifact(store, f"m{model_id}")[1] == blob
            assert model_version(store, f"m{model_id}")[1] == hashlib.sha256(blob).hexdigest()
    finally:
        store.dispose()
    with engine.begin() as connection:
        alembic(connection, "downgrade", "0004")
        back = dict(connection.execute(text("SELECT id, artifact FROM models")).all())
    engine.dispose()
    assert {key: bytes(value) for key, value in back.items()} == blobs


def _old_registry(connection: Any) -> dict[int, bytes]:
    """Models of a store at 0010 (a name per row): ``mic`` versions 1, 2 and 4 (3 deleted),
    ``old@name`` stored before names refused '@'; aliases and their history, one step of
    which names ``mic@5``, deleted since; each model's artifact and an ONNX twin. Returns
    the artifacts by id."""
    blobs = {7: os.urandom(50_000), 8: b"two", 9: b"four", 11: b"old"}
    versions = {7: ("mic", 1), 8: ("mic", 2), 9: ("mic", 4), 11: ("old@name", 1)}
    for model_id, blob in blobs.items():
        name, version = versions[model_id]
        connection.execute(
            text(
                "INSERT INTO models (id, name, version, classifier, params, schema, targets, "
                "sha256, size_bytes, created_at, format) VALUES (:id, :name, :version, 'nb', "
                '\'{}\', \'{"relation": "r", "attributes": []}\', \'["g"]\', :s, :n, '
                ":at, 'skops')"
            ),
            {
                "id": model_id,
                "name": name,
                "version": version,
                "s": hashlib.sha256(blob).hexdigest(),
                "n": len(blob),
                "at": f"2026-01-0{version} 10:00:00",
            },
        )
        for table, column in (("model_artifacts", "artifact"), ("model_exports", "data")):
            extra = ", format, sha256, size_bytes, created_at" if table == "model_exports" else ""
            values = ", 'onnx', :s, 1, '2026-01-01'" if table == "model_exports" else ""
            connection.execute(
                text(f"INSERT INTO {table} (model_id, {column}{extra}) VALUES (:id, :b{values})"),
                {"id": model_id, "b": blob, "s": hashlib.sha256(blob).hexdigest()},
            )
    connection.execute(
        text(
            "INSERT INTO model_aliases (name, alias, version, set_at) VALUES "
            "('mic', 'champion', 2, '2026-02-01'), ('mic', 'staging', 4, '2026-02-01')"
        )
    )
    if connection.dialect.name == "postgresql":  # where touchbench's own inserts leave it
        connection.execute(text("SELECT setval(pg_get_serial_sequence('models', 'id'), 11)"))
    for step, (version, undone) in enumerate([(1, False), (5, False), (2, False)]):
        connection.execute(
            text(
                "INSERT INTO model_alias_history (id, name, alias, version, set_at, undone) "
                "VALUES (:id, 'mic', 'champion', :v, '2026-02-01', :u)"
            ),
            {"id": step + 1, "v": version, "u": undone},
        )
    return blobs


def test_the_registry_moves_under_registered_models_and_back(store_url: str) -> None:
    """A store of revision 0010 keeps every model, artifact, twin, alias and step of
    history through the upgrade to registered models (0013) and the downgrade; the counter
    starts past every version the store knew of, deleted ones named in the history
    included."""
    url = store_url.replace("postgresql://", "postgresql+psycopg://", 1)
    engine = create_engine(url)
    with engine.begin() as connection:
        alembic(connection, "upgrade", "0010")
        blobs = _old_registry(connection)
    store = Store(store_url)
    try:
        listed = [(m.id, m.label, m.aliases) for m in list_models(store)]
        assert listed == [
            (7, "mic@1", ()),
            (8, "mic@2", ("champion",)),
            (9, "mic@4", ("staging",)),
            (11, "old@name@1", ()),
        ]
        for model_id, blob in blobs.items():
            assert load_artifact(store, model_id)[1] == blob
            assert load_export(store, model_id, "onnx") == blob
        assert get_model(store, "old@name").id == 11
        assert model_version(store, "mic@champion") == (
            8,
            hashlib.sha256(b"two").hexdigest(),
            "mic@2",
            hashlib.sha256(b"two").hexdigest(),  # its twin, copied here from its artifact
        )
        assert rollback_alias(store, "mic").model.label == "mic@1"  # past 5, deleted
        again = _add(store, "mic", b"six")
        assert get_model(store, again).label == "mic@6" and again > 11
        assert [m.label for m in list_models(store)][-1] == "mic@6"
        rename_model(store, "mic", "mac")
        assert get_model(store, "mac@champion").label == "mac@1"
        _check_registry_schema(store)
    finally:
        store.dispose()
    with engine.begin() as connection:
        alembic(connection, "downgrade", "0010")
        rows = connection.execute(text("SELECT id, name, version FROM models ORDER BY id")).all()
        aliases = connection.execute(text("SELECT name, alias, version FROM model_aliases")).all()
        history = connection.execute(
            text("SELECT name, version, undone FROM model_alias_history ORDER BY id")
        ).all()
        kept = dict(
            connection.execute(text("SELECT model_id, artifact FROM model_artifacts")).all()
        )
    engine.dispose()
    assert [tuple(row) for row in rows] == [
        (7, "mac", 1),
        (8, "mac", 2),
        (9, "mac", 4),
        (11, "old@name", 1),
        (again, "mac", 6),
    ]
    assert sorted(tuple(row) for row in aliases) == [("mac", "champion", 1), ("mac", "staging", 4)]
    assert [tuple(row) for row in history][:3] == [
        ("mac", 1, False),
        ("mac", 5, True),
        ("mac", 2, True),
    ]
    assert {key: bytes(value) for key, value in kept.items()} == {**blobs, again: b"six"}
    reopened = Store(store_url)  # and up again
    try:
        assert get_model(reopened, "mac@champion").id == 7
    finally:
        reopened.dispose()


def _check_registry_schema(store: Store) -> None:
    """The migrated registry is the one the ORM describes (no table, column, key or index
    of the registry differs)."""
    from alembic.autogenerate import compare_metadata
    from alembic.migration import MigrationContext

    from touchbench.app.store.tables import Base

    registry = {"registered_models", "models", "model_aliases", "model_alias_history"}
    with store.engine.connect() as connection:
        differences = compare_metadata(MigrationContext.configure(connection), Base.metadata)

    def table_of(difference: Any) -> str:
        if isinstance(difference, list):  # changes of one column: (kind, schema, table, ...)
            return str(difference[0][2])
        kind, subject = difference[0], difference[1]
        if kind.endswith("_column"):
            return str(difference[2])
        return str(subject.name if kind.endswith("_table") else subject.table.name)

    assert [d for d in differences if table_of(d) in registry] == []
