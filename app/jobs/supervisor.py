"""The worker processes of a dispatcher: started one per item, at most ``limit`` at once,
reaped when they end, ended when the dispatcher stops."""

from __future__ import annotations

import contextlib
import logging
import subprocess
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from touchbench.app.jobs.queue import Item

log = logging.getLogger("touchbench.jobs")


@dataclass
class _Worker:
    item: Item
    process: subprocess.Popen[bytes]


class Supervisor:
    """Starts, counts and ends the worker processes.

    Parameters
    ----------
    limit : int
        Most processes alive at once.
    command : callable
        The command line of the process for an item.  It must hold nothing secret: any user
        on the host reads it (``ps``, ``/proc/PID/cmdline``).
    environment : callable
        The environment of a new process (read when it starts; only its user and root can
        read it, ``/proc/PID/environ``).
    """

    def __init__(
        self,
        limit: int,
        command: Callable[[Item], Sequence[str]],
        environment: Callable[[], Mapping[str, str]],
    ) -> None:
        self.limit = limit
        self._command = command
        self._environment = environment
        self._workers: list[_Worker] = []

    @property
    def busy(self) -> frozenset[Item]:
        """The items whose processes have not been reaped yet."""
        return frozenset(worker.item for worker in self._workers)

    @property
    def full(self) -> bool:
        """Whether ``limit`` processes are alive."""
        return len(self._workers) >= self.limit

    def start(self, item: Item) -> None:
        """Start the process for ``item``."""
        log.info("starting %s %s", item.kind, item.id)
        process = subprocess.Popen(
            list(self._command(item)), env=dict(self._environment()), stdin=subprocess.DEVNULL
        )
        self._workers.append(_Worker(item, process))

    def reap(self) -> bool:
        """Forget the processes that ended; whether any of them failed (a status not 0)."""
        ended = [worker for worker in self._workers if worker.process.poll() is not None]
        if not ended:
            return False
        self._workers = [worker for worker in self._workers if worker not in ended]
        return any(worker.process.returncode != 0 for worker in ended)

    def stop(self, grace: float = 10.0) -> None:
        """End every process: SIGTERM, then SIGKILL for one still alive after ``grace``."""
        for worker in self._workers:
            with contextlib.suppress(ProcessLookupError):
                worker.process.terminate()
        for worker in self._workers:
            try:
                worker.process.wait(timeout=grace)
            except subprocess.TimeoutExpired:
                worker.process.kill()
                worker.process.wait()
        self._workers = []
