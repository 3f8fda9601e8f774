"""The cross-validation engine: every classifier on every fold, in parallel, with time limits.

Tasks (one classifier on one fold) run in worker processes (:mod:`benchmark.run.worker`) that
each receive the run's data once.  Locally, ``jobs`` workers take tasks from one queue;
with ``scheduler="tcp://host:port"`` the tasks go to a Dask distributed cluster, where each
Dask worker thread keeps such a worker process (:mod:`benchmark.run.dask_backend`).

Why our own pool rather than joblib's: a task that overruns its time limit must be
stopped, native code included, without losing the other workers or their data, and a
worker that crashes (segfault, out-of-memory kill) must cost one task, not the run.
joblib can neither cancel one running task nor survive a killed worker without
restarting its whole pool; here the parent kills that one process group and starts a
replacement.

Every finished task is reported at once through ``on_result`` (in the calling process),
so that the caller can store it; ``skip`` resumes a run without repeating what is done.
"""

from __future__ import annotations

import os
import pickle
import time
from collections import deque
from collections.abc import Callable, Collection, Mapping, Sequence
from multiprocessing.connection import wait

from benchmark.catalogue import ClassifierSpec
from benchmark.errors import BenchmarkError, ConfigurationError
from benchmark.estimators import check_classifier
from benchmark.problem import Problem
from benchmark.results import TaskKey, TaskResult
from benchmark.run.folds import Fold
from benchmark.run.task import TaskContext, failed_result
from benchmark.run.worker import Worker, WorkerDiedError

__all__ = [
    "Problem",
    "RunStopped",
    "TaskKey",
    "TaskResult",
    "available_cores",
    "plan_tasks",
    "run_tasks",
]

ResultCallback = Callable[[TaskResult], None]
StartCallback = Callable[[TaskKey], None]
StopCheck = Callable[[], bool]

#: Seconds between checks of ``stop`` while tasks run.
STOP_POLL = 0.5


class RunStopped(Exception):  # noqa: N818 (a signal, not an error)
    """``stop`` asked the engine to end the run early; finished tasks were reported."""


def run_tasks(
    problem: Problem,
    classifiers: Sequence[str],
    folds: Sequence[Fold],
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    timeout: float | None = 600.0,
    random_state: int = 0,
    skip: Collection[TaskKey] = (),
    on_start: StartCallback | None = None,
    on_result: ResultCallback | None = None,
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
    max_memory: int | None = None,
    stop: StopCheck | None = None,
) -> list[TaskResult]:
    """Cross-validate classifiers on a problem.

    Parameters
    ----------
    problem : Problem
        Features and targets.  One target: catalogue classifiers; several targets:
        multi-target configurations (``META:BASE``) of :mod:`benchmark.multitarget`;
        numeric targets: regressors (:mod:`benchmark.catalogue.regressors`).
    classifiers : sequence of str
        Classifier ids, run in this order (duplicates ignored).
    folds : sequence of Fold
        The folds, shared by every classifier (:func:`benchmark.run.folds.make_folds`).
    jobs : int
        Local worker processes; -1 for one per core.  Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a Dask distributed scheduler (``tcp://host:port``) to run on instead.
    timeout : float or None
        Seconds one task may take before its worker is killed; ``None`` for no limit.
    random_state : int
        Seed of every classifier.
    skip : collection of TaskKey
        Tasks already done (a resumed run); they are neither run nor returned.
    on_start : callable, optional
        Called with each task's key when it starts.
    on_result : callable, optional
        Called in the calling process with each result as soon as it arrives.
    extra_specs : mapping of str to ClassifierSpec, optional
        Multi-class classifiers that are not in the catalogue (they win over catalogue
        entries of the same id).  Their factories must be importable by the workers.
    max_memory : int, optional
        Bytes of memory one task may allocate beyond its worker's copy of the data; a task
        that needs more fails with an ``error`` result saying so.
    stop : callable, optional
        Checked about twice a second; when it returns true, running tasks are killed and
        :class:`RunStopped` is raised (the results reported so far stand).

    Returns
    -------
    list of TaskResult
        One per task run, classifier-major in the order of ``classifiers`` and ``folds``.
        Classifiers that raise, run out of memory, crash or time out give results with
        status ``error`` or ``timeout``; the run goes on.

    Raises
    ------
    ConfigurationError
        Unknown classifier ids, no folds, impossible ``jobs``, ``timeout`` or
        ``max_memory``, an unreachable scheduler.
    RunStopped
        ``stop`` returned true.
    """
    specs, tasks = plan_tasks(problem, classifiers, folds, skip=skip, extra_specs=extra_specs)
    if timeout is not None and not timeout > 0:
        raise ConfigurationError(f"timeout must be a positive number of seconds, got {timeout}")
    if max_memory is not None and max_memory <= 0:
        raise ConfigurationError(f"max_memory must be a positive number of bytes, got {max_memory}")
    if not tasks:
        return []
    context = pickle.dumps(
        TaskContext(problem, specs, list(folds), random_state), protocol=pickle.HIGHEST_PROTOCOL
    )
    sizes = {(f.repeat, f.fold): (int(f.train.size), int(f.test.size)) for f in folds}
    results: dict[TaskKey, TaskResult] = {}

    def deliver(result: TaskResult) -> None:
        if result.status != "ok":
            result.n_train, result.n_test = sizes[(result.key.repeat, result.key.fold)]
            if max_memory is not None and _looks_out_of_memory(result.error):
                result.error = (
                    f"exceeded the memory limit of {max_memory / 2**20:g} MB per task "
                    f"({result.error})"
                )
        results[result.key] = result
        if on_result is not None:
            on_result(result)

    started = on_start or _ignore
    if scheduler:
        from benchmark.run.dask_backend import run_on_dask

        run_on_dask(
            scheduler,
            context,
            tasks,
            timeout=timeout,
            on_start=started,
            on_result=deliver,
            max_memory=max_memory,
            stop=stop,
        )
    else:
        pool = _LocalPool(context, _worker_count(jobs, len(tasks)), max_memory)
        pool.run(tasks, timeout, started, deliver, stop)
    return [results[key] for key in tasks if key in results]


