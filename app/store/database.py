"""Opening a store: the SQLAlchemy engine, SQLite's pragmas, and migrations to head."""

from __future__ import annotations

import contextlib
import functools
import re
import sqlite3
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from sqlalchemy import Engine, create_engine, event, inspect, text
from sqlalchemy.engine import ExceptionContext, make_url
from sqlalchemy.exc import ArgumentError, DatabaseError, OperationalError
from sqlalchemy.sql.compiler import SQLCompiler
from sqlalchemy.sql.elements import ClauseElement

from touchbench.app.errors import AppError, ConflictError
from touchbench.app.store.reading import HEAD_REVISION

if TYPE_CHECKING:
    from sqlalchemy.orm import Session, sessionmaker

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
        self._sessions: sessionmaker[Session] | None = None
        self._compiled: dict[ClauseElement, SQLCompiler] = {}
        self.migrate()

    def migrate(self) -> None:
        """Bring the schema to the newest revision (a no-op when it is there).

        The revision is read with one query; Alembic is imported only when a migration is
        due, which keeps every CLI command's start-up short.  Processes that open a new
        store at the same moment migrate it one at a time: PostgreSQL through an advisory
        lock, SQLite through its write lock taken before the revision is read again.
        """
        try:
            revision = self.revision()
            if revision == HEAD_REVISION:
                return
            if revision is None:
                self._refuse_foreign_database()
            from alembic import command  # start-up time: alembic loads only to migrate
            from alembic.config import Config

            config = Config()
            config.set_main_option("script_location", str(MIGRATIONS))
            with self.engine.begin() as connection:
                _lock_for_migration(connection)
                if _revision(connection) == HEAD_REVISION:
                    return  # another process migrated it while this one waited
                config.attributes["connection"] = connection
                command.upgrade(config, "head")
        except (OperationalError, DatabaseError) as error:
            raise AppError(
                f"cannot open the store at {display_url(self.url)}: {first_line(error.orig)}"
            ) from None

    def _refuse_foreign_database(self) -> None:
        """An unversioned database that holds tables belongs to someone else: never write."""
        tables = sorted(inspect(self.engine).get_table_names())
        if tables:
            shown = ", ".join(tables[:5]) + (f", ... ({len(tables)})" if len(tables) > 5 else "")
            raise AppError(
                f"{display_url(self.url)} holds another application's tables ({shown}) and "
                "no touchbench store; touchbench will not write into it: choose a new file "
                "or an empty database"
            )

    def revision(self) -> str | None:
        """The schema revision the store is at, ``None`` for an empty database."""
        with self.engine.connect() as connection:
            return _revision(connection)

    @contextmanager
    def session(self) -> Iterator[Session]:
        """A session whose transaction commits on success and rolls back on any error."""
        if self._sessions is None:
            # start-up time: the ORM loads with the first session, not with every command
            from sqlalchemy.orm import sessionmaker

            self._sessions = sessionmaker(self.engine, expire_on_commit=False)
        with self._sessions.begin() as session:
            yield session

    def first_row(self, statement: ClauseElement, **params: Any) -> tuple[Any, ...] | None:
        """The first row of a read-only ``statement`` with bound ``params``, or ``None``.

        Run on the driver's own cursor, compiled once per statement: for a lookup on an
        index SQLAlchemy's execution machinery costs several times the query itself, and the
        service asks one on every prediction.
        """
        compiled = self._compiled.get(statement)
        if compiled is None:
            compiled = cast(SQLCompiler, statement.compile(dialect=self.engine.dialect))
            self._compiled[statement] = compiled
        values = compiled.construct_params(params) or {}
        arguments: Any = values
        if compiled.positional:
            arguments = tuple(values[name] for name in compiled.positiontup or ())
        connection = self.engine.raw_connection()
        try:
            cursor = connection.cursor()
            try:
                cursor.execute(compiled.string, arguments)
                row = cursor.fetchone()
            finally:
                cursor.close()
        finally:
            connection.close()  # back to the pool, which ends the read's transaction
        return None if row is None else tuple(row)

    @contextmanager
    def reading(self) -> Iterator[Any]:
        """A DB-API connection of the pool for reading (:mod:`app.store.reading`): its
        transaction ends when it goes back to the pool, with the block."""
        connection = self.engine.raw_connection()
        try:
            yield connection
        finally:
            connection.close()

    def dispose(self) -> None:
        self.engine.dispose()


#: Key of the PostgreSQL advisory lock held while a store is migrated.
_MIGRATION_LOCK = 0x746F7563  # "touc"


def _revision(connection: Any) -> str | None:
    if not inspect(connection).has_table("alembic_version"):
        return None
    value = connection.execute(text("SELECT version_num FROM alembic_version")).scalar()
    return None if value is None else str(value)


