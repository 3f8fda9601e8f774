"""Models in the store: artifacts apart from the small columns, the version query, the
migration that moved them (0004 -> 0005 and back)."""

from __future__ import annotations

import hashlib
import os

import pytest
from sqlalchemy import create_engine, func, select, text

from tests.app.test_store import _alembic
from touchbench.app.errors import NotFoundError
from touchbench.app.store.database import Store
from touchbench.app.store.models import (
    delete_model,
    load_artifact,
    model_version,
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
    assert model_version(store, "big") == (model_id, digest, "big@1")
    assert model_version(store, str(model_id)) == (model_id, digest, "big@1")
    assert model_version(store, model_id) == (model_id, digest, "big@1")
    rename_model(store, "big", "large")
    assert model_version(store, model_id) == (model_id, digest, "large@1")
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
        _alembic(connection, "upgrade", "0004")
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
        _alembic(connection, "downgrade", "0004")
        back = dict(connection.execute(text("SELECT id, artifact FROM models")).all())
    engine.dispose()
    assert {key: bytes(value) for key, value in back.items()} == blobs
