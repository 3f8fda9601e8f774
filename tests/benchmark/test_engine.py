"""The engine end to end: worker processes, callbacks, resume, failures, jobs, Dask."""

from __future__ import annotations

import os
import pickle
import resource
import signal
import threading
import time
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin

from touchbench.benchmark.catalogue import ClassifierSpec, get_spec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.run.backend import Backend, RunStopped
from touchbench.benchmark.run.dask_backend import DaskBackend
from touchbench.benchmark.run.engine import Problem, TaskKey, TaskResult, plan_tasks, run_tasks
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.run.local_backend import LocalBackend
from touchbench.benchmark.run.schedule import TaskList
from touchbench.benchmark.run.task import TaskContext

# Deliberately misbehaving classifiers.  The engine's workers import them from this module.


class SleepingClassifier(ClassifierMixin, BaseEstimator):
    """A runaway fit: writes its process id to ``pid_file``, then sleeps in C for an hour."""

    def __init__(self, pid_file: str = "") -> None:
        self.pid_file = pid_file

    def fit(self, X: np.ndarray, y: np.ndarray) -> SleepingClassifier:
        if self.pid_file:
            Path(self.pid_file).write_text(str(os.getpid()))
        time.sleep(3600)
        return self


class FailingClassifier(ClassifierMixin, BaseEstimator):
    def fit(self, X: np.ndarray, y: np.ndarray) -> FailingClassifier:
        raise ValueError("deliberate failure")


