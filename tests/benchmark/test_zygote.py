"""Workers forked from the zygote behave as the fresh interpreters they replace: same
results, the caller's environment, path and folder at the time, nothing inherited that a
fresh process would not have, their own random state, exit statuses, and a fresh
interpreter where no zygote answers.  Real processes throughout."""

from __future__ import annotations

import json
import os
import pickle
import resource
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin

from tests.benchmark.test_engine import scores_only, small_problem, stand_in
from touchbench.benchmark.catalogue import get_spec
from touchbench.benchmark.results import TaskKey, TaskResult
from touchbench.benchmark.run import zygote
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.run.task import TaskContext
from touchbench.benchmark.run.worker import Worker, WorkerDiedError
from touchbench.benchmark.run.zygote import ForkedProcess

#: What the reporting classifier's fit reads from the environment.
VARIABLE = "TOUCHBENCH_TEST_ZYGOTE_VARIABLE"
ROOT = Path(__file__).resolve().parents[2]


class ReportingClassifier(ClassifierMixin, BaseEstimator):
    """Majority class; its fit writes what its process sees into ``report_dir/PID.json``."""

    def __init__(self, report_dir: str = "") -> None:
        self.report_dir = report_dir

    def fit(self, X: np.ndarray, y: np.ndarray) -> ReportingClassifier:
        report = {
            "variable": os.environ.get(VARIABLE),
            "directory": os.getcwd(),
            "path": sys.path,
            "descriptors": sorted(int(fd) for fd in os.listdir("/proc/self/fd")),
            "random": float(np.random.random()),
            "parent": os.getppid(),
            "session": os.getsid(0),
        }
        (Path(self.report_dir) / f"{os.getpid()}.json").write_text(json.dumps(report))
        labels, counts = np.unique(y, return_counts=True)
        self.majority_ = labels[int(np.argmax(counts))]
        self.classes_ = labels
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        return np.full(len(X), self.majority_)


class ExitingClassifier(ClassifierMixin, BaseEstimator):
    """Says something on stderr, then ends its process with status 3."""

    def fit(self, X: np.ndarray, y: np.ndarray) -> ExitingClassifier:
        print("the exiting classifier leaves now", file=sys.stderr, flush=True)
        os._exit(3)


def _context(tmp_path: Path) -> bytes:
    problem = small_problem(30)
    folds = make_folds(problem.Y, n_folds=2)[0]
    specs = {
        "reporting": stand_in("reporting", ReportingClassifier, report_dir=str(tmp_path)),
        "exiting": stand_in("exiting", ExitingClassifier),
        "nb": get_spec("nb"),
    }
    return pickle.dumps(TaskContext(problem, specs, list(folds), 0))


def _run(worker: Worker, key: TaskKey) -> TaskResult:
    while not worker.ready:
        worker.receive()
    worker.submit(key, None)
    kind, result = worker.receive()
    assert kind == "result"
    return result


@pytest.fixture
def workers() -> Iterator[list[Worker]]:
    started: list[Worker] = []
    yield started
    for worker in started:
        worker.close()


def _reports(tmp_path: Path) -> dict[int, dict]:
    return {int(p.stem): json.loads(p.read_text()) for p in tmp_path.glob("*.json")}


def test_a_forked_worker_gives_what_a_fresh_interpreter_gives(
    tmp_path: Path, workers: list[Worker], monkeypatch: pytest.MonkeyPatch
) -> None:
    context = _context(tmp_path)
    forked = Worker(context)
    workers.append(forked)
    assert isinstance(forked.process, ForkedProcess)
    with monkeypatch.context() as patched:
        patched.setattr(zygote, "spawn", lambda *args, **kwargs: None)
        fresh = Worker(context)
    workers.append(fresh)
    assert isinstance(fresh.process, subprocess.Popen)
    keys = [TaskKey("nb", 0, 0), TaskKey("nb", 0, 1)]
    from_fork = [_run(forked, k) for k in keys]
    assert [r.status for r in from_fork] == ["ok", "ok"]
    assert scores_only(from_fork) == scores_only([_run(fresh, k) for k in keys])


