"""One dispatcher per store on a host: several service processes queue work, one starts
the worker processes, at most ``job_workers`` at once and one per run; the others wake it
and take its place when it ends."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable
from datetime import datetime
from itertools import pairwise
from pathlib import Path

import pytest

from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff
from touchbench.app.jobs import dispatcher as dispatching
from touchbench.app.jobs.dispatcher import Dispatcher, dispatch_address
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.runs import BenchRequest
from touchbench.app.services.datasets import import_file
from touchbench.app.services.runs import create_run
from touchbench.app.settings import Settings
from touchbench.app.store.database import Store
from touchbench.app.store.runs import get_run


@pytest.mark.slow
def test_two_service_processes_run_one_job_at_a_time_each_once(
    make_sqlite_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_sqlite_server(job_workers="1", arguments=("--workers", "2"))
    with touch_arff(tmp_path / "t.arff", n=90).open("rb") as handle:
        uploaded = server.client.post(
            "/api/datasets", files={"file": ("t.arff", handle)}, data={"name": "touch"}
        )
    assert uploaded.status_code == 201, uploaded.text
    request = {"dataset": "touch", "target": "gesture", "classifiers": ["nb"], "folds": 2}
    ids = []
    for seed in range(4):
        started = server.client.post("/api/runs", json={**request, "seed": seed})
        assert started.status_code == 202, started.text
        ids.append(started.json()["id"])
    runs = [server.wait_for(f"/api/runs/{run_id}", finished) for run_id in ids]

    assert [run["status"] for run in runs] == ["done"] * 4
    spans = sorted(
        (datetime.fromisoformat(run["started_at"]), datetime.fromisoformat(run["finished_at"]))
        for run in runs
    )
    for (_, earlier_end), (later_start, _) in pairwise(spans):
        assert later_start >= earlier_end, spans  # job_workers=1 holds for the host
    assert server.log is not None
    assert "is being executed by" not in server.log.read_text()  # no second process per run


@pytest.fixture
def touch_store(sqlite_store: Store, tmp_path: Path) -> Store:
    """A SQLite store holding the data set ``touch``."""
    file = touch_arff(tmp_path / "t.arff", n=60)
    import_file(sqlite_store, ImportRequest(file=file, name="touch"))
    return sqlite_store


def _wait_done(store: Store, run_id: int, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while get_run(store, run_id).status != "done":
        assert time.monotonic() < deadline, get_run(store, run_id)
        time.sleep(0.1)


def test_the_leader_hears_a_wake_from_another_process_and_is_replaced_when_it_stops(
    touch_store: Store, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Polling only every 10 minutes: a run is dispatched within the test only if the
    # wake-up reaches the leader.
    monkeypatch.setattr(dispatching, "POLL", 600.0)
    settings = Settings(database_url=touch_store.url, job_workers=1, work_dir=tmp_path / "w")
    first, second = Dispatcher(touch_store, settings), Dispatcher(touch_store, settings)
    first.start()
    deadline = time.monotonic() + 30
    while not first.leading:
        assert time.monotonic() < deadline
        time.sleep(0.01)
    second.start()
    try:
        request = BenchRequest(dataset="touch", classifiers=["nb"], target="gesture", folds=2)
        run = create_run(touch_store, request)
        second.wake()
        _wait_done(touch_store, run.id)
        assert not second.leading

        first.stop()
        later = create_run(touch_store, request)
        second.wake()
        _wait_done(touch_store, later.id)
        assert second.leading
    finally:
        first.stop()
        second.stop()


def test_dispatch_addresses_name_the_store(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    addresses = []
    for folder in ("a", "b", "a"):
        monkeypatch.chdir(tmp_path / folder)
        store = Store("sqlite:///relative.db")
        addresses.append(dispatch_address(store))
        store.dispose()
    assert addresses[0] is not None and addresses[0].startswith("\0touchbench-dispatch-")
    assert addresses[0] == addresses[2] != addresses[1]  # the same file, another file
    memory = Store("sqlite://")
    assert dispatch_address(memory) is None  # a store of its own in every process
    memory.dispose()


#: Binds an address as user ``nobody`` and waits: a neighbour on the host squatting it.
SQUATTER = """
import os, socket, sys, time
os.setuid(65534)
squat = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
squat.bind("\\0" + sys.argv[1])
squat.listen()
print("bound", flush=True)
time.sleep(120)
"""


@pytest.mark.skipif(os.getuid() != 0, reason="needs root to run a squatter as another user")
def test_an_address_held_by_another_user_does_not_stop_dispatching(
    touch_store: Store, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(dispatching, "POLL", 600.0)  # only a wake-up dispatches in time
    address = dispatch_address(touch_store)
    assert address is not None
    squatter = subprocess.Popen(
        [sys.executable, "-c", SQUATTER, address[1:]], stdout=subprocess.PIPE, text=True
    )
    settings = Settings(database_url=touch_store.url, job_workers=1, work_dir=tmp_path / "w")
    dispatcher = Dispatcher(touch_store, settings)
    try:
        assert squatter.stdout is not None and squatter.stdout.readline().strip() == "bound"
        dispatcher.start()
        request = BenchRequest(dataset="touch", classifiers=["nb"], target="gesture", folds=2)
        run = create_run(touch_store, request)
        dispatcher.wake()
        _wait_done(touch_store, run.id)
        assert not dispatcher.leading  # the squatter still holds the address
    finally:
        dispatcher.stop()
        squatter.kill()
        squatter.wait()
