"""Which process executes a run or a job, and whether it is still alive.

An owner is ``host:pid@start`` (the start time tells a live process from a later one that
reuses its pid); a process on this host is looked up directly, one elsewhere is judged by
the heartbeat it writes.  Runs and jobs left ``running`` by a dead owner are *lost*.
"""

from __future__ import annotations

import os
import socket
from datetime import UTC, datetime, timedelta
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.orm import Session

from touchbench.app.schemas.status import Status
from touchbench.app.store.naming import is_decimal

#: A running item whose heartbeat is older than this has lost its process.
STALE_AFTER = 30.0


def process_owner(pid: int | None = None) -> str:
    """``host:pid@start`` of this process (or of ``pid`` on this host)."""
    pid = os.getpid() if pid is None else pid
    return f"{socket.gethostname()}:{pid}@{_start_ticks(pid)}"


def owner_alive(owner: str | None, heartbeat_at: datetime | None) -> bool:
    """Whether the process ``owner`` still runs: looked up directly when it is on this host,
    judged by its heartbeat otherwise."""
    if not owner:
        return False
    host, _, rest = owner.partition(":")
    pid_text, _, start = rest.partition("@")
    if host == socket.gethostname() and is_decimal(pid_text):
        return start == _start_ticks(int(pid_text)) != ""
    if heartbeat_at is None:
        return False
    return datetime.now(UTC) - aware(heartbeat_at) < timedelta(seconds=STALE_AFTER)


def mark_lost(
    session: Session, table: Any, *, of: Status = Status.RUNNING, **values: Any
) -> list[int]:
    """Set ``values`` on the rows of ``table`` left in status ``of`` by a dead owner; their
    ids.

    ``table`` is a mapped class with ``id``, ``status``, ``owner`` and ``heartbeat_at``.
    """
    running = session.execute(
        select(table.id, table.owner, table.heartbeat_at).where(table.status == of)
    ).all()
    lost = [item for item, owner, beat in running if not owner_alive(owner, beat)]
    if lost:
        session.execute(
            update(table)
            .where(table.id.in_(lost))
            .values(**values)
            .execution_options(synchronize_session=False)
        )
    return lost


def aware(moment: datetime) -> datetime:
    """SQLite hands timestamps back without their time zone: they are UTC."""
    return moment if moment.tzinfo is not None else moment.replace(tzinfo=UTC)


def _start_ticks(pid: int) -> str:
    """The start time of process ``pid`` in clock ticks since boot; '' if it does not exist."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return ""
