"""Stores for the app tests: every test that takes ``store_url`` runs twice, on a fresh
SQLite file and on a fresh schema of a real PostgreSQL server."""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from touchbench.app.store.database import Store

DEFAULT_POSTGRES = "postgresql://postgres:postgres@127.0.0.1:5432/test"


def _psycopg_url(url: str) -> str:
    return (
        "postgresql+psycopg://" + url.split("://", 1)[1] if url.startswith("postgresql://") else url
    )


@pytest.fixture(scope="session")
def postgres_database() -> Iterator[str]:
    """A database of its own on the test server for this session, dropped at the end."""
    server = os.environ.get("TOUCHBENCH_TEST_POSTGRES_URL", DEFAULT_POSTGRES)
    if not server:
        pytest.skip("no PostgreSQL server could be started here (scripts/postgres.sh failed)")
    admin = create_engine(_psycopg_url(server), isolation_level="AUTOCOMMIT")
    name = f"touchbench_test_{os.getpid()}_{uuid.uuid4().hex[:6]}"
    try:
        with admin.connect() as connection:
            connection.execute(text(f'CREATE DATABASE "{name}"'))
    except Exception as error:  # no server: the PostgreSQL leg cannot run
        admin.dispose()
        pytest.skip(f"no PostgreSQL server at {server}: {str(error).splitlines()[0]}")
    url = make_url(_psycopg_url(server)).set(database=name).render_as_string(hide_password=False)
    yield url
    with admin.connect() as connection:
        connection.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
    admin.dispose()


@pytest.fixture(params=["sqlite", "postgresql"])
def store_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """URL of an empty store, on SQLite then on PostgreSQL."""
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'touchbench.db'}"
    return emptied(request.getfixturevalue("postgres_database"))


def emptied(url: str) -> str:
    """``url``, a PostgreSQL database, once its tables are all dropped."""
    engine = create_engine(url, isolation_level="AUTOCOMMIT")
    with engine.connect() as connection:
        connection.execute(text("DROP SCHEMA public CASCADE"))
        connection.execute(text("CREATE SCHEMA public"))
    engine.dispose()
    return url


@pytest.fixture
def store(store_url: str) -> Iterator[Store]:
    opened = Store(store_url)
    yield opened
    opened.dispose()
