"""Opening a store: the SQLAlchemy engine, SQLite's pragmas, and migrations to head."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError, OperationalError
from sqlalchemy.orm import Session, sessionmaker

from app.errors import AppError

MIGRATIONS = Path(__file__).with_name("migrations")


class Store:
    """A touchbench store at a SQLAlchemy URL, migrated to the newest schema on open.

    Parameters
    ----------
    url : str
        Any SQLAlchemy URL: ``sqlite:///touchbench.db``,
        ``postgresql+psycopg://user@host/db`` (``postgresql://`` means psycopg 3 here).
    """

    def __init__(self, url: str) -> None:
        self.url = _normalise(url)
        self.engine = _create_engine(self.url)
        self._sessions = sessionmaker(self.engine, expire_on_commit=False)
        self.migrate()

    def migrate(self) -> None:
        """Bring the schema to the newest revision (a no-op when it is there)."""
        config = Config()
        config.set_main_option("script_location", str(MIGRATIONS))
        head = ScriptDirectory.from_config(config).get_current_head()
        try:
            with self.engine.begin() as connection:
                current = MigrationContext.configure(connection).get_current_heads()
                if head in current:
                    return
                config.attributes["connection"] = connection
                command.upgrade(config, "head")
        except OperationalError as error:
            raise AppError(
                f"cannot open the store at {self.engine.url.render_as_string()}: "
                f"{_first_line(error.orig)}"
            ) from None

    @contextmanager
    def session(self) -> Iterator[Session]:
        """A session whose transaction commits on success and rolls back on any error."""
        with self._sessions.begin() as session:
            yield session

    def dispose(self) -> None:
        self.engine.dispose()


def _normalise(url: str) -> str:
    if url.startswith("postgresql://") or url.startswith("postgres://"):
        return "postgresql+psycopg://" + url.split("://", 1)[1]
    return url


def _create_engine(url: str) -> Engine:
    try:
        parsed = make_url(url)
    except ArgumentError:
        raise AppError(f"not a database URL: '{url}' (e.g. sqlite:///touchbench.db)") from None
    options: dict[str, Any] = {}
    if parsed.get_backend_name() == "sqlite":
        database = parsed.database or ""
        if database and database != ":memory:" and not Path(database).parent.exists():
            raise AppError(f"cannot open the store at {url}: folder does not exist")
        options["connect_args"] = {"timeout": 30}
    try:
        engine = create_engine(url, **options)
    except (ArgumentError, ImportError) as error:
        raise AppError(f"cannot use the database URL '{url}': {error}") from None
    if parsed.get_backend_name() == "sqlite":
        event.listen(engine, "connect", _sqlite_pragmas)
    return engine


def _sqlite_pragmas(dbapi_connection: Any, _record: Any) -> None:
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.close()


def _first_line(error: object) -> str:
    return str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
