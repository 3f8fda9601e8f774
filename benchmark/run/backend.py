"""What a backend of the engine is, and what every backend reports the same way.

A backend runs tasks (one classifier on one fold) somewhere: local worker processes
(:mod:`benchmark.run.local_backend`) or a Dask cluster (:mod:`benchmark.run.dask_backend`).
The engine (:mod:`benchmark.run.engine`) plans the tasks, builds the run's context, picks a
backend and calls :meth:`Backend.run`.  Backends import this module and never the engine,
so that each outcome a user reads (a timeout, a worker that could not start) is worded here,
once.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, runtime_checkable

from touchbench.benchmark.results import TaskKey, TaskResult
from touchbench.benchmark.run.schedule import TaskSource
from touchbench.benchmark.run.task import failed_result

__all__ = [
    "STOP_POLL",
    "Backend",
    "ResultCallback",
    "RunStopped",
    "StartCallback",
    "StopCheck",
    "timed_out",
    "worker_could_not_start",
]

StartCallback = Callable[[TaskKey], None]
ResultCallback = Callable[[TaskResult], None]
StopCheck = Callable[[], bool]

#: Seconds at most between two checks of ``stop`` while tasks run.
STOP_POLL = 0.1


class RunStopped(Exception):  # noqa: N818 (a signal, not an error)
    """``stop`` asked the engine to end the run early; finished tasks were reported."""


@runtime_checkable
class Backend(Protocol):
    """Runs a plan's tasks and reports each one as it starts and as it ends.

    A backend is built with what its tasks share (the run's pickled context, the time and
    memory limits of a task); running it holds no state between runs.
    """

    def run(
        self,
        tasks: TaskSource,
        on_start: StartCallback,
        deliver: ResultCallback,
        stop: StopCheck,
    ) -> None:
        """Run every task of ``tasks``; the callbacks are called in the calling thread.

        Parameters
        ----------
        tasks : TaskSource
            The tasks: asked for the next one whenever a worker is free; a result is
            delivered before the source is asked again, so what starts may depend on it.
        on_start : callable
            Called in the calling thread with a task's key when it is handed to a worker.
        deliver : callable
            Called in the calling thread with each task's result as soon as it arrives;
            a task that times out or whose worker dies gets a result too.
        stop : callable
            Cheap; checked at least every :data:`STOP_POLL` seconds while tasks run.

        Raises
        ------
        RunStopped
            ``stop`` returned true; running tasks were ended and nothing more is reported.
        BenchmarkError
            A worker could not load the run's data.
        """
        ...


def timed_out(key: TaskKey, timeout: float) -> TaskResult:
    """The result of a task whose worker was killed at its time limit of ``timeout`` s."""
    message = f"timed out after {timeout:g} s (worker process killed)"
    return failed_result(key, "timeout", message, None)


def worker_could_not_start(reason: object) -> RuntimeError:
    """The error for a worker process that died before it was ready (``reason``: why)."""
    return RuntimeError(f"a worker process could not start: {reason}")
