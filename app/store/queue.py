"""The protocol every queued item follows, a run or a job: claimed by one process, which
keeps a heartbeat while it works and hears a cancel through it, then finished.

Runs (:mod:`app.store.runs`) and jobs (:mod:`app.store.jobs`) are rows of two tables with
the same columns for it: ``status``, ``owner`` (``host:pid@start`` of the process executing
the item), ``heartbeat_at`` and ``cancel_requested``.  The rules of which status may become
which are in :mod:`app.store.states`; this module reads and writes them.

The executing process looks for a cancel every :data:`CANCEL_POLL` seconds (one read of the
item's row by its primary key, cheap enough on either store to take a few times a second)
and writes its heartbeat every :data:`HEARTBEAT_INTERVAL` seconds, so that a cancel is heard
within a fraction of a second while the store takes a write only every few seconds.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.orm import Session

from touchbench.app.schemas.status import ACTIVE, Status
from touchbench.app.store.database import Store
from touchbench.app.store.states import Item, cancel_outcome
from touchbench.app.store.tables import utcnow

#: Seconds between heartbeats of the process executing an item.
HEARTBEAT_INTERVAL = 5.0
#: Seconds between the executing process's looks for a cancel request.
CANCEL_POLL = 0.2


def beat(store: Store, table: Any, item_id: int, owner: str) -> bool:
    """Say that ``owner`` still executes the item; returns whether it should stop (see
    :func:`should_stop`)."""
    with store.session() as session:
        session.execute(
            update(table)
            .where(table.id == item_id, table.owner == owner, table.status.in_(ACTIVE))
            .values(heartbeat_at=utcnow())
        )
        return _should_stop(session, table, item_id, owner)


def should_stop(store: Store, table: Any, item_id: int, owner: str) -> bool:
    """Whether the process ``owner`` executing the item should stop: a cancel was requested,
    or the item was taken away from it (deleted, claimed by another process)."""
    with store.session() as session:
        return _should_stop(session, table, item_id, owner)


def _should_stop(session: Session, table: Any, item_id: int, owner: str) -> bool:
    row = session.execute(
        select(table.cancel_requested, table.owner, table.status).where(table.id == item_id)
    ).one_or_none()
    if row is None:
        return True
    cancel, current_owner, status = row
    return bool(cancel) or current_owner != owner or status not in ACTIVE


def request_cancel(store: Store, table: Any, item: Item, kind: str) -> str:
    """Apply a cancel to ``item`` (a run's or job's description, as read just before):
    ask its process to stop, or cancel it at once (see
    :func:`app.store.states.cancel_outcome`).

    Returns
    -------
    str
        ``cancelling``, ``cancelled``, ``unchanged``, or ``changed`` when the item's status
        changed meanwhile (read it again and ask again).

    Raises
    ------
    ConflictError
        The item is over.
    """
    outcome = cancel_outcome(item, kind)
    if outcome == "unchanged":
        return outcome
    values: dict[str, Any] = {"status": outcome}
    if outcome == Status.CANCELLING:
        values["cancel_requested"] = True
    else:
        values.update(finished_at=utcnow(), owner=None, heartbeat_at=None)
    with store.session() as session:
        written = session.execute(
            update(table)
            .where(table.id == item.id, table.status == item.status)
            .values(**values)
            .execution_options(synchronize_session=False)
        ).rowcount  # type: ignore[attr-defined]  # an UPDATE gives a CursorResult
    return outcome if written else "changed"


class Heartbeat:
    """A thread that keeps an item's heartbeat and calls ``on_stop`` once when the item
    should stop (:func:`should_stop`)."""

    def __init__(
        self,
        store: Store,
        table: Any,
        item_id: int,
        owner: str,
        on_stop: Callable[[], None],
    ) -> None:
        self._store = store
        self._table = table
        self._item_id = item_id
        self._owner = owner
        self._on_stop = on_stop
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._beat, daemon=True, name="heartbeat")

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._done.set()
        if self._thread.is_alive():
            self._thread.join(timeout=HEARTBEAT_INTERVAL * 2)

    def _beat(self) -> None:
        next_beat = time.monotonic() + HEARTBEAT_INTERVAL
        told = False
        while not self._done.wait(CANCEL_POLL):
            try:
                if time.monotonic() >= next_beat:
                    next_beat = time.monotonic() + HEARTBEAT_INTERVAL
                    stop = beat(self._store, self._table, self._item_id, self._owner)
                else:
                    stop = should_stop(self._store, self._table, self._item_id, self._owner)
            except Exception:  # a busy store: try again at the next look
                continue
            if stop and not told:
                told = True
                self._on_stop()
