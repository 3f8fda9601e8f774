"""The dispatcher a service process runs: it hands queued runs and jobs to worker processes.

Every ``POLL`` seconds, and at once when a request queues something, it looks in the store
for queued work and, while fewer than ``job_workers`` of its worker processes are busy,
starts ``python -m app.jobs.process`` for the oldest item.

It wires three parts together: :mod:`app.jobs.leadership` (on one host, one service process
per store dispatches, so ``touchbench serve --workers N`` runs at most ``job_workers`` jobs
at once, not N times as many, and never starts two processes for one run),
:mod:`app.jobs.queue` (queued runs and jobs, oldest first, extraction jobs only on the host
that received their upload) and :mod:`app.jobs.supervisor` (the worker processes).  Worker
processes still claim items atomically, as several hosts on one PostgreSQL store each have
a dispatcher.

A worker process gets the store's URL in its environment, never on its command line, which
any user on the host can read: the URL may hold a PostgreSQL password.
"""

from __future__ import annotations

import logging
import os
import sys
import threading

from touchbench.app.jobs.leadership import Leadership, address_for
from touchbench.app.jobs.process import DATABASE_URL_VARIABLE
from touchbench.app.jobs.queue import Item, next_item
from touchbench.app.jobs.supervisor import Supervisor
from touchbench.app.settings import Settings
from touchbench.app.store.database import Store, display_url, first_line
from touchbench.app.store.jobs import mark_lost_jobs
from touchbench.app.store.runs import mark_lost_runs

log = logging.getLogger("touchbench.jobs")

#: Seconds between looks at the queue.
POLL = 0.5

#: Variables that set the thread count of numpy's BLAS and of OpenMP, pinned to 1 in a
#: worker process (its run has ``run_jobs`` engine processes of its own).
_NATIVE_THREADS = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS")


class Dispatcher:
    """Starts worker processes for queued work; one per item, ``job_workers`` at once.

    Parameters
    ----------
    store : Store
    settings : Settings
        ``job_workers``, ``run_jobs``, ``job_nice``, ``dask_scheduler``.
    """

    def __init__(self, store: Store, settings: Settings) -> None:
        self.store = store
        self.settings = settings
        self._leadership = Leadership(dispatch_address(store), display_url(store.url))
        self._workers = Supervisor(settings.job_workers, self._command, self._environment)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True, name="dispatcher")

    def start(self) -> None:
        self._thread.start()

    def wake(self) -> None:
        """Look at the queue now (a request just queued something), whichever service
        process on this host dispatches for the store."""
        self._leadership.wake()

    @property
    def leading(self) -> bool:
        """Whether this process dispatches for the store on this host."""
        return self._leadership.leading

    def stop(self) -> None:
        """Stop dispatching and end the worker processes (their runs become resumable)."""
        self._stop.set()
        self.wake()
        self._thread.join(timeout=10)
        self._leadership.release()
        self._workers.stop()
        self._mark_lost()

    def _loop(self) -> None:
        while not self._stop.is_set():
            dispatching = self._leadership.dispatches()
            try:
                if self._workers.reap():
                    self._mark_lost()
                if dispatching:
                    self._dispatch()
            except Exception as error:  # a busy or unreachable store: try again later
                log.warning("dispatcher: %s: %s", type(error).__name__, first_line(error))
            self._leadership.wait(POLL)

    def _dispatch(self) -> None:
        while not self._workers.full:
            item = next_item(self.store, taken=self._workers.busy)
            if item is None:
                return
            self._workers.start(item)

    def _mark_lost(self) -> None:
        """Runs and jobs whose process died without recording how they ended."""
        mark_lost_runs(self.store)
        mark_lost_jobs(self.store)

    def _command(self, item: Item) -> list[str]:
        command = [
            sys.executable,
            "-m",
            "touchbench.app.jobs.process",
            "--jobs",
            str(self.settings.run_jobs),
            "--nice",
            str(self.settings.job_nice),
        ]
        if self.settings.dask_scheduler:
            command += ["--scheduler", self.settings.dask_scheduler]
        return [*command, item.kind, str(item.id)]

    def _environment(self) -> dict[str, str]:
        environment = dict(os.environ)
        environment[DATABASE_URL_VARIABLE] = self.store.url
        paths = [p for p in sys.path if p]
        environment["PYTHONPATH"] = os.pathsep.join(dict.fromkeys(paths))
        for name in _NATIVE_THREADS:
            environment[name] = "1"
        return environment


def dispatch_address(store: Store) -> str | None:
    """The abstract Unix socket address naming ``store``'s dispatcher on this host, or None
    where every service process dispatches for itself (see
    :func:`app.jobs.leadership.address_for`)."""
    return address_for(store.url)
