"""Where a run or a job is in its life, and the sets of statuses that rules and views name.

Runs and jobs live the same life (the diagram and every rule of which status may become
which: :mod:`app.store.states`); a job is never resumed.  This module is the only place a
status is spelt: everything else names :class:`Status` members and the sets below.
"""

from __future__ import annotations

from enum import StrEnum


class Status(StrEnum):
    """Where a run or a job is in its life; stored and shown as the value (queued, ...)."""

    #: Created, waiting for a worker.
    QUEUED = "queued"
    #: A process executes it.
    RUNNING = "running"
    #: Its process was asked to stop and has not yet.
    CANCELLING = "cancelling"
    #: Every task has a result (a job: its work ended well).
    DONE = "done"
    #: Every task failed, or it could not be carried out.
    FAILED = "failed"
    #: Cancelled on request.
    CANCELLED = "cancelled"
    #: Its process stopped (Ctrl-C, kill -9, a crash); resuming a run finishes it.
    INTERRUPTED = "interrupted"


#: A process executes the item.
ACTIVE: frozenset[Status] = frozenset({Status.RUNNING, Status.CANCELLING})
#: Nothing more happens unless the run is resumed.
FINAL: frozenset[Status] = frozenset(
    {Status.DONE, Status.FAILED, Status.CANCELLED, Status.INTERRUPTED}
)
#: Under way: waiting for a worker or executed (a data set under such a run stays).
UNFINISHED: frozenset[Status] = frozenset(Status) - FINAL
#: What a resume puts back in the queue (see :func:`app.store.states.check_resume`).
RESUMABLE: frozenset[Status] = frozenset({Status.INTERRUPTED, Status.CANCELLED, Status.FAILED})
#: Stopped before the end: a run's entries without a result never started.
STOPPED_EARLY: frozenset[Status] = RESUMABLE | {Status.CANCELLING}
