"""What every command shares: the store URL from ``--db`` and the store opened lazily."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import typer

if TYPE_CHECKING:
    from touchbench.app.store.database import Store
    from touchbench.app.store.reading import Readable


@dataclass
class CliState:
    database_url: str
    _store: Store | None = field(default=None, repr=False)

    @property
    def store(self) -> Store:
        if self._store is None:
            # loaded when the command runs: start-up time (SQLAlchemy and the store's tables)
            from touchbench.app.store.database import Store

            self._store = Store(self.database_url)
        return self._store

    @property
    def reader(self) -> Readable:
        """The store for a command that only reads it: a SQLite file at the newest revision
        read without SQLAlchemy, else :attr:`store`."""
        if self._store is not None:
            return self._store
        # loaded when the command runs: start-up time (sqlite3 only)
        from touchbench.app.store.reading import sqlite_file

        return sqlite_file(self.database_url) or self.store


def get_state(ctx: typer.Context) -> CliState:
    state = ctx.find_root().obj
    assert isinstance(state, CliState), "the root callback sets the CLI state"
    return state