class MemoryHogClassifier(ClassifierMixin, BaseEstimator):
    """Asks for 16 GB under an address-space limit of 512 MB more than it uses."""

    def fit(self, X: np.ndarray, y: np.ndarray) -> MemoryHogClassifier:
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        in_use = int(Path("/proc/self/statm").read_text().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        resource.setrlimit(resource.RLIMIT_AS, (in_use + 512 * 2**20, hard))
        try:
            np.ones(2 * 2**30, dtype=np.float64)
        finally:
            resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
        return self


class GreedyClassifier(ClassifierMixin, BaseEstimator):
    """Allocates and touches 300 MB in its fit (no limit of its own)."""

    def fit(self, X: np.ndarray, y: np.ndarray) -> GreedyClassifier:
        block = np.ones(300 * 2**20 // 8)
        self.total_ = float(block.sum())
        self.classes_ = np.unique(y)
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        return np.full(len(X), self.classes_[0])


class SelfKillingClassifier(ClassifierMixin, BaseEstimator):
    """Dies as the kernel's out-of-memory killer would kill it."""

    def fit(self, X: np.ndarray, y: np.ndarray) -> SelfKillingClassifier:
        os.kill(os.getpid(), signal.SIGKILL)
        return self


#: A time limit no task of these tests should reach, so that none can hang the suite.
TIMEOUT = 600.0


class ParkedClassifier(ClassifierMixin, BaseEstimator):
    """A fit that never ends: announces its process id as a file in ``pid_dir``, then sleeps."""

    def __init__(self, pid_dir: str = "") -> None:
        self.pid_dir = pid_dir

    def fit(self, X: np.ndarray, y: np.ndarray) -> ParkedClassifier:
        (Path(self.pid_dir) / str(os.getpid())).touch()
        time.sleep(3600)
        return self


def stand_in(classifier_id: str, factory: type, **params: object) -> ClassifierSpec:
    return replace(
        get_spec("zeror"), id=classifier_id, factory=factory, params=params, probabilities=False
    )


def small_problem(n: int = 90) -> Problem:
    rng = np.random.default_rng(0)
    y = np.arange(n) % 3
    X = rng.normal(size=(n, 4)) + 2.0 * y[:, None]
    X[::11, 2] = np.nan
    return Problem(X=X, Y=y[:, None], n_classes=(3,), target_names=("gesture",))


@pytest.fixture(scope="module")
def problem() -> Problem:
    return small_problem()


@pytest.fixture(scope="module")
def folds(problem: Problem) -> list:
    return make_folds(problem.Y, n_folds=3)[0]


def scores_only(results: list[TaskResult]) -> list[tuple[TaskKey, str, dict[str, float]]]:
    costs = {"fit_time", "predict_time", "fit_cpu_time", "predict_cpu_time"}
    return [
        (r.key, r.status, {k: v for k, v in r.metrics.items() if k not in costs}) for r in results
    ]


def test_every_task_runs_once_and_is_reported_in_the_calling_process(problem, folds) -> None:
    started: list[TaskKey] = []
    reported: list[tuple[TaskKey, int]] = []
    results = run_tasks(
        problem,
        ["zeror", "nb", "zeror"],
        folds,
        timeout=TIMEOUT,
        on_start=started.append,
        on_result=lambda r: reported.append((r.key, os.getpid())),
    )
    expected = [TaskKey(c, 0, k) for c in ("zeror", "nb") for k in range(3)]
    assert [r.key for r in results] == expected
    assert started == expected
    assert [key for key, _ in reported] == expected
    assert {pid for _, pid in reported} == {os.getpid()}
    assert all(r.status == "ok" for r in results)
    assert results[3].metrics["accuracy"] > 0.8
    assert results[0].metrics["accuracy"] == pytest.approx(1 / 3)
    assert (results[0].n_train, results[0].n_test) == (60, 30)


def test_an_interrupted_run_resumes_without_repeating_tasks(problem, folds) -> None:
    stored: list[TaskResult] = []

    def store_then_interrupt(result: TaskResult) -> None:
        stored.append(result)
        if len(stored) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_tasks(
            problem, ["nb", "j48"], folds, jobs=2, timeout=TIMEOUT, on_result=store_then_interrupt
        )
    assert len(stored) == 2
    done = {r.key for r in stored}
    # the interrupted run had a task in flight in its second worker; the rest needs only one
    rest = run_tasks(
        problem, ["nb", "j48"], folds, jobs=1, timeout=TIMEOUT, skip=done, on_result=stored.append
    )
    assert {r.key for r in rest}.isdisjoint(done)
    assert sorted(r.key for r in stored) == sorted(
        TaskKey(c, 0, k) for c in ("nb", "j48") for k in range(3)
    )
    skip = {r.key for r in stored}
    assert run_tasks(problem, ["nb", "j48"], folds, timeout=TIMEOUT, skip=skip) == []


def test_errors_crashes_memory_and_timeouts_are_recorded_and_the_run_goes_on(
    problem, folds, tmp_path: Path
) -> None:
    pid_file = tmp_path / "sleeper.pid"
    specs = {
        "failing": stand_in("failing", FailingClassifier),
        "sleeper": stand_in("sleeper", SleepingClassifier, pid_file=str(pid_file)),
        "hog": stand_in("hog", MemoryHogClassifier),
        "killer": stand_in("killer", SelfKillingClassifier),
    }
    two_folds = folds[:2]
    results = run_tasks(
        problem,
        ["failing", "sleeper", "hog", "killer", "nb"],
        two_folds,
        jobs=2,
        timeout=2.0,
        extra_specs=specs,
    )
    by_classifier: dict[str, list[TaskResult]] = {}
    for result in results:
        by_classifier.setdefault(result.key.classifier, []).append(result)
    assert len(results) == 10
    for result in by_classifier["failing"]:
        assert result.status == "error"
        assert str(result.error).startswith("ValueError: deliberate failure")
    for result in by_classifier["sleeper"]:
        assert result.status == "timeout"
        assert result.error == "timed out after 2 s (worker process killed)"
        assert (result.n_train, result.n_test) == (60, 30)
    for result in by_classifier["hog"]:
        assert result.status == "error"
        assert str(result.error).startswith("MemoryError")
    for result in by_classifier["killer"]:
        assert result.status == "error"
        assert str(result.error).startswith(
            "worker process killed by signal SIGKILL (out of memory?)"
        )
    assert [r.status for r in by_classifier["nb"]] == ["ok", "ok"]
    sleeper_pid = int(pid_file.read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(sleeper_pid, 0)


def test_two_jobs_give_the_same_scores_as_one(problem, folds) -> None:
    classifiers = ["rf", "logistic", "ibk"]
    one = run_tasks(problem, classifiers, folds, jobs=1, timeout=TIMEOUT, random_state=3)
    two = run_tasks(problem, classifiers, folds, jobs=2, timeout=TIMEOUT, random_state=3)
    assert scores_only(one) == scores_only(two)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"classifiers": ["rff"]}, "unknown classifier 'rff'; did you mean 'rf'"),
        ({"classifiers": []}, "no classifiers to run"),
        ({"folds": []}, "no folds"),
        ({"timeout": 0}, "timeout must be a positive, finite number of seconds or None, got 0"),
        ({"timeout": -1.5}, "timeout must be a positive, finite number of seconds"),
        ({"timeout": float("inf")}, "timeout must be a positive, finite number of seconds"),
        ({"timeout": float("nan")}, "timeout must be a positive, finite number of seconds"),
        ({"max_memory": 0}, "max_memory must be a positive number of bytes up to 2\\*\\*62, got 0"),
        ({"max_memory": 2**63}, "max_memory must be a positive number of bytes"),
        ({"jobs": 0}, "jobs must be a positive number of processes or -1, got 0"),
        ({"jobs": -2}, "jobs must be a positive number"),
        ({"jobs": 0, "scheduler": "tcp://127.0.0.1:9"}, "jobs must be a positive number"),
    ],
)
def test_bad_input_is_refused_before_anything_runs(problem, folds, kwargs, message) -> None:
    arguments = {"classifiers": ["nb"], "folds": folds, "timeout": TIMEOUT, **kwargs}
    with pytest.raises(ConfigurationError, match=message):
        run_tasks(problem, arguments.pop("classifiers"), arguments.pop("folds"), **arguments)