def test_a_forked_worker_sees_the_callers_state_when_it_starts(
    tmp_path: Path, workers: list[Worker], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The zygote started long before: the environment, import path and working folder are
    the caller's at the worker's start, as a fresh interpreter would have them."""
    reports = tmp_path / "reports"
    reports.mkdir()
    context = _context(reports)
    workers.append(Worker(context))  # the zygote is running from here on
    _run(workers[0], TaskKey("reporting", 0, 0))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.setenv(VARIABLE, "set after the zygote started")
    monkeypatch.chdir(elsewhere)
    monkeypatch.syspath_prepend(str(elsewhere))
    later = Worker(context)
    workers.append(later)
    _run(later, TaskKey("reporting", 0, 1))
    report = _reports(reports)[later.pid]
    assert report["variable"] == "set after the zygote started"
    assert report["directory"] == str(elsewhere)
    assert str(elsewhere) in report["path"]
    assert report["session"] == later.pid  # its own process group, killed as one
    assert report["parent"] != os.getpid()  # forked by the zygote, not by this process


def test_a_forked_worker_holds_only_its_own_descriptors_and_its_own_random_state(
    tmp_path: Path, workers: list[Worker]
) -> None:
    context = _context(tmp_path)
    for fold in (0, 1):
        workers.append(Worker(context))
        _run(workers[-1], TaskKey("reporting", 0, fold))
    reports = _reports(tmp_path)
    assert set(reports) == {w.pid for w in workers}
    for pid, report in reports.items():
        # stdin, stdout, stderr, its two pipes, and the listing's own descriptor and the
        # report file while they are open: nothing of the zygote's or of other workers'
        assert len(report["descriptors"]) <= 7, (pid, report["descriptors"])
        assert all(isinstance(fd, int) for fd in report["descriptors"])
    first, second = reports.values()
    assert first["random"] != second["random"]


def test_a_forked_workers_exit_status_and_stderr_are_reported(
    tmp_path: Path, workers: list[Worker]
) -> None:
    context = _context(tmp_path)
    exiting = Worker(context)
    workers.append(exiting)
    while not exiting.ready:
        exiting.receive()
    exiting.submit(TaskKey("exiting", 0, 0), None)
    with pytest.raises(WorkerDiedError, match="status 3: the exiting classifier leaves now"):
        exiting.receive()
    killed = Worker(context)
    workers.append(killed)
    while not killed.ready:
        killed.receive()
    os.kill(killed.pid, signal.SIGSEGV)
    with pytest.raises(WorkerDiedError, match="killed by signal SIGSEGV"):
        killed.receive()
    assert killed.process.poll() == -signal.SIGSEGV


def test_a_worker_starts_from_a_fresh_interpreter_where_no_zygote_answers(
    tmp_path: Path, workers: list[Worker], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(zygote, "_ZYGOTE", None)
    monkeypatch.setattr(zygote, "_ZYGOTE_MAIN", "import sys; sys.exit(3)")
    worker = Worker(_context(tmp_path))
    workers.append(worker)
    assert isinstance(worker.process, subprocess.Popen)
    assert _run(worker, TaskKey("nb", 0, 0)).status == "ok"
    assert zygote._ZYGOTE is None


def test_the_zygote_and_its_workers_end_with_a_killed_caller(tmp_path: Path) -> None:
    """kill -9 of the process that asked: its zygote, and a worker that is idle (not in a
    fit, the engine's own test covers that), are gone within seconds."""
    script = (
        "import os, pickle, sys, time\n"
        "from pathlib import Path\n"
        "from tests.benchmark.test_zygote import _context\n"
        "from touchbench.benchmark.run import zygote\n"
        "from touchbench.benchmark.run.worker import Worker\n"
        f"worker = Worker(_context(Path({str(tmp_path)!r})))\n"
        "while not worker.ready:\n"
        "    worker.receive()\n"
        "print(worker.pid, zygote._ZYGOTE.process.pid, flush=True)\n"
        "time.sleep(3600)\n"
    )
    caller = subprocess.Popen(
        [sys.executable, "-c", script], cwd=ROOT, stdout=subprocess.PIPE, text=True
    )
    try:
        assert caller.stdout is not None
        pids = [int(pid) for pid in caller.stdout.readline().split()]
    finally:
        caller.kill()
        caller.wait()
    assert len(pids) == 2
    deadline = time.monotonic() + 15
    alive = pids
    while alive and time.monotonic() < deadline:
        alive = [pid for pid in alive if _running(pid)]
        time.sleep(0.2)
    for pid in alive:
        os.kill(pid, signal.SIGKILL)
    assert alive == [], "still running 15 s after their caller was killed"


def _running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return False
    return state != "Z"


def test_an_idle_zygote_ends_and_the_next_worker_starts_another(
    tmp_path: Path, workers: list[Worker], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A zygote with no child left and no request for its idle time ends (a notebook's
    kernel lives long; the zygote's memory need not); it waits while a child lives."""
    monkeypatch.setattr(zygote, "_ZYGOTE", None)
    monkeypatch.setattr(zygote, "IDLE_SECONDS", 1.0)
    context = _context(tmp_path)
    first = Worker(context)
    _run(first, TaskKey("nb", 0, 0))
    started = zygote._ZYGOTE
    assert started is not None
    time.sleep(3.0)  # idle time thrice over, but its child lives
    assert not started.ended()
    first.close()
    deadline = time.monotonic() + 15
    while not started.ended() and time.monotonic() < deadline:
        time.sleep(0.2)
    assert started.ended(), "the zygote outlived its idle time"
    second = Worker(context)
    workers.append(second)
    assert isinstance(second.process, ForkedProcess)
    assert zygote._ZYGOTE is not started
    assert _run(second, TaskKey("nb", 0, 1)).status == "ok"
    zygote._close_zygote()


def test_a_caller_with_many_descriptors_reads_its_workers_statuses(
    tmp_path: Path, workers: list[Worker], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A long-lived service holds more than select's 1,024 descriptors: its zygote's socket
    and a worker's status pipe then get numbers past it, and still work."""
    monkeypatch.setattr(zygote, "_ZYGOTE", None)
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard != resource.RLIM_INFINITY and hard < 1200:
        pytest.skip(f"this machine allows {hard} open files, fewer than the test needs")
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(soft, 1200), hard))
    held: list[int] = []
    try:
        with open(os.devnull) as null:
            while not held or held[-1] < 1100:
                held.append(os.dup(null.fileno()))
        worker = Worker(_context(tmp_path))
        workers.append(worker)
        assert isinstance(worker.process, ForkedProcess)
        assert worker.process._status > 1024
        _run(worker, TaskKey("nb", 0, 0))
        worker.close()
        assert worker.process.poll() == 0
        zygote._close_zygote()
    finally:
        for fd in held:
            os.close(fd)
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))


def test_a_request_interrupted_before_its_answer_retires_the_zygote(
    tmp_path: Path, workers: list[Worker], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C after a request was sent and before its answer was read (a notebook goes on
    afterwards): the answer left in the socket must not be taken as the next request's,
    so the next worker has its own pid, the one that reports from the fit."""
    monkeypatch.setattr(zygote, "_ZYGOTE", None)
    reports = tmp_path / "reports"
    reports.mkdir()
    context = _context(reports)
    workers.append(Worker(context))  # a zygote, running
    first = zygote._ZYGOTE
    assert first is not None
    send = socket.send_fds

    def interrupted(*args: object, **kwargs: object) -> int:
        send(*args, **kwargs)  # type: ignore[arg-type]
        raise KeyboardInterrupt

    with monkeypatch.context() as patched:
        patched.setattr(socket, "send_fds", interrupted)
        with pytest.raises(KeyboardInterrupt):
            Worker(context)
    assert zygote._ZYGOTE is None and first.ended()
    later = Worker(context)
    workers.append(later)
    assert isinstance(later.process, ForkedProcess)
    _run(later, TaskKey("reporting", 0, 0))
    assert later.pid in _reports(reports)
    zygote._close_zygote()


def test_a_caller_in_a_deleted_folder_still_gets_a_forked_worker(
    tmp_path: Path, workers: list[Worker], monkeypatch: pytest.MonkeyPatch
) -> None:
    context = _context(tmp_path)
    gone = tmp_path / "gone"
    gone.mkdir()
    monkeypatch.chdir(gone)
    gone.rmdir()
    worker = Worker(context)
    workers.append(worker)
    assert isinstance(worker.process, ForkedProcess)
    assert _run(worker, TaskKey("nb", 0, 0)).status == "ok"
