"""Worker processes that hold one run's data and execute its tasks on request.

A worker is forked from this process's zygote (:mod:`benchmark.run.zygote`), a fresh
interpreter that has imported what every worker needs, or, where no zygote answers, is a
fresh interpreter itself (``subprocess``, not ``multiprocessing``).  Either way it can be
started from anywhere (a multi-threaded service, a daemonic Dask worker), its BLAS and
OpenMP thread counts are set through the environment before those libraries load, and it
can be killed outright (its whole process group) when a task overruns its time limit,
native code included.  BLAS and OpenMP get one thread each: parallelism comes from running
several workers, the matrices of a fold are small, and threads that spin-wait for cores
other processes hold slow fits down many times.

The run's :class:`~benchmark.run.task.TaskContext` is pickled once by the parent and sent
to each worker once; afterwards each task costs one small message each way.

Messages from a worker: ``("ready", pid)`` once the context is loaded, ``("result",
TaskResult)`` per task, ``("broken", text)`` if the context cannot be loaded.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from multiprocessing.connection import Connection
from typing import Any, TypeAlias

from touchbench.benchmark.results import TaskKey, TaskResult
from touchbench.benchmark.run import zygote
from touchbench.benchmark.run.task import describe_exception, execute_task
from touchbench.benchmark.run.zygote import ForkedProcess

#: Characters of a dead worker's stderr quoted in the error.
STDERR_TAIL = 300
#: Seconds between a worker's checks that its parent is still alive.
PARENT_CHECK_INTERVAL = 1.0
#: How a fresh interpreter becomes a worker (its arguments: the pipes and the memory limit).
FRESH_WORKER = "from touchbench.benchmark.run.worker import serve; serve()"
#: What a worker imports, once for all a process's workers (by the zygote).
PRELOAD = (
    __name__,
    "sklearn.calibration",
    "sklearn.discriminant_analysis",
    "sklearn.ensemble",
    "sklearn.linear_model",
    "sklearn.metrics",
    "sklearn.model_selection",
    "sklearn.naive_bayes",
    "sklearn.neighbors",
    "sklearn.neural_network",
    "sklearn.preprocessing",
    "sklearn.svm",
    "sklearn.tree",
    "xgboost",
)


Process: TypeAlias = "ForkedProcess | subprocess.Popen[bytes]"


class WorkerDiedError(Exception):
    """The worker process ended while the parent waited for it."""


class Worker:
    """The parent's handle on one worker process.

    Parameters
    ----------
    context : bytes
        The pickled :class:`~benchmark.run.task.TaskContext`.
    max_memory : int, optional
        Bytes of data memory each task may allocate on top of what the worker holds once
        the run's data is loaded (``RLIMIT_DATA``); a task that needs more fails with an
        out-of-memory error instead of taking the machine down.
    """

    def __init__(self, context: bytes, *, max_memory: int | None = None) -> None:
        self._stderr = tempfile.TemporaryFile()  # noqa: SIM115 (open for the worker's life)
        environment = _worker_environment()
        limit = max_memory or 0

        def fork(child_in: int, child_out: int) -> ForkedProcess | None:
            return zygote.spawn(
                f"{__name__}:serve_pipes",
                (child_in, child_out),
                (limit,),
                stderr=self._stderr,
                environment=environment,
                preload=PRELOAD,
            )

        def interpret(child_in: int, child_out: int) -> subprocess.Popen[bytes]:
            command = [sys.executable, "-c", FRESH_WORKER, str(child_in), str(child_out)]
            return subprocess.Popen(
                [*command, str(limit)],
                pass_fds=(child_in, child_out),
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=self._stderr,
                env=environment,
                start_new_session=True,
            )

        # a fresh interpreter where no zygote answers, with pipes of its own
        started = _with_pipes(fork) or _with_pipes(interpret)
        assert started is not None  # Popen answers or raises
        parent_in, parent_out, self.process = started
        self.connection = Connection(parent_in, writable=False)
        self._outbox = Connection(parent_out, readable=False)
        self.ready = False
        self.task: TaskKey | None = None
        self.deadline: float | None = None
        self._killed = False
        # The worker reads its data only after its imports: send it without blocking.
        self._sender = threading.Thread(target=self._send_context, args=(context,), daemon=True)
        self._sender.start()

    @property
    def pid(self) -> int:
        return self.process.pid

    def submit(self, key: TaskKey, timeout: float | None) -> None:
        """Start ``key`` on the worker; it must be ready and idle."""
        self.task = key
        self.deadline = None if timeout is None else time.monotonic() + timeout
        self._outbox.send(key)

    def receive(self) -> tuple[str, Any]:
        """The next message; raises :class:`WorkerDiedError` if the process ended instead."""
        try:
            message = self.connection.recv()
        except (EOFError, OSError) as exc:
            raise WorkerDiedError(self.death_reason()) from exc
        if message[0] == "ready":
            self.ready = True
        elif message[0] == "result":
            self.task, self.deadline = None, None
        return message

    def _send_context(self, context: bytes) -> None:
        with contextlib.suppress(OSError):
            self._outbox.send_bytes(context)

    def kill(self) -> None:
        """Kill the worker and anything it started, at once."""
        self._killed = True
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.process.pid, signal.SIGKILL)
        with contextlib.suppress(ProcessLookupError):
            self.process.kill()

    def close(self) -> None:
        """Stop the worker (killing it if it does not exit promptly) and free its pipes."""
        if self.process.poll() is None:
            if self.ready and self.task is None:
                with contextlib.suppress(OSError):
                    self._outbox.send(None)
                try:
                    self.process.wait(timeout=0.5)
                except subprocess.TimeoutExpired:
                    self.kill()
            else:
                self.kill()
        self.process.wait()
        self._sender.join(timeout=5.0)
        for end in (self.connection, self._outbox):
            with contextlib.suppress(OSError):
                end.close()
        self._stderr.close()

    def death_reason(self) -> str:
        """Why the process ended: exit status or signal, and the tail of its stderr."""
        try:
            code = self.process.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            return "the worker stopped answering"
        if code < 0:
            name = signal.Signals(-code).name
            reason = f"worker process killed by signal {name}"
            if -code == signal.SIGKILL and not self._killed:
                reason += " (out of memory?)"
        else:
            reason = f"worker process exited with status {code}"
        tail = self._stderr_tail()
        return f"{reason}: {tail}" if tail else reason

    def _stderr_tail(self) -> str:
        self._stderr.seek(0, os.SEEK_END)
        size = self._stderr.tell()
        self._stderr.seek(max(0, size - 4 * STDERR_TAIL))
        lines = [
            line.strip()
            for line in self._stderr.read().decode("utf-8", "replace").splitlines()
            if line.strip()
        ]
        return lines[-1][-STDERR_TAIL:] if lines else ""


def _with_pipes(
    start: Callable[[int, int], Process | None],
) -> tuple[int, int, Process] | None:
    """Start a worker on two new pipes: the parent's ends and the process, or ``None``.

    ``start`` is given the worker's ends (read, write), which are closed here afterwards.
    """
    parent_in, child_out = os.pipe()
    child_in, parent_out = os.pipe()
    try:
        process = start(child_in, child_out)
    except BaseException:
        process = None
        raise
    finally:
        os.close(child_in)
        os.close(child_out)
        if process is None:
            os.close(parent_in)
            os.close(parent_out)
    return None if process is None else (parent_in, parent_out, process)


def _exit_with_parent(parent: int) -> None:
    """End this worker, even in the middle of a fit, once its parent has died (kill -9)."""
    while os.getppid() == parent:
        time.sleep(PARENT_CHECK_INTERVAL)
    os._exit(1)


def _worker_environment() -> dict[str, str]:
    environment = dict(os.environ)
    paths = [p for p in sys.path if p]
    if environment.get("PYTHONPATH"):
        paths.append(environment["PYTHONPATH"])
    environment["PYTHONPATH"] = os.pathsep.join(dict.fromkeys(paths))
    for name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS"):
        environment[name] = "1"
    environment["OMP_NUM_THREADS"] = "1"
    return environment


def _limit_data_memory(extra: int) -> None:
    """Allow this process ``extra`` bytes of data memory beyond what it uses now."""
    import resource

    in_use = 0
    with contextlib.suppress(OSError, ValueError), open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmData:"):
                in_use = int(line.split()[1]) * 1024
    resource.setrlimit(resource.RLIMIT_DATA, (in_use + extra, in_use + extra))


def serve() -> None:
    """A fresh interpreter's worker: its pipes and memory limit are its arguments."""
    serve_pipes(int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]) if len(sys.argv) > 3 else 0)


def serve_pipes(inbox_fd: int, outbox_fd: int, limit: int) -> None:
    """The worker's main loop: load the context, then run tasks until told to stop.

    Parameters
    ----------
    inbox_fd, outbox_fd : int
        The read end of the pipe from the parent and the write end of the pipe to it.
    limit : int
        Bytes of data memory a task may allocate beyond the loaded context; 0 for no limit.
    """
    threading.Thread(target=_exit_with_parent, args=(os.getppid(),), daemon=True).start()
    inbox = Connection(inbox_fd, writable=False)
    outbox = Connection(outbox_fd, readable=False)
    try:
        context = pickle.loads(inbox.recv_bytes())
    except EOFError:
        return
    except Exception as exc:
        outbox.send(("broken", f"cannot load the run's data: {describe_exception(exc)}"))
        return
    if limit > 0:
        _limit_data_memory(limit)
    outbox.send(("ready", os.getpid()))
    while True:
        try:
            key = inbox.recv()
        except EOFError:
            return
        if key is None:
            return
        result: TaskResult = execute_task(context, key)
        try:
            outbox.send(("result", result))
        except (BrokenPipeError, OSError):
            return
