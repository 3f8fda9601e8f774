"""Running the engine's tasks on worker processes of this machine.

Why our own pool rather than joblib's: a task that overruns its time limit must be
stopped, native code included, without losing the other workers or their data, and a
worker that crashes (segfault, out-of-memory kill) must cost one task, not the run.
joblib can neither cancel one running task nor survive a killed worker without
restarting its whole pool; here the parent kills that one process group and starts a
replacement.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from multiprocessing.connection import wait

from touchbench.benchmark.errors import BenchmarkError
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

__all__ = ["LocalBackend"]


@dataclass(frozen=True)
class LocalBackend:
    """Up to ``workers`` local worker processes, one task each at a time.

    A worker that dies or overruns its task's time limit is replaced while tasks remain.

    Parameters
    ----------
    context : bytes
        The run's pickled :class:`~benchmark.run.task.TaskContext`, sent to each worker once.
    workers : int
        Worker processes at most (never more than there are tasks).
    timeout : float or None
        Seconds one task may take before its worker is killed; ``None`` for no limit.
    max_memory : int or None
        Bytes one task may allocate beyond its worker's copy of the data.
    """

    context: bytes
    workers: int
    timeout: float | None
    max_memory: int | None

    def run(
        self,
        tasks: TaskSource,
        on_start: StartCallback,
        deliver: ResultCallback,
        stop: StopCheck,
    ) -> None:
        """Run ``tasks`` (see :meth:`benchmark.run.backend.Backend.run`)."""
        timeout = self.timeout
        pool = [self._spawn() for _ in range(min(self.workers, tasks.remaining()))]
        try:
            while not tasks.exhausted or any(w.task is not None for w in pool):
                if stop():
                    raise RunStopped
                for worker in pool:
                    if worker.ready and worker.task is None and not tasks.exhausted:
                        key = tasks.next_task()
                        if key is None:
                            break  # the next tasks wait for a result
                        on_start(key)
                        worker.submit(key, timeout)
                arrived = wait([w.connection for w in pool], timeout=_wait_time(pool))
                survivors = []
                for worker in pool:
                    alive = worker.connection not in arrived or _take_message(worker, deliver)
                    task = worker.task
                    if (
                        alive
                        and task is not None
                        and timeout is not None
                        and _past_deadline(worker)
                    ):
                        worker.kill()
                        deliver(timed_out(task, timeout))
                        alive = False
                    if alive:
                        survivors.append(worker)
                        continue
                    worker.close()
                    if not tasks.exhausted:
                        survivors.append(self._spawn())
                pool = survivors
        finally:
            for worker in pool:
                worker.close()

    def _spawn(self) -> Worker:
        return Worker(self.context, max_memory=self.max_memory)


def _take_message(worker: Worker, deliver: ResultCallback) -> bool:
    """Handle one message of ``worker``; ``False`` if the worker has died."""
    try:
        kind, payload = worker.receive()
    except WorkerDiedError as died:
        if worker.task is None and not worker.ready:
            raise worker_could_not_start(died) from None
        if worker.task is not None:
            deliver(failed_result(worker.task, "error", str(died), None))
        return False
    if kind == "result":
        deliver(payload)
    elif kind == "broken":
        raise BenchmarkError(payload)
    return True


def _past_deadline(worker: Worker) -> bool:
    return worker.deadline is not None and time.monotonic() >= worker.deadline


def _wait_time(workers: Sequence[Worker]) -> float:
    """Seconds to wait for a message: until the next deadline, :data:`STOP_POLL` at most."""
    deadlines = [w.deadline for w in workers if w.task is not None and w.deadline is not None]
    if not deadlines:
        return STOP_POLL
    return max(0.0, min(STOP_POLL, min(deadlines) - time.monotonic()))
