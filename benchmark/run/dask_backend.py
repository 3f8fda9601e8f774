"""Running the engine's tasks on an existing Dask distributed cluster.

The run's pickled :class:`~benchmark.run.task.TaskContext` is scattered to every Dask worker
once.  Each Dask worker thread keeps one :class:`~benchmark.run.worker.Worker` subprocess per
run (Dask worker processes are daemonic and may not fork ``multiprocessing`` children,
but they may start subprocesses), so time limits and crash isolation work as they do
locally.  The client keeps as many tasks in flight as the cluster has threads, so that
``on_start`` is called roughly when a task really starts.
"""

from __future__ import annotations

import contextlib
import re
import threading
import uuid
from dataclasses import dataclass
from queue import Empty, SimpleQueue
from typing import TYPE_CHECKING, Any

from touchbench.benchmark.errors import BenchmarkError, ConfigurationError
from touchbench.benchmark.results import TaskKey, TaskResult
from touchbench.benchmark.run.backend import (
    STOP_POLL,
    ResultCallback,
    RunStopped,
    StartCallback,
    StopCheck,
    timed_out,
    worker_could_not_start,
)
from touchbench.benchmark.run.schedule import TaskSource
from touchbench.benchmark.run.task import failed_result
from touchbench.benchmark.run.worker import Worker, WorkerDiedError

if TYPE_CHECKING:
    from distributed import Future

#: Seconds to wait for the scheduler to answer.
CONNECT_TIMEOUT = "10s"
_ADDRESS = re.compile(
    r"(?P<protocol>(?:tcp|tls)://)?(?P<host>\[[0-9a-fA-F:]+\]|[\w.-]+):(?P<port>\d{1,5})"
)

_LOCAL_WORKERS: dict[tuple[str, int], Worker] = {}
_LOCAL_LOCK = threading.Lock()


def check_scheduler_address(address: str) -> str:
    """``address`` if it reads as a Dask scheduler address (``tcp://host:port``).

    Raises
    ------
    ConfigurationError
        Anything else, before any connection is tried.
    """
    match = _ADDRESS.fullmatch(address.strip())
    if match is None or not 0 < int(match["port"]) < 65536:
        raise ConfigurationError(
            f"'{address}' is not a Dask scheduler address (expected tcp://HOST:PORT, e.g. "
            "tcp://10.0.0.5:8786)"
        )
    return f"{match['protocol'] or 'tcp://'}{match['host']}:{match['port']}"


def connect(address: str) -> Any:
    """A Dask client of the scheduler at ``address``.

    Raises
    ------
    ConfigurationError
        A malformed address, or no scheduler answers within :data:`CONNECT_TIMEOUT`.
    """
    from distributed import Client

    address = check_scheduler_address(address)
    try:
        return Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        reason = str(exc).splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ConfigurationError(
            f"cannot reach the Dask scheduler at {address}: {reason}"
        ) from None


@dataclass(frozen=True)
class DaskBackend:
    """The workers of the Dask distributed cluster at ``scheduler``.

    Parameters
    ----------
    scheduler : str
        The scheduler's address (``tcp://host:port``); it is connected to by :meth:`run`.
    context : bytes
        The run's pickled :class:`~benchmark.run.task.TaskContext`, scattered to every
        Dask worker once.
    timeout : float or None
        Seconds one task may take before its worker process is killed; ``None`` for no limit.
    max_memory : int or None
        Bytes one task may allocate beyond its worker process's copy of the data.
    """

    scheduler: str
    context: bytes
    timeout: float | None
    max_memory: int | None

    def run(
        self,
        tasks: TaskSource,
        on_start: StartCallback,
        deliver: ResultCallback,
        stop: StopCheck,
    ) -> None:
        """Run ``tasks`` (see :meth:`benchmark.run.backend.Backend.run`).

        Raises
        ------
        ConfigurationError
            The scheduler cannot be reached.
        RunStopped
            ``stop`` returned true (the tasks in flight are cancelled, their worker
            processes killed).
        """
        client = connect(self.scheduler)
        token = uuid.uuid4().hex
        try:
            [data] = client.scatter([self.context], broadcast=True, hash=False)
            slots = max(1, sum(client.nthreads().values()))
            in_flight: dict[Future, TaskKey] = {}
            # Dask calls the callbacks in its own thread; this thread waits on the queue.
            finished: SimpleQueue[Future] = SimpleQueue()
            while not tasks.exhausted or in_flight:
                if stop():
                    client.cancel(list(in_flight))
                    raise RunStopped
                while len(in_flight) < slots and (key := tasks.next_task()) is not None:
                    on_start(key)
                    future = client.submit(
                        run_remote_task,
                        data,
                        token,
                        key,
                        self.timeout,
                        self.max_memory,
                        pure=False,
                        key=f"touchbench-{token}-{key}",
                    )
                    in_flight[future] = key
                    future.add_done_callback(finished.put)
                try:
                    future = finished.get(timeout=STOP_POLL)
                except Empty:
                    continue
                key = in_flight.pop(future)
                try:
                    result = future.result()
                except BenchmarkError:
                    raise
                except Exception as exc:
                    result = failed_result(key, "error", f"Dask: {exc}", None)
                deliver(result)
        finally:
            with contextlib.suppress(Exception):
                client.run(release_remote_workers, token)
            client.close()


def run_remote_task(
    context: bytes,
    token: str,
    key: TaskKey,
    timeout: float | None,
    max_memory: int | None = None,
) -> TaskResult:
    """Run one task on this Dask worker through the calling thread's worker process."""
    slot = (token, threading.get_ident())
    with _LOCAL_LOCK:
        worker = _LOCAL_WORKERS.get(slot)
        if worker is None or worker.process.poll() is not None:
            worker = Worker(context, max_memory=max_memory)
            _LOCAL_WORKERS[slot] = worker
    try:
        while not worker.ready:
            kind, payload = worker.receive()
            if kind == "broken":
                raise BenchmarkError(payload)
    except WorkerDiedError as died:
        _forget(slot)
        raise worker_could_not_start(died) from None
    worker.submit(key, timeout)
    if timeout is not None and not worker.connection.poll(timeout):
        worker.kill()
        _forget(slot)
        return timed_out(key, timeout)
    try:
        kind, payload = worker.receive()
    except WorkerDiedError as died:
        _forget(slot)
        return failed_result(key, "error", str(died), None)
    return payload


def release_remote_workers(token: str) -> int:
    """Stop this Dask worker's worker processes of run ``token``; returns how many."""
    with _LOCAL_LOCK:
        slots = [slot for slot in _LOCAL_WORKERS if slot[0] == token]
        workers = [_LOCAL_WORKERS.pop(slot) for slot in slots]
    for worker in workers:
        worker.close()
    return len(workers)


def _forget(slot: tuple[str, int]) -> None:
    with _LOCAL_LOCK:
        worker = _LOCAL_WORKERS.pop(slot, None)
    if worker is not None:
        worker.close()