def test_multitarget_problems_run_multitarget_configurations() -> None:
    rng = np.random.default_rng(2)
    Y = np.column_stack([np.arange(60) % 3, (np.arange(60) // 3) % 2])
    X = rng.normal(size=(60, 3)) + 2.0 * Y @ np.array([[1.0, 0, 0], [0, 0, 1.0]])
    problem = Problem(X=X, Y=Y, n_classes=(3, 2), target_names=("gesture", "place"))
    folds, _ = make_folds(Y, n_folds=2)
    results = run_tasks(problem, ["cr:nb"], folds, timeout=TIMEOUT)
    assert [r.status for r in results] == ["ok", "ok"]
    assert all(r.metrics["hamming_score"] > 0.6 for r in results)
    with pytest.raises(ConfigurationError):
        run_tasks(problem, ["nope:nb"], folds, timeout=TIMEOUT)


@pytest.fixture(scope="module")
def dask_scheduler() -> Iterator[str]:
    """The address of a real Dask LocalCluster: one worker process with two threads."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=True, dashboard_address=None
    ) as cluster:
        yield cluster.scheduler_address


def test_dask_local_cluster_runs_the_same_tasks(problem, folds, dask_scheduler) -> None:
    specs = {"failing": stand_in("failing", FailingClassifier)}
    reported: list[TaskKey] = []
    results = run_tasks(
        problem,
        ["nb", "failing", "j48"],
        folds,
        scheduler=dask_scheduler,
        timeout=TIMEOUT,
        extra_specs=specs,
        on_result=lambda r: reported.append(r.key),
    )
    local = run_tasks(problem, ["nb", "j48"], folds, timeout=TIMEOUT)
    assert sorted(reported) == sorted(r.key for r in results)
    assert [r.key.classifier for r in results] == ["nb"] * 3 + ["failing"] * 3 + ["j48"] * 3
    assert all(str(r.error).startswith("ValueError: deliberate failure") for r in results[3:6])
    assert scores_only(results[:3] + results[6:]) == scores_only(local)


def test_an_unreachable_scheduler_is_a_configuration_error(problem, folds, monkeypatch) -> None:
    monkeypatch.setattr("touchbench.benchmark.run.dask_backend.CONNECT_TIMEOUT", "1s")
    with pytest.raises(ConfigurationError, match="cannot reach the Dask scheduler"):
        run_tasks(problem, ["nb"], folds, scheduler="tcp://127.0.0.1:9", timeout=TIMEOUT)


def test_workers_do_not_outlive_a_killed_run(tmp_path: Path) -> None:
    """kill -9 of the process running the engine ends its workers, even mid-fit."""
    import subprocess
    import sys

    pid_file = tmp_path / "sleeper.pid"
    sleeper = f"stand_in('sleeper', SleepingClassifier, pid_file={str(pid_file)!r})"
    script = (
        "from tests.benchmark.test_engine import *\n"
        f"specs = {{'sleeper': {sleeper}}}\n"
        "p = small_problem()\n"
        "folds = make_folds(p.Y, n_folds=2)[0]\n"
        "run_tasks(p, ['sleeper'], folds, timeout=None, extra_specs=specs)\n"
    )
    root = Path(__file__).resolve().parents[2]
    runner = subprocess.Popen([sys.executable, "-c", script], cwd=root)
    try:
        deadline = time.monotonic() + 60
        text = ""
        while not text and time.monotonic() < deadline:
            time.sleep(0.1)
            text = pid_file.read_text() if pid_file.exists() else ""
        worker = int(text)
    finally:
        runner.kill()
        runner.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.kill(worker, 0)
        except ProcessLookupError:
            return
        time.sleep(0.2)
    os.kill(worker, signal.SIGKILL)
    pytest.fail("the worker was still running 10 s after its parent was killed")


def test_a_task_over_the_memory_limit_fails_alone(problem, folds) -> None:
    specs = {"greedy": stand_in("greedy", GreedyClassifier)}
    limited = run_tasks(
        problem,
        ["greedy", "nb"],
        folds[:2],
        timeout=TIMEOUT,
        extra_specs=specs,
        max_memory=100 * 2**20,
    )
    greedy = [r for r in limited if r.key.classifier == "greedy"]
    assert [r.status for r in greedy] == ["error", "error"]
    assert all(str(r.error).startswith("exceeded the memory limit of 100 MB") for r in greedy)
    assert [r.status for r in limited if r.key.classifier == "nb"] == ["ok", "ok"]
    unlimited = run_tasks(problem, ["greedy"], folds[:1], timeout=TIMEOUT, extra_specs=specs)
    assert unlimited[0].status == "ok"


def test_stop_ends_the_run_and_keeps_what_finished(problem, folds, tmp_path: Path) -> None:
    specs = {"sleeper": stand_in("sleeper", SleepingClassifier, pid_file=str(tmp_path / "pid"))}
    reported: list[TaskResult] = []
    with pytest.raises(RunStopped):
        run_tasks(
            problem,
            ["nb", "sleeper"],
            folds,
            timeout=None,
            extra_specs=specs,
            on_result=reported.append,
            stop=lambda: (tmp_path / "pid").exists(),
        )
    assert [r.key.classifier for r in reported] == ["nb"] * 3
    sleeper_pid = int((tmp_path / "pid").read_text())
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.kill(sleeper_pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    with pytest.raises(ProcessLookupError):
        os.kill(sleeper_pid, 0)


def _set_when_parked(event: threading.Event, pid_dir: Path, count: int) -> threading.Thread:
    """A thread that sets ``event`` once ``count`` parked fits are running (or after 120 s,
    so that a run that never parks them cannot hang the test)."""

    def watch() -> None:
        deadline = time.monotonic() + 120
        while len(list(pid_dir.iterdir())) < count and time.monotonic() < deadline:
            time.sleep(0.05)
        event.set()

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    return thread


@pytest.mark.parametrize("where", ["local", "dask"])
def test_a_stop_set_while_tasks_run_ends_the_run_at_the_next_check(
    problem, folds, tmp_path: Path, request: pytest.FixtureRequest, where: str
) -> None:
    """Two fits that never end, a third task waiting: a stop set by another thread (as the
    service's heartbeat sets it) ends the run at the first check that sees it; nothing
    more starts or is reported, and the parked fits' processes are gone."""
    scheduler = request.getfixturevalue("dask_scheduler") if where == "dask" else None
    pid_dir = tmp_path / "pids"
    pid_dir.mkdir()
    specs = {"parked": stand_in("parked", ParkedClassifier, pid_dir=str(pid_dir))}
    event = threading.Event()
    checks: list[bool] = []

    def stop() -> bool:
        checks.append(event.is_set())
        return checks[-1]

    started: list[TaskKey] = []
    reported: list[TaskResult] = []
    watcher = _set_when_parked(event, pid_dir, 2)
    with pytest.raises(RunStopped):
        run_tasks(
            problem,
            ["parked"],
            folds,
            jobs=2,
            scheduler=scheduler,
            timeout=None,
            extra_specs=specs,
            on_start=started.append,
            on_result=reported.append,
            stop=stop,
        )
    watcher.join()
    assert started == [TaskKey("parked", 0, 0), TaskKey("parked", 0, 1)]
    assert reported == []
    assert checks.count(True) == 1 and checks[-1] is True
    pids = [int(path.name) for path in pid_dir.iterdir()]
    assert len(pids) == 2
    for pid in pids:
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)


@pytest.mark.slow
def test_both_backends_run_the_same_plan_to_the_same_results(
    problem, folds, dask_scheduler
) -> None:
    extra = {"sleeper": stand_in("sleeper", SleepingClassifier)}
    specs, tasks = plan_tasks(problem, ["nb", "sleeper", "j48"], folds[:2], extra_specs=extra)
    context = pickle.dumps(TaskContext(problem, specs, list(folds), 0))
    backends: list[Backend] = [
        LocalBackend(context, workers=2, timeout=2.0, max_memory=None),
        DaskBackend(dask_scheduler, context, timeout=2.0, max_memory=None),
    ]
    outcomes = []
    for backend in backends:
        assert isinstance(backend, Backend)
        started: list[TaskKey] = []
        delivered: list[TaskResult] = []
        backend.run(TaskList(tasks), started.append, delivered.append, lambda: False)
        assert started == tasks
        ordered = sorted(delivered, key=lambda r: r.key)
        assert [r.key for r in ordered] == sorted(tasks)
        outcomes.append((scores_only(ordered), [r.error for r in ordered]))
    local, dask = outcomes
    assert local == dask
    assert local[1] == [
        "timed out after 2 s (worker process killed)" if key.classifier == "sleeper" else None
        for key in sorted(tasks)
    ]