def _lock_for_migration(connection: Any) -> None:
    """Hold, until the transaction ends, a lock that other migrating processes wait for."""
    if connection.dialect.name == "postgresql":
        connection.execute(text(f"SELECT pg_advisory_xact_lock({_MIGRATION_LOCK})"))
    elif connection.dialect.name == "sqlite":
        # Python's sqlite3 opens no transaction before DDL, so each CREATE TABLE would
        # commit on its own and two processes would both create the schema: take SQLite's
        # write lock explicitly; the migration's DDL then runs, and commits, inside it.
        connection.exec_driver_sql("BEGIN IMMEDIATE")


def _normalise(url: str) -> str:
    if url.startswith("postgresql://") or url.startswith("postgres://"):
        return "postgresql+psycopg://" + url.split("://", 1)[1]
    return url


def display_url(url: str) -> str:
    """``url`` as a message or a log line may show it: with its password hidden (``***``).

    Every URL of a store that touchbench prints goes through here.  Everything between
    ``user:`` and the last ``@`` is hidden too, in a URL that does not parse as in one that
    does: a password with an unescaped ``@`` in it would otherwise show its end as the host.
    """
    try:
        shown = make_url(url).render_as_string(hide_password=True)
    except (ArgumentError, ValueError):
        shown = url
    return _USER_PASSWORD.sub(r"\1***@", shown, count=1)


#: ``scheme://user:`` and what follows it up to the last ``@``: where a password may be.
_USER_PASSWORD = re.compile(r"(://[^:/@]*:).*@")


def _create_engine(url: str) -> Engine:
    try:
        parsed = make_url(url)
    except (ArgumentError, ValueError):  # ValueError: a port that is not a number
        raise AppError(
            f"not a database URL: '{display_url(url)}' (e.g. sqlite:///touchbench.db)"
        ) from None
    options: dict[str, Any] = {}
    if parsed.get_backend_name() == "sqlite":
        database = parsed.database or ""
        if database and database != ":memory:":
            _check_sqlite_file(Path(database), url)
        options["connect_args"] = {"timeout": 30}
    try:
        engine = create_engine(parsed, **options)
    except (ArgumentError, ImportError) as error:
        raise AppError(f"cannot use the database URL '{display_url(url)}': {error}") from None
    if parsed.get_backend_name() == "sqlite":
        event.listen(engine, "connect", _sqlite_pragmas)
    event.listen(engine, "handle_error", functools.partial(_refuse_read_only, url))
    return engine


#: SQLite's result code for a write to a read-only database (the low byte of the extended
#: codes, e.g. SQLITE_READONLY_DIRECTORY); PostgreSQL's SQLSTATE for a read-only transaction.
_SQLITE_READONLY = 8
_PG_READ_ONLY = "25006"


def _refuse_read_only(url: str, context: ExceptionContext) -> None:
    """A write to a read-only store (a file or mount without write access, a standby
    server), as the one line of a :class:`~app.errors.ConflictError` instead of the
    driver's error with the statement and its parameters."""
    original = context.original_exception
    sqlite_code = getattr(original, "sqlite_errorcode", None)
    read_only = (isinstance(sqlite_code, int) and sqlite_code & 0xFF == _SQLITE_READONLY) or (
        getattr(original, "sqlstate", None) == _PG_READ_ONLY
    )
    if read_only:
        raise ConflictError(
            f"the store at {display_url(url)} is read-only ({first_line(original)}); give "
            "this process write access to it, or use another store"
        ) from None


def _check_sqlite_file(path: Path, url: str) -> None:
    """Refuse a path that cannot hold a SQLite store before SQLite touches it."""
    if not path.parent.is_dir():
        raise AppError(
            f"cannot open the store at {display_url(url)}: folder {path.parent} does not exist"
        )
    if not path.exists():
        return
    if not path.is_file():
        raise AppError(f"cannot open the store at {display_url(url)}: {path} is not a regular file")
    if path.stat().st_size == 0:
        return

    # Through SQLite itself, read-only: opening and closing the file any other way would
    # drop the POSIX locks this process's own connections hold on it (SQLite shares them
    # between its connections), and SQLite's WAL pragma must not touch a foreign file.
    try:
        with contextlib.closing(sqlite3.connect(f"file:{path}?mode=ro", uri=True)) as peek:
            tables = {name for (name,) in peek.execute("SELECT name FROM sqlite_master")}
    except sqlite3.DatabaseError as error:
        reason = "is not a SQLite database" if "not a database" in str(error) else str(error)
        raise AppError(f"cannot open the store at {display_url(url)}: {path} {reason}") from None
    if tables and "alembic_version" not in tables:
        shown = ", ".join(sorted(tables)[:5])
        raise AppError(
            f"{path} is another application's SQLite database (tables: {shown}); touchbench "
            "will not write into it: choose a new file"
        )


def _sqlite_pragmas(dbapi_connection: Any, _record: Any) -> None:
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA busy_timeout=30000")
    # Pages of 64 KiB (a new database's only: an existing one keeps its own) halve the cost
    # of writing and checkpointing the megabyte blocks of instances an import stores.
    cursor.execute("PRAGMA page_size=65536")
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.close()


def first_line(error: object) -> str:
    """The first line of ``error``'s message (its type's name when it has none): driver and
    SQLAlchemy errors add the statement, hints and a link on lines of their own."""
    return str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
