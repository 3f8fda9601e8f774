"""A real service on a PostgreSQL store whose URL holds a password: its job processes get
the URL without it on their command line (which any user on the host reads), and its log
says a lost store in one line without the password."""

from __future__ import annotations

import os
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text
from sqlalchemy.engine import Engine, make_url

from tests.support.service import Server, finished, servers
from tests.support.stores import DEFAULT_POSTGRES, psycopg_url
from tests.support.synthetic import touch_arff

PASSWORD = f"pa55-{uuid.uuid4().hex}"


@pytest.fixture
def admin() -> Iterator[Engine]:
    server = os.environ.get("TOUCHBENCH_TEST_POSTGRES_URL", DEFAULT_POSTGRES)
    if not server:
        pytest.skip("no PostgreSQL server for this test")
    engine = create_engine(psycopg_url(server), isolation_level="AUTOCOMMIT")
    yield engine
    engine.dispose()


@pytest.fixture
def secret_url(admin: Engine) -> Iterator[str]:
    """A database of its own owned by a role with a password (the test server trusts every
    client, so any password logs in: what matters is where it shows)."""
    name = f"touchbench_secret_{uuid.uuid4().hex[:8]}"
    try:
        with admin.connect() as connection:
            connection.execute(text(f"CREATE ROLE {name} LOGIN PASSWORD '{PASSWORD}'"))
            connection.execute(text(f"CREATE DATABASE {name} OWNER {name}"))
    except Exception as error:  # no server: this test cannot run
        pytest.skip(f"no PostgreSQL server: {str(error).splitlines()[0]}")
    url = make_url(admin.url).set(username=name, password=PASSWORD, database=name)
    yield url.render_as_string(hide_password=False)
    with admin.connect() as connection:
        connection.execute(text(f"DROP DATABASE IF EXISTS {name} WITH (FORCE)"))
        connection.execute(text(f"DROP ROLE IF EXISTS {name}"))


@pytest.fixture
def make_secret_server(secret_url: str, tmp_path: Path) -> Iterator[Callable[..., Server]]:
    yield from servers(secret_url, tmp_path)


def _descendants(pid: int) -> list[int]:
    """The processes below ``pid``, read from ``/proc/*/stat``."""
    parents: dict[int, int] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:  # ended meanwhile
            continue
        parents[int(stat.parent.name)] = int(fields[1])
    found, frontier = [], [pid]
    while frontier:
        children = [child for child, parent in parents.items() if parent in frontier]
        found += children
        frontier = children
    return found


def _read(path: Path) -> list[str]:
    """The NUL-terminated strings of a ``/proc/PID/cmdline`` or ``environ``."""
    try:
        return path.read_bytes().decode(errors="replace").split("\0")[:-1]
    except OSError:  # ended meanwhile
        return []


def _upload(server: Server, tmp_path: Path) -> None:
    with touch_arff(tmp_path / "t.arff", n=60).open("rb") as handle:
        uploaded = server.client.post(
            "/api/datasets", files={"file": ("t.arff", handle)}, data={"name": "touch"}
        )
    assert uploaded.status_code == 201, uploaded.text


def test_job_processes_have_no_password_on_their_command_line(
    make_secret_server: Callable[..., Server], secret_url: str, tmp_path: Path
) -> None:
    assert PASSWORD in secret_url
    server = make_secret_server()
    gate = server.gate
    assert gate is not None and server.process is not None
    _upload(server, tmp_path)
    started = server.client.post(
        "/api/runs",
        json={"dataset": "touch", "target": "gesture", "classifiers": ["gate"], "folds": 2},
    )
    assert started.status_code == 202, started.text
    gate.wait_started(1)  # the job process is at work, its first fit waiting at the gate

    processes = {
        pid: _read(Path(f"/proc/{pid}/cmdline")) for pid in _descendants(server.process.pid)
    }
    jobs = [pid for pid, argv in processes.items() if "touchbench.app.jobs.process" in argv]
    assert len(jobs) == 1, processes
    for pid, argv in processes.items():
        assert not any(PASSWORD in argument for argument in argv), (pid, argv)
    [job] = jobs
    assert "--db" not in processes[job]
    assert processes[job][-2:] == ["run", str(started.json()["id"])]
    environment = _read(Path(f"/proc/{job}/environ"))  # the service's user's and root's only
    assert any(v.startswith("TOUCHBENCH_DATABASE_URL=") and PASSWORD in v for v in environment)

    gate.open()
    run = server.wait_for(f"/api/runs/{started.json()['id']}", finished)
    assert (run["status"], run["tasks_done"]) == ("done", 2)


def test_a_lost_store_is_one_log_line_without_the_password(
    make_secret_server: Callable[..., Server], secret_url: str, admin: Engine
) -> None:
    server = make_secret_server()
    assert server.log is not None
    role = make_url(secret_url).username
    with admin.connect() as connection:  # the store goes away under the running service
        connection.execute(text(f"ALTER ROLE {role} NOLOGIN"))
        connection.execute(
            text("SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE usename = :role"),
            {"role": role},
        )
    try:
        deadline = time.monotonic() + 120
        while "dispatcher: OperationalError" not in server.log.read_text():
            assert time.monotonic() < deadline, server.log.read_text()[-3000:]
            time.sleep(0.1)
    finally:
        with admin.connect() as connection:
            connection.execute(text(f"ALTER ROLE {role} LOGIN"))
    log = server.log.read_text()
    assert PASSWORD not in log
    lines = log.splitlines()
    warnings = [i for i, line in enumerate(lines) if line.startswith("dispatcher: ")]
    for i in warnings:
        following = lines[i + 1] if i + 1 < len(lines) else ""
        assert not following.startswith(("[SQL", "(Background", "\t", " ")), lines[i : i + 2]
