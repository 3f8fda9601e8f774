"""Ctrl-C and SIGTERM stop ``touchbench serve`` within a few seconds whatever it computes
(issue 21, case 3 and 11): exit 130 or 143, ``touchbench: interrupted`` once, no
traceback, also after a second Ctrl-C.  A real service in a subprocess, made busy by
importing a CSV upload (parsed in Python: seconds of computing in a worker thread, which
nothing can interrupt).  The time it takes is bounded by the wait's time-out only."""

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

from tests.app.api.conftest import Server

#: Longest a stop may take before the test fails (the service needs about 5 s at most).
STOP_TIMEOUT = 60.0


def _busy(server: Server, tmp_path: Path) -> threading.Thread:
    """Upload a CSV whose import computes for seconds; returns once the service is at it."""
    columns = 20
    csv = tmp_path / "heavy.csv"
    header = ",".join(f"f{i}" for i in range(columns)) + ",c\n"
    row = ",".join(f"{i}.25" for i in range(columns)) + ",a\n"
    csv.write_bytes((header + row * 150_000).encode())
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
            httpx.post(
                f"{server.url}/api/datasets",
                content=body(),
                headers={"Content-Type": "multipart/form-data; boundary=touchbench-boundary"},
                timeout=STOP_TIMEOUT,
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
    ("signals", "status", "workers"),
    [
        ((signal.SIGINT,), 130, 1),
        ((signal.SIGTERM,), 143, 1),
        ((signal.SIGINT, signal.SIGINT), 130, 1),
        ((signal.SIGTERM,), 143, 2),
    ],
    ids=["ctrl-c", "sigterm", "ctrl-c-twice", "sigterm-2-workers"],
)
def test_a_busy_service_stops_on_a_signal(
    make_sqlite_server: Callable[..., Server],
    tmp_path: Path,
    signals: tuple[signal.Signals, ...],
    status: int,
    workers: int,
) -> None:
    server = make_sqlite_server(arguments=("--workers", str(workers)))
    assert server.process is not None
    uploading = _busy(server, tmp_path)
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


def test_an_idle_service_stops_on_ctrl_c(make_sqlite_server: Callable[..., Server]) -> None:
    server = make_sqlite_server()
    assert server.process is not None
    os.killpg(server.process.pid, signal.SIGINT)
    code, log = _stopped(server)
    assert code == 130, log[-3000:]
    assert "Traceback" not in log and log.count("touchbench: interrupted") == 1, log[-3000:]
