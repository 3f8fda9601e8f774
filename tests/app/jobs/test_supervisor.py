"""The worker processes of a dispatcher, with a trivial command in place of a job process:
at most ``limit`` at once, each given its environment, reaped when it ends (a failure
reported), and ended by ``stop``."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from touchbench.app.jobs.queue import Item
from touchbench.app.jobs.supervisor import Supervisor

#: Item 1 exits 0 and item 2 exits 3 once their file ``go-ID`` exists; item 3 sleeps until
#: it is ended.  Each first writes its variable ``SECRET`` to ``env-ID``.
WORKER = """
import os, pathlib, sys, time
folder, item = pathlib.Path(sys.argv[1]), int(sys.argv[2])
(folder / f"env-{item}").write_text(os.environ.get("SECRET", ""))
while item != 3 and not (folder / f"go-{item}").exists():
    time.sleep(0.01)
if item == 3:
    time.sleep(600)
sys.exit({1: 0, 2: 3}[item])
"""


@pytest.fixture
def supervisor(tmp_path: Path) -> Iterator[Supervisor]:
    def command(item: Item) -> list[str]:
        return [sys.executable, "-c", WORKER, str(tmp_path), str(item.id)]

    workers = Supervisor(2, command, lambda: {"SECRET": "s3cret"})
    yield workers
    workers.stop()


def _reap_until(supervisor: Supervisor, busy: frozenset[Item], timeout: float = 60.0) -> bool:
    """Reap until only ``busy`` is left; whether a reaped process failed."""
    failed = False
    deadline = time.monotonic() + timeout
    while supervisor.busy != busy:
        assert time.monotonic() < deadline, supervisor.busy
        failed = supervisor.reap() or failed
        time.sleep(0.01)
    return failed


def test_at_most_limit_processes_each_reaped_and_a_failure_reported(
    supervisor: Supervisor, tmp_path: Path
) -> None:
    one, two, three = Item("run", 1), Item("job", 2), Item("run", 3)
    supervisor.start(one)
    assert not supervisor.full
    supervisor.start(two)
    assert supervisor.full and supervisor.busy == {one, two}
    assert not supervisor.reap()  # both still wait for their go

    (tmp_path / "go-1").touch()
    assert not _reap_until(supervisor, frozenset({two}))  # exit status 0
    assert not supervisor.full
    supervisor.start(three)
    (tmp_path / "go-2").touch()
    assert _reap_until(supervisor, frozenset({three}))  # exit status 3
    assert [(tmp_path / f"env-{i}").read_text() for i in (1, 2)] == ["s3cret"] * 2


def test_stop_ends_every_process(supervisor: Supervisor, tmp_path: Path) -> None:
    supervisor.start(Item("run", 3))
    deadline = time.monotonic() + 60
    while not (tmp_path / "env-3").exists():  # started, and now sleeping
        assert time.monotonic() < deadline
        time.sleep(0.01)
    processes = [worker.process for worker in supervisor._workers]
    supervisor.stop(grace=30)
    assert supervisor.busy == frozenset()
    assert [process.returncode for process in processes] == [-15]  # SIGTERM, not a kill
