"""A job's worker process runs at a lower CPU priority than the service that started it
(the setting ``job_nice``), and so do the processes it starts: a heavy run shares the
cores with the service's predictions rather than starving them.  Tried on a real service
whose run waits at the test's gate (tests/gate.py) while its processes are looked at."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from tests.support.service import Server
from tests.support.synthetic import touch_arff

JOB_PROCESS = b"touchbench.app.jobs.process"


def _children(pid: int) -> list[int]:
    found = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        children = (task / "children").read_text().split()
        found += [int(child) for child in children]
    return found


def _descendants(pid: int) -> list[int]:
    """The processes under ``pid`` (those that end meanwhile left out)."""
    found, todo = [], [pid]
    while todo:
        try:
            children = _children(todo.pop())
        except FileNotFoundError:
            continue
        found += children
        todo += children
    return found


def _command(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except FileNotFoundError:
        return b""


def test_a_job_process_is_nicer_than_the_service(
    make_sqlite_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_sqlite_server(job_nice="7")
    assert server.process is not None and server.gate is not None
    data = touch_arff(tmp_path / "touch.arff", n=60, with_place=False)
    with data.open("rb") as handle:
        uploaded = server.client.post(
            "/api/datasets", files={"file": (data.name, handle)}, data={"name": "touch"}
        )
    assert uploaded.status_code == 201, uploaded.text
    queued = server.client.post(
        "/api/runs", json={"dataset": "touch", "classifiers": ["gate"], "folds": 2}
    )
    assert queued.status_code == 202, queued.text
    server.gate.wait_started(1)  # the run's first fit waits: its processes are alive
    try:
        service = os.getpriority(os.PRIO_PROCESS, server.process.pid)
        under = _descendants(server.process.pid)
        jobs = [pid for pid in under if JOB_PROCESS in _command(pid)]
        assert len(jobs) == 1, [_command(pid) for pid in under]
        # the job process and whatever it started (the engine's workers)
        working = [jobs[0], *_descendants(jobs[0])]
        for pid in working:
            assert os.getpriority(os.PRIO_PROCESS, pid) == min(service + 7, 19), _command(pid)
    finally:
        server.gate.open()
    server.wait_for(f"/api/runs/{queued.json()['id']}", lambda body: body["status"] == "done")
