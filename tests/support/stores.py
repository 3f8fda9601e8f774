"""Test stores' URLs: the PostgreSQL test server's, and a database emptied for reuse."""

from __future__ import annotations

import sqlite3
from contextlib import closing
from pathlib import Path
from typing import Any

from sqlalchemy import create_engine, text

DEFAULT_POSTGRES = "postgresql://postgres:postgres@127.0.0.1:5432/test"


def psycopg_url(url: str) -> str:
    return (
        "postgresql+psycopg://" + url.split("://", 1)[1] if url.startswith("postgresql://") else url
    )


def emptied(url: str) -> str:
    """``url``, a PostgreSQL database, once its tables are all dropped."""
    engine = create_engine(url, isolation_level="AUTOCOMMIT")
    with engine.connect() as connection:
        connection.execute(text("DROP SCHEMA public CASCADE"))
        connection.execute(text("CREATE SCHEMA public"))
    engine.dispose()
    return url


def alembic(connection: Any, action: str, revision: str) -> None:
    from alembic import command
    from alembic.config import Config

    from touchbench.app.store.database import MIGRATIONS

    config = Config()
    config.set_main_option("script_location", str(MIGRATIONS))
    config.attributes["connection"] = connection
    getattr(command, action)(config, revision)


def copy_sqlite(source: Path, target: Path) -> str:
    """A copy at ``target`` of the SQLite store ``source`` (with what its write-ahead log
    holds): a test's own store, made from a module's template; its URL."""
    with closing(sqlite3.connect(source)) as original, closing(sqlite3.connect(target)) as copy:
        original.backup(copy)
    return f"sqlite:///{target}"
