"""Opening a store: the SQLAlchemy engine, SQLite's pragmas, and migrations to head."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event, text
from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError, OperationalError, ProgrammingError
from sqlalchemy.orm import Session, sessionmaker

from app.errors import AppError

MIGRATIONS = Path(__file__).with_name("migrations")
#: The newest migration; a test checks it against Alembic's own idea of the head.
HEAD_REVISION = "0003"


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
        """Bring the schema to the newest revision (a no-op when it is there).

        The revision is read with one query; Alembic is imported only when a migration is
        due, which keeps every CLI command's start-up short.
        """
        try:
            if self.revision() == HEAD_REVISION:
                return
            from alembic import command
            from alembic.config import Config

            config = Config()
            config.set_main_option("script_location", str(MIGRATIONS))
            with self.engine.begin() as connection:
                config.attributes["connection"] = connection
                command.upgrade(config, "head")
        except OperationalError as error:
            raise AppError(
                f"cannot open the store at {self.engine.url.render_as_string()}: "
                f"{_first_line(error.orig)}"
            ) from None

    def revision(self) -> str | None:
        """The schema revision the store is at, ``None`` for an empty database."""
        with self.engine.connect() as connection:
            try:
                return connection.execute(
                    text("SELECT version_num FROM alembic_version")
                ).scalar_one_or_none()
            except (OperationalError, ProgrammingError) as error:
                if "alembic_version" in str(error):
                    return None
                raise

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