def plan_tasks(
    problem: Problem,
    classifiers: Sequence[str],
    folds: Sequence[Fold],
    *,
    skip: Collection[TaskKey] = (),
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
) -> tuple[dict[str, ClassifierSpec], list[TaskKey]]:
    """Check the classifier ids and list the tasks still to run.

    Returns
    -------
    specs : dict of str to ClassifierSpec
        The multi-class specs the workers need: the run's multi-class classifiers and
        every extra spec.
    tasks : list of TaskKey
        Classifier-major, without the keys in ``skip``.
    """
    ids = list(dict.fromkeys(classifiers))
    if not ids:
        raise ConfigurationError("no classifiers to run")
    if not folds:
        raise ConfigurationError("no folds to run the classifiers on")
    # extra specs travel too: a multi-target configuration may take one as its base
    specs: dict[str, ClassifierSpec] = dict(extra_specs or {})
    for classifier in ids:
        spec = check_classifier(classifier, problem, extra_specs)
        if spec is not None:
            specs[classifier] = spec
    done = set(skip)
    tasks = [
        key
        for classifier in ids
        for fold in folds
        if (key := TaskKey(classifier, fold.repeat, fold.fold)) not in done
    ]
    return specs, tasks


def available_cores() -> int:
    """CPU cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _worker_count(jobs: int, n_tasks: int) -> int:
    if jobs == -1:
        jobs = available_cores()
    if jobs < 1:
        raise ConfigurationError(f"jobs must be a positive number of processes or -1, got {jobs}")
    return min(jobs, n_tasks)


class _LocalPool:
    """``n_workers`` local worker processes, one task each at a time.

    A worker that dies or overruns its task's time limit is replaced while tasks remain.
    """

    def __init__(self, context: bytes, n_workers: int, max_memory: int | None) -> None:
        self.context = context
        self.n_workers = n_workers
        self.max_memory = max_memory

    def _spawn(self) -> Worker:
        return Worker(self.context, max_memory=self.max_memory)

    def run(
        self,
        tasks: Sequence[TaskKey],
        timeout: float | None,
        on_start: StartCallback,
        deliver: ResultCallback,
        stop: StopCheck | None,
    ) -> None:
        queue = deque(tasks)
        pool = [self._spawn() for _ in range(self.n_workers)]
        try:
            while queue or any(w.task is not None for w in pool):
                if stop is not None and stop():
                    raise RunStopped
                for worker in pool:
                    if worker.ready and worker.task is None and queue:
                        key = queue.popleft()
                        on_start(key)
                        worker.submit(key, timeout)
                wait_for = _time_left(pool)
                if stop is not None:
                    wait_for = STOP_POLL if wait_for is None else min(wait_for, STOP_POLL)
                arrived = wait([w.connection for w in pool], timeout=wait_for)
                survivors = []
                for worker in pool:
                    alive = worker.connection not in arrived or _take_message(worker, deliver)
                    task = worker.task
                    if alive and task is not None and _past_deadline(worker):
                        worker.kill()
                        deliver(failed_result(task, "timeout", _timeout_message(timeout), None))
                        alive = False
                    if alive:
                        survivors.append(worker)
                        continue
                    worker.close()
                    if queue:
                        survivors.append(self._spawn())
                pool = survivors
        finally:
            for worker in pool:
                worker.close()


def _take_message(worker: Worker, deliver: ResultCallback) -> bool:
    """Handle one message of ``worker``; ``False`` if the worker has died."""
    try:
        kind, payload = worker.receive()
    except WorkerDiedError as died:
        if worker.task is None and not worker.ready:
            raise RuntimeError(f"a worker process could not start: {died}") from None
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


def _time_left(workers: Sequence[Worker]) -> float | None:
    deadlines = [w.deadline for w in workers if w.task is not None and w.deadline is not None]
    if not deadlines:
        return None
    return max(0.0, min(deadlines) - time.monotonic())


def _timeout_message(timeout: float | None) -> str:
    return f"timed out after {timeout:g} s (worker process killed)"


def _ignore(key: TaskKey) -> None:
    return None


def _looks_out_of_memory(error: str | None) -> bool:
    text = error or ""
    return "MemoryError" in text or "SIGSEGV" in text or "SIGABRT" in text or "bad_alloc" in text
