"""The life of a run or a job: which status may become which, and what a request that does
not fit the item's state is told (a :class:`~app.errors.ConflictError`, HTTP 409, exit 2).

A run:

::

    queued ──claim──► running ──► done | failed
      │                 │  └─(process lost, Ctrl-C, SIGTERM)──► interrupted
      │                 └─cancel──► cancelling ──(the process stops)──► cancelled
      └─cancel──► cancelled
    interrupted | cancelled | failed ──resume──► queued

A job (an extraction, a training) lives the same life but is never resumed: a job whose
process was lost is ``interrupted`` for good, and is submitted again instead.

An item is *active* while a process executes it (``running``, ``cancelling``); a cancel of
an active item asks its process to stop (status ``cancelling`` until it has), a cancel of
any other unfinished item takes effect at once.  Every rule about these changes lives here
(the statuses and their named sets are :mod:`app.schemas.status`); the store's functions
(:mod:`app.store.runs`, :mod:`app.store.jobs`, the protocol both follow in
:mod:`app.store.queue`) apply them.
"""

from __future__ import annotations

from typing import Protocol

from touchbench.app.errors import ConflictError
from touchbench.app.schemas.status import ACTIVE, FINAL, Status

#: What a process whose owner died leaves, of a run or a job: a running one is interrupted,
#: one being cancelled is cancelled (its process stopped, as asked).
LOST_AS: dict[Status, Status] = {
    Status.RUNNING: Status.INTERRUPTED,
    Status.CANCELLING: Status.CANCELLED,
}


class Item(Protocol):
    """What the rules read of a run or a job."""

    @property
    def id(self) -> int: ...

    @property
    def status(self) -> str: ...

    def owner_alive(self) -> bool: ...


class Claimed(Item, Protocol):
    """What the rules of claims read of a run (:class:`app.store.runs.RunInfo`): who
    executes it, and when it was last heard from.  A protocol, so that these rules sit
    below the store's runs, which apply them."""

    @property
    def owner(self) -> str | None: ...

    def seconds_since_heartbeat(self) -> float: ...


class RunBusy(ConflictError):  # noqa: N818 (a state, like ConflictError's other cases)
    """Another live process executes the run."""

    def __init__(self, run: Claimed) -> None:
        super().__init__(
            f"run {run.id} is being executed by {run.owner} (heard from "
            f"{run.seconds_since_heartbeat():.0f} s ago); wait for it to end or cancel it"
        )
        self.run_id = run.id


def is_active(item: Item) -> bool:
    """Whether a live process executes the item."""
    return item.status in ACTIVE and item.owner_alive()


def check_claim(run: Claimed, owner: str) -> None:
    """Refuse to let ``owner`` execute a run that another live process executes or that is
    being cancelled.

    Raises
    ------
    RunBusy
        Another live process executes it.
    ConflictError
        It is being cancelled.
    """
    if run.status == Status.CANCELLING and run.owner_alive():
        raise ConflictError(f"run {run.id} is being cancelled; resume it once it is cancelled")
    if run.status == Status.RUNNING and run.owner != owner and run.owner_alive():
        raise RunBusy(run)


def cancel_outcome(item: Item, kind: str = "run") -> str:
    """What a cancel does to a run or a job (``kind``): ``cancelling`` (its process is asked
    to stop), ``cancelled`` (at once), or ``unchanged`` (a cancel already asked).

    Raises
    ------
    ConflictError
        The item is done, failed or already cancelled; a job that was interrupted.
    """
    # an interrupted run waits to be resumed, and a cancel settles it; a job is never resumed
    over = FINAL if kind == "job" else FINAL - {Status.INTERRUPTED}
    if item.status in over:
        raise ConflictError(f"{kind} {item.id} is already {item.status}; nothing to cancel")
    if item.status == Status.CANCELLING and item.owner_alive():
        return "unchanged"
    return Status.CANCELLING if is_active(item) else Status.CANCELLED


def check_resume(run: Item) -> None:
    """Refuse to queue again a run that is queued, executing, being cancelled or done.

    Raises
    ------
    ConflictError
    """
    if run.status == Status.CANCELLING and run.owner_alive():
        raise ConflictError(
            f"run {run.id} is being cancelled; resume it once it is cancelled (its process "
            "stops within a second)"
        )
    if run.status == Status.RUNNING and run.owner_alive():
        raise ConflictError(f"run {run.id} is running; nothing to resume")
    if run.status == Status.DONE:
        raise ConflictError(f"run {run.id} is done; nothing to resume")
    if run.status == Status.QUEUED:
        raise ConflictError(f"run {run.id} is queued already; it starts when a worker is free")
