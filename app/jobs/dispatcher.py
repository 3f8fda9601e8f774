"""The dispatcher a service process runs: it hands queued runs and jobs to worker processes.

Every ``POLL`` seconds, and at once when a request queues something, it looks in the store
for queued work and, while fewer than ``job_workers`` of its worker processes are busy,
starts ``python -m app.jobs.process`` for the oldest item.

On one host, one service process per store dispatches: the one that holds the store's
dispatch address (an abstract Unix socket named after the store, released by the kernel
when its process ends, kill -9 included).  The others queue work and wake it through that
address, and take its place within ``POLL`` seconds when it ends.  Abstract sockets have
no permissions, so anyone on the host can take the address: a process finding it held by
another user's process dispatches for itself, as every process did before.  So ``touchbench serve
--workers N`` runs at most ``job_workers`` jobs at once, not N times as many, and never
starts two processes for one run.  Worker processes still claim items atomically, as
several hosts on one PostgreSQL store each have a dispatcher; upload folders are on one
host's disk, so extraction jobs are only taken by a dispatcher on the host that received
them.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import math
import os
import select
import socket
import struct
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from sqlalchemy.engine import make_url

from app.settings import Settings
from app.store.database import Store
from app.store.jobs import mark_lost_jobs, queued_jobs
from app.store.runs import list_runs, mark_lost_runs

log = logging.getLogger("touchbench.jobs")

#: Seconds between looks at the queue.
POLL = 0.5

#: Seconds between checks of who holds the dispatch address, by the processes that do not.
HOLDER_CHECK = 10.0


@dataclass
class _Active:
    kind: str
    id: int
    process: subprocess.Popen[bytes]


class Dispatcher:
    """Starts worker processes for queued work; one per item, ``job_workers`` at once.

    Parameters
    ----------
    store : Store
    settings : Settings
        ``job_workers``, ``run_jobs``, ``dask_scheduler``.
    """

    def __init__(self, store: Store, settings: Settings) -> None:
        self.store = store
        self.settings = settings
        self._active: list[_Active] = []
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._address = dispatch_address(store)
        self._inbox: socket.socket | None = None
        self._holder_ours = True  # whether the address's holder runs as this user
        self._holder_checked = -math.inf  # time.monotonic() of the last check
        self._thread = threading.Thread(target=self._loop, daemon=True, name="dispatcher")

    def start(self) -> None:
        self._thread.start()

    def wake(self) -> None:
        """Look at the queue now (a request just queued something), whichever service
        process on this host dispatches for the store."""
        self._wake.set()
        if self._address is not None:
            with (
                contextlib.suppress(OSError),
                socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as caller,
            ):
                caller.setblocking(False)
                caller.connect(self._address)  # the leader's select sees the connection

    @property
    def leading(self) -> bool:
        """Whether this process dispatches for the store on this host."""
        return self._address is None or self._inbox is not None

    def stop(self) -> None:
        """Stop dispatching and end the worker processes (their runs become resumable)."""
        self._stop.set()
        self.wake()
        self._thread.join(timeout=10)
        if self._inbox is not None:
            self._inbox.close()
            self._inbox = None
        for active in self._active:
            with contextlib.suppress(ProcessLookupError):
                active.process.terminate()
        for active in self._active:
            try:
                active.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                active.process.kill()
        mark_lost_runs(self.store)
        mark_lost_jobs(self.store)

    def _loop(self) -> None:
        while not self._stop.is_set():
            dispatching = self.leading or self._lead() or not self._trust_holder()
            try:
                self._reap()
                if dispatching:
                    self._dispatch()
            except Exception as error:  # a busy or unreachable store: try again later
                log.warning("dispatcher: %s: %s", type(error).__name__, error)
            self._wait()

    def _lead(self) -> bool:
        """Take the store's dispatch address if no other process on this host holds it."""
        assert self._address is not None  # else this process always leads
        inbox = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            inbox.bind(self._address)
            inbox.listen(64)
        except OSError:
            inbox.close()
            return False
        inbox.setblocking(False)
        self._inbox = inbox
        log.info("dispatching for %s", self.store.engine.url.render_as_string())
        return True

    def _wait(self) -> None:
        """Wait up to ``POLL`` seconds for a wake-up."""
        if self._inbox is None:
            self._wake.wait(POLL)
            self._wake.clear()
            return
        ready, _, _ = select.select([self._inbox], [], [], POLL)
        while ready:
            try:
                self._inbox.accept()[0].close()
            except BlockingIOError:
                break
        self._wake.clear()

    def _trust_holder(self) -> bool:
        """Whether the process holding the dispatch address dispatches for this one: it runs
        as this user (checked every ``HOLDER_CHECK`` seconds)."""
        if time.monotonic() - self._holder_checked >= HOLDER_CHECK:
            ours = self._holder_is_ours()
            if self._holder_ours and not ours:
                log.warning("another user holds the dispatch address: dispatching from here")
            self._holder_ours, self._holder_checked = ours, time.monotonic()
        return self._holder_ours

    def _holder_is_ours(self) -> bool:
        """Whether the process holding the dispatch address runs as this user (one that
        cannot be reached is not trusted)."""
        assert self._address is not None
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
            probe.settimeout(1.0)
            try:
                probe.connect(self._address)
                credentials = probe.getsockopt(
                    socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i")
                )
            except OSError:
                return False
        _, uid, _ = struct.unpack("3i", credentials)
        return bool(uid == os.getuid())

    def _reap(self) -> None:
        finished = [a for a in self._active if a.process.poll() is not None]
        if not finished:
            return
        self._active = [a for a in self._active if a.process.poll() is None]
        if any(a.process.returncode != 0 for a in finished):
            mark_lost_runs(self.store)
            mark_lost_jobs(self.store)

    def _dispatch(self) -> None:
        while len(self._active) < self.settings.job_workers:
            item = self._next()
            if item is None:
                return
            self._active.append(_Active(item[0], item[1], self._spawn(*item)))

    def _next(self) -> tuple[str, int] | None:
        taken = {(a.kind, a.id) for a in self._active}
        runs = [
            (run.created_at, "run", run.id)
            for run in list_runs(self.store, status="queued")
            if ("run", run.id) not in taken
        ]
        host = socket.gethostname()
        jobs = [
            (job.created_at, "job", job.id)
            for job in queued_jobs(self.store)
            if ("job", job.id) not in taken and job.params.get("host", host) == host
        ]
        waiting = sorted(runs + jobs, key=lambda item: (item[0].timestamp(), item[2]))
        return (waiting[0][1], waiting[0][2]) if waiting else None

    def _spawn(self, kind: str, item_id: int) -> subprocess.Popen[bytes]:
        command = [
            sys.executable,
            "-m",
            "app.jobs.process",
            "--db",
            self.store.url,
            "--jobs",
            str(self.settings.run_jobs),
        ]
        if self.settings.dask_scheduler:
            command += ["--scheduler", self.settings.dask_scheduler]
        command += [kind, str(item_id)]
        environment = dict(os.environ)
        paths = [p for p in sys.path if p]
        environment["PYTHONPATH"] = os.pathsep.join(dict.fromkeys(paths))
        for name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS"):
            environment[name] = "1"
        log.info("starting %s %s", kind, item_id)
        return subprocess.Popen(command, env=environment, stdin=subprocess.DEVNULL)


def dispatch_address(store: Store) -> str | None:
    """The abstract Unix socket address naming ``store``'s dispatcher on this host, or None
    where every service process dispatches for itself: not Linux (no abstract sockets), or
    an in-memory SQLite store (one per process).

    SQLite files are named by their absolute path, so two stores with the same relative
    URL in different folders are two stores.
    """
    url = make_url(store.url)
    if url.get_backend_name() == "sqlite":
        if url.database in (None, "", ":memory:") or "mode=memory" in str(url):
            return None
        url = url.set(database=str(Path(url.database).resolve()))
    if not sys.platform.startswith("linux"):
        return None
    key = url.render_as_string(hide_password=False).encode()
    return "\0touchbench-dispatch-" + hashlib.sha256(key).hexdigest()[:32]
