"""The store a Python call works in: one the caller names (a URL, or a path to a SQLite
file, which the CLI and the service read too), or a temporary SQLite file that lives as
long as the Python session holds what was made in it."""

from __future__ import annotations

import atexit
import shutil
import tempfile
from pathlib import Path

from touchbench.app.store.database import Store

#: A store as the Python API takes it: ``None`` (in memory), a URL or a path.
StoreLike = Store | str | Path | None

_temporary: Store | None = None


def store_url(store: str | Path) -> str:
    """A URL as given, or a path as the URL of its SQLite file."""
    text = str(store)
    if "://" in text:
        return text
    return f"sqlite:///{Path(text).expanduser().resolve()}"


def open_store(store: StoreLike) -> Store:
    """The store of ``store``: itself, the one its URL or path names, or the session's
    temporary store (``None``), made on first use and removed when Python exits."""
    global _temporary
    if isinstance(store, Store):
        return store
    if store is not None:
        # opened afresh on each call (the leaderboards and models made keep theirs): a
        # store its owner replaced meanwhile is seen as it now is
        return Store(store_url(store))
    if _temporary is None:
        folder = tempfile.mkdtemp(prefix="touchbench-")
        _temporary = Store(f"sqlite:///{folder}/touchbench.db")
        atexit.register(_remove, _temporary, folder)
    return _temporary


def _remove(store: Store, folder: str) -> None:
    store.dispose()
    shutil.rmtree(folder, ignore_errors=True)
