"""Ctrl-C and SIGTERM stop ``touchbench serve`` within a few seconds whatever it computes
(issue 21, case 3 and 11): exit 130 or 143, ``touchbench: interrupted`` once, no
traceback, also after a second Ctrl-C; the upload the stop cuts short is answered 503 in
JSON.  A real service in a subprocess, made busy by importing a CSV upload (parsed in
Python: seconds of computing in a worker thread, which nothing can interrupt).  The time
it takes is bounded by the wait's time-out only."""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import pytest

from tests.support.service import Server

#: Longest a stop may take before the test fails (the service needs about 5 s at most).
STOP_TIMEOUT = 60.0


def _busy(
    server: Server, tmp_path: Path, answers: list[httpx.Response], rows: int
) -> threading.Thread:
    """Upload a CSV of ``rows`` whose import computes for seconds; returns once the service
    is at it.  The answer, if the upload gets one, goes into ``answers``."""
    columns = 20
    csv = tmp_path / "heavy.csv"
    header = ",".join(f"f{i}" for i in range(columns)) + ",c\n"
    row = ",".join(f"{i}.25" for i in range(columns)) + ",a\n"
    csv.write_bytes((header + row * rows).encode())
    sent = threading.Event()

    def body() -> Iterator[bytes]:
        boundary = "touchbench-boundary"
        yield (
            f'--{boundary}\r\nContent-Disposition: form-data; name="file"; '
            f'filename="heavy.csv"\r\nContent-Type: text/csv\r\n\r\n'
        ).encode()
        yield csv.read_bytes()
        yield f"\r\n--{boundary}--\r\n".encode()
        sent.set()

    def upload() -> None:
        with contextlib.suppress(httpx.HTTPError):  # the service stops under it
            answers.append(
                httpx.post(
                    f"{server.url}/api/datasets",
                    content=body(),
                    headers={"Content-Type": "multipart/form-data; boundary=touchbench-boundary"},
                    timeout=STOP_TIMEOUT,
                )
            )

    thread = threading.Thread(target=upload, daemon=True)
    thread.start()
    assert sent.wait(STOP_TIMEOUT), "the upload was not sent"
    time.sleep(1.0)  # the file is saved and its import under way
    return thread


def _stopped(server: Server) -> tuple[int, str]:
    """The service's exit status and what it printed, once it ends."""
    assert server.process is not None and server.log is not None
    status = server.process.wait(timeout=STOP_TIMEOUT)
    return status, server.log.read_text(errors="replace")


@pytest.mark.parametrize(
    ("signals", "status", "workers", "answered"),
    [
        ((signal.SIGINT,), 130, 1, True),
        ((signal.SIGTERM,), 143, 1, True),
        # a second Ctrl-C ends the process at once; the supervisor of 2 kills its workers
        ((signal.SIGINT, signal.SIGINT), 130, 1, False),
        ((signal.SIGTERM,), 143, 2, False),
    ],
    ids=["ctrl-c", "sigterm", "ctrl-c-twice", "sigterm-2-workers"],
)
@pytest.mark.slow
def test_a_busy_service_stops_on_a_signal(
    make_sqlite_server: Callable[..., Server],
    tmp_path: Path,
    signals: tuple[signal.Signals, ...],
    status: int,
    workers: int,
    answered: bool,
) -> None:
    server = make_sqlite_server(arguments=("--workers", str(workers)))
    assert server.process is not None
    answers: list[httpx.Response] = []
    # an import far longer than the stop's grace of 2 s on any machine, in every case: the
    # workers of a supervisor get that grace too, and a shorter import could end inside it
    uploading = _busy(server, tmp_path, answers, 400_000)
    for signum in signals:
        if signum == signal.SIGINT:  # Ctrl-C: the terminal signals the whole group
            os.killpg(server.process.pid, signum)
        else:  # kill, systemd: the service's process
            os.kill(server.process.pid, signum)
        time.sleep(0.3)
    code, log = _stopped(server)
    assert code == status, log[-3000:]
    assert "Traceback" not in log, log[-3000:]
    assert "CancelledError" not in log, log[-3000:]
    assert log.count("touchbench: interrupted") == 1, log[-3000:]
    uploading.join(STOP_TIMEOUT)
    # the request the stop cut short: a JSON 503 (uvicorn's would be a plain-text 500)
    assert [answer.status_code for answer in answers] == (
        [503] if answered else [503] * len(answers)
    )
    for answer in answers:
        assert answer.json()["error"]["type"] == "ServiceUnavailable", answer.text


def test_an_idle_service_stops_on_ctrl_c(make_sqlite_server: Callable[..., Server]) -> None:
    server = make_sqlite_server()
    assert server.process is not None
    os.killpg(server.process.pid, signal.SIGINT)
    code, log = _stopped(server)
    assert code == 130, log[-3000:]
    assert "Traceback" not in log and log.count("touchbench: interrupted") == 1, log[-3000:]
