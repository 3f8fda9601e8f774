"""A real touchbench service: uvicorn on loopback with its own worker processes, driven
with httpx."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.support.cli_runner import run_cli
from tests.support.gate import Gate
from tests.support.synthetic import touch_arff

ROOT = Path(__file__).resolve().parents[2]


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@dataclass
class Server:
    """A ``touchbench serve`` process and a client for it."""

    url: str
    database_url: str
    work_dir: Path
    environment: dict[str, str]
    process: subprocess.Popen[bytes] | None = None
    log: Path | None = None
    arguments: tuple[str, ...] = ()
    gate: Gate | None = None
    client: httpx.Client = field(init=False)

    def start(self, *, timeout: float = 120.0) -> None:
        port = self.url.rsplit(":", 1)[1]
        assert self.log is not None
        command = [
            sys.executable,
            "-m",
            "touchbench.app.cli.main",
            "--db",
            self.database_url,
            "serve",
            "--port",
            port,
            "--log-level",
            "warning",
            *self.arguments,
        ]
        self.process = subprocess.Popen(
            command,
            cwd=ROOT,
            env=self.environment,
            stdout=self.log.open("ab"),
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        headers = {}
        if self.environment.get("TOUCHBENCH_API_KEY"):
            headers["X-API-Key"] = self.environment["TOUCHBENCH_API_KEY"]
        # one client for the polls too: building one costs 20 ms of CPU (its TLS context)
        self.client = httpx.Client(base_url=self.url, timeout=120, headers=headers)
        deadline = time.monotonic() + timeout
        while True:
            assert self.process.poll() is None, self.log.read_text()[-3000:]
            try:
                if self.client.get("/healthz", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            assert time.monotonic() < deadline, "the service did not start"
            time.sleep(0.1)

    def stop(self, sig: int = signal.SIGTERM) -> None:
        if self.process is None:
            return
        if self.process.poll() is None:
            os.killpg(self.process.pid, sig)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait()
        if hasattr(self, "client"):
            self.client.close()
        self.process = None

    def wait_for(
        self, path: str, done: Callable[[dict[str, Any]], bool], *, timeout: float = 300.0
    ) -> dict[str, Any]:
        """Poll ``GET path`` until ``done(body)``; the last body."""
        deadline = time.monotonic() + timeout
        while True:
            response = self.client.get(path)
            assert response.status_code == 200, response.text
            body: dict[str, Any] = response.json()
            if done(body):
                return body
            assert self.process is not None and self.process.poll() is None, "service died"
            assert time.monotonic() < deadline, f"{path} never finished: {body}"
            time.sleep(0.25)


def finished(body: dict[str, Any]) -> bool:
    return body["status"] in {"done", "failed", "cancelled", "interrupted"}


def servers(database_url: str, tmp_path: Path) -> Iterator[Callable[..., Server]]:
    servers: list[Server] = []

    def build(*, arguments: tuple[str, ...] = (), **settings: str) -> Server:
        gate = Gate(
            tmp_path / "gate"
        )  # the `gate` entry waits for the test (tests/support/gate.py)
        environment = {
            **os.environ,
            **gate.environment(),
            "TOUCHBENCH_WORK_DIR": str(tmp_path / "work"),
            "TOUCHBENCH_JOB_WORKERS": "2",
            # the background import only saves a first request's wait; here it costs CPU
            "TOUCHBENCH_WARM_UP": "false",
            **{f"TOUCHBENCH_{key.upper()}": value for key, value in settings.items()},
        }
        environment.pop("TOUCHBENCH_DATABASE_URL", None)
        server = Server(
            url=f"http://127.0.0.1:{free_port()}",
            database_url=database_url,
            work_dir=tmp_path / "work",
            environment=environment,
            log=tmp_path / f"service-{len(servers)}.log",
            arguments=arguments,
            gate=gate,
        )
        servers.append(server)
        server.start()
        return server

    yield build
    for server in servers:
        server.stop()


def cancelled_run(capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path) -> int:
    """A run of the gate classifier cancelled before any fold: resuming it changes it."""
    path = touch_arff(tmp_path / "touch.arff", n=60)
    assert run_cli(capsys, server.database_url, "import", str(path), "--name", "touch").code == 0
    api, gate = server.client, server.gate
    assert gate is not None
    created = api.post(
        "/api/runs",
        json={"dataset": "touch", "target": "gesture", "classifiers": ["gate"], "folds": 3},
    )
    assert created.status_code == 202, created.text
    run_id: int = created.json()["id"]
    gate.wait_started(1)
    assert api.post(f"/api/runs/{run_id}/cancel").status_code == 200
    assert server.wait_for(f"/api/runs/{run_id}", finished)["status"] == "cancelled"
    return run_id


def upload(server: Server, path: Path, **fields: str) -> httpx.Response:
    with path.open("rb") as handle:
        return server.client.post("/api/datasets", files={"file": (path.name, handle)}, data=fields)
