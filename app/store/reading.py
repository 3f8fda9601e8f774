"""Reading a store through its database driver alone, without SQLAlchemy.

``touchbench datasets`` reads one table; importing SQLAlchemy would cost it more than all
else (``perf/startup.py`` measures it).  A store is read here
through a DB-API connection: the :class:`~app.store.database.Store`'s own (pooled, any
database) or, for a SQLite file at the newest revision, one that :mod:`sqlite3` opens
read-only (:func:`sqlite_file`).  Anything else about the URL or the file (not there yet,
due a migration, not a store, a URL with options) is left to ``Store``, which creates,
migrates or refuses it in its own words.
"""

from __future__ import annotations

import contextlib
import sqlite3
from collections.abc import Iterator
from contextlib import AbstractContextManager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

#: The newest migration; a test checks it against Alembic's own idea of the head.
HEAD_REVISION = "0014"

#: What a plain SQLite URL starts with (``sqlite:///relative.db``, ``sqlite:////abs.db``).
_SQLITE_PREFIX = "sqlite:///"


class Readable(Protocol):
    """A store that lends a DB-API connection for reading (its transaction ends with it)."""

    def reading(self) -> AbstractContextManager[Any]:
        """A DB-API connection, given back (or closed) when the block ends."""
        ...


def fetch_all(store: Readable, statement: str) -> list[tuple[Any, ...]]:
    """The rows of a read-only ``statement`` without parameters, as the driver gives them."""
    with store.reading() as connection:
        cursor = connection.cursor()
        try:
            cursor.execute(statement)
            return [tuple(row) for row in cursor.fetchall()]
        finally:
            cursor.close()


@dataclass(frozen=True)
class SQLiteFile:
    """A store in a SQLite file known to be at :data:`HEAD_REVISION`, read-only."""

    path: Path

    @contextlib.contextmanager
    def reading(self) -> Iterator[sqlite3.Connection]:
        with contextlib.closing(_connect_read_only(self.path)) as connection:
            yield connection


def sqlite_file(url: str) -> SQLiteFile | None:
    """The SQLite file of ``url`` when it holds a store at the newest revision, else
    ``None`` (then open a :class:`~app.store.database.Store`)."""
    if not url.startswith(_SQLITE_PREFIX):
        return None
    database = url[len(_SQLITE_PREFIX) :]
    # Options, escapes and in-memory databases: as SQLAlchemy reads them, in Store.
    if not database or any(sign in database for sign in "?%#") or database == ":memory:":
        return None
    path = Path(database)
    try:
        if not path.is_file() or path.stat().st_size == 0:
            return None
        with contextlib.closing(_connect_read_only(path)) as connection:
            row = connection.execute("SELECT version_num FROM alembic_version").fetchone()
    except (OSError, sqlite3.Error):
        return None
    return SQLiteFile(path) if row is not None and row[0] == HEAD_REVISION else None


def _connect_read_only(path: Path) -> sqlite3.Connection:
    # Read-only through a URI: never creates a file nor writes to one; waits for a writer
    # as long as the Store's connections do (``busy_timeout``).
    return sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True, timeout=30)
