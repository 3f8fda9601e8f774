"""Stores and services for the app tests: every test that takes ``store_url`` runs twice, on
a fresh SQLite file and on a fresh schema of a real PostgreSQL server; ``make_server`` starts
real services (uvicorn on loopback) on it.

Which leg when: a test whose subject is the store's behaviour (transactions, concurrency,
locking, round trips of stored values, kill -9 and resume, ids and versions never reused,
nothing half-written, jobs dispatched between processes, migrations) takes ``store_url``,
``store``, ``make_server`` or ``server`` and runs on both. A test that only puts things in a
store while its subject is something else (validation, refusals and their words, keys and
origins, pages and plots, live prediction, scoring, fold logic, parsing bounds, fuzzing)
takes the ``sqlite_`` twin and runs on SQLite only."""

from __future__ import annotations

import os
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from tests.support.service import Server, servers
from tests.support.stores import DEFAULT_POSTGRES, emptied, psycopg_url
from touchbench.app.store.database import Store


@pytest.fixture(scope="session")
def postgres_database() -> Iterator[str]:
    """A database of its own on the test server for this session, dropped at the end."""
    server = os.environ.get("TOUCHBENCH_TEST_POSTGRES_URL", DEFAULT_POSTGRES)
    if not server:
        pytest.skip("no PostgreSQL server could be started here (scripts/postgres.sh failed)")
    admin = create_engine(psycopg_url(server), isolation_level="AUTOCOMMIT")
    name = f"touchbench_test_{os.getpid()}_{uuid.uuid4().hex[:6]}"
    try:
        with admin.connect() as connection:
            connection.execute(text(f'CREATE DATABASE "{name}"'))
    except Exception as error:  # no server: the PostgreSQL leg cannot run
        admin.dispose()
        pytest.skip(f"no PostgreSQL server at {server}: {str(error).splitlines()[0]}")
    url = make_url(psycopg_url(server)).set(database=name).render_as_string(hide_password=False)
    yield url
    with admin.connect() as connection:
        connection.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
    admin.dispose()


@pytest.fixture(params=["sqlite", "postgresql"])
def store_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """URL of an empty store, on SQLite then on PostgreSQL: for tests of the store's own
    behaviour (see the module's docstring)."""
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'touchbench.db'}"
    return emptied(request.getfixturevalue("postgres_database"))


@pytest.fixture
def sqlite_store_url(tmp_path: Path) -> str:
    """URL of an empty SQLite store, the one leg for tests whose subject is not the store
    (the store only holds what they need); what the store itself does runs on ``store_url``."""
    return f"sqlite:///{tmp_path / 'touchbench.db'}"


@pytest.fixture
def store(store_url: str) -> Iterator[Store]:
    opened = Store(store_url)
    yield opened
    opened.dispose()


@pytest.fixture
def sqlite_store(sqlite_store_url: str) -> Iterator[Store]:
    """A store on SQLite only, for tests whose subject is not the store."""
    opened = Store(sqlite_store_url)
    yield opened
    opened.dispose()


@pytest.fixture
def make_server(store_url: str, tmp_path: Path) -> Iterator[Callable[..., Server]]:
    """Builds (and at the end stops) services on the test's store (SQLite, PostgreSQL)."""
    yield from servers(store_url, tmp_path)


@pytest.fixture
def make_sqlite_server(sqlite_store_url: str, tmp_path: Path) -> Iterator[Callable[..., Server]]:
    """Builds services on a SQLite file of the test's own: for tests whose subject is not
    the store (what the store itself does runs on ``make_server``, both stores)."""
    yield from servers(sqlite_store_url, tmp_path)


@pytest.fixture
def server(make_server: Callable[..., Server]) -> Server:
    return make_server()


@pytest.fixture
def sqlite_server(make_sqlite_server: Callable[..., Server]) -> Server:
    """A service on SQLite only, for tests whose subject is not the store."""
    return make_sqlite_server()


@pytest.fixture(autouse=True)
def _command_options_end_with_the_test() -> Iterator[None]:
    """A test that builds a request as a command does (``build_request``, outside the CLI's
    ``main``, which runs each command in a context of its own) names the options in the
    test's context: they end with the test, as a command's end with its call."""
    from touchbench.app.cli import requests

    token = requests._options.set(requests._options.get())
    yield
    requests._options.reset(token)
