"""docker-compose.yml: it parses and names commands and settings that exist, and its stack
(PostgreSQL, a Dask scheduler and worker, the API with the compose file's settings) works
when started as processes, since these machines run no Docker engine."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
import yaml

from tests.support.service import ROOT, Server, finished, free_port
from tests.support.synthetic import touch_arff
from touchbench.app.settings import Settings

COMPOSE = ROOT / "docker-compose.yml"


def _compose() -> dict[str, Any]:
    return yaml.safe_load(COMPOSE.read_text(encoding="utf-8"))


def test_the_compose_file_names_what_exists() -> None:
    import typer

    from touchbench.app.cli.main import app as cli

    services = _compose()["services"]
    assert {"db", "api", "predictions", "scheduler", "worker"} <= set(services)
    commands = typer.main.get_command(cli).commands  # type: ignore[attr-defined]
    for name in ("api", "predictions"):
        command = services[name]["command"]
        assert command[0] == "touchbench" and command[1] in commands, name
        options = {o for p in commands[command[1]].params for o in p.opts}
        assert {part for part in command if part.startswith("--")} <= options, name
    assert "--predictions-only" in services["predictions"]["command"]
    assert services["scheduler"]["command"][:2] == ["dask", "scheduler"]
    assert services["worker"]["command"][:2] == ["dask", "worker"]
    for name in ("scheduler", "worker"):
        help_text = subprocess.run(
            [
                str(Path(sys.executable).with_name("dask")),
                *services[name]["command"][1:2],
                "--help",
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert help_text.returncode == 0, help_text.stderr
        for option in [part for part in services[name]["command"] if part.startswith("--")]:
            assert option in help_text.stdout, (name, option)
    known = {f"TOUCHBENCH_{field.upper()}" for field in Settings.model_fields}
    for name, service in services.items():
        environment = service.get("environment", {})
        for key, value in environment.items():
            if key.startswith("TOUCHBENCH_"):
                assert key in known, (name, key)
            if re.search(r"PASSWORD|API_KEY|SECRET", key):
                assert str(value).startswith("${") or "${" in str(value), (name, key)
    assert "TOUCHBENCH_API_KEY" in services["api"]["environment"]
    for name in ("db", "scheduler", "api", "predictions"):
        assert services[name].get("healthcheck"), f"{name} has no health check"
    assert "${TOUCHBENCH_DB_PASSWORD" in services["api"]["environment"]["TOUCHBENCH_DATABASE_URL"]


def _expand(value: str, variables: dict[str, str]) -> str:
    """Compose's ``${NAME:?message}`` and ``${NAME}`` substitution."""
    return re.sub(r"\$\{(\w+)(?::\?[^}]*)?\}", lambda m: variables[m.group(1)], value)


@pytest.fixture
def dask_cluster(tmp_path: Path) -> Iterator[str]:
    """The compose file's scheduler and worker commands, as processes on loopback."""
    services = _compose()["services"]
    port = free_port()
    dask = str(Path(sys.executable).with_name("dask"))
    scheduler_command = [
        dask,
        "scheduler",
        "--host",
        "127.0.0.1",
        "--port",
        str(port),
        "--dashboard-address",
        ":0",
    ]
    worker_command = [dask, *services["worker"]["command"][1:]]
    worker_command[worker_command.index("tcp://scheduler:8786")] = f"tcp://127.0.0.1:{port}"
    environment = {**os.environ, "PYTHONPATH": str(ROOT), **services["worker"]["environment"]}
    log = (tmp_path / "dask.log").open("wb")
    processes = [
        subprocess.Popen(
            scheduler_command,
            env=environment,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        ),
    ]
    time.sleep(1.0)
    processes.append(
        subprocess.Popen(
            worker_command,
            env=environment,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
    )
    try:
        from distributed import Client

        with Client(f"tcp://127.0.0.1:{port}", timeout="60s") as client:
            client.wait_for_workers(1, timeout=120)
        yield f"tcp://127.0.0.1:{port}"
    finally:
        for process in processes:
            os.killpg(process.pid, signal.SIGTERM)
        for process in processes:
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
        log.close()


def _service(name: str, postgres_database: str, tmp_path: Path, **variables: str) -> Server:
    """The compose file's service ``name`` as a process on loopback: its command's options
    but the address, its environment with the compose network's host names replaced by
    those this machine reaches."""
    from sqlalchemy.engine import make_url

    service = _compose()["services"][name]
    environment = service["environment"].items()
    settings = {key: _expand(str(value), variables) for key, value in environment}
    database = make_url(postgres_database)
    settings["TOUCHBENCH_DATABASE_URL"] = (
        make_url(settings["TOUCHBENCH_DATABASE_URL"])
        .set(
            host=database.host,
            port=database.port,
            username=database.username,
            database=database.database,
            drivername="postgresql+psycopg",
        )
        .render_as_string(hide_password=False)
    )
    settings["TOUCHBENCH_WORK_DIR"] = str(tmp_path / "work")
    command = service["command"]
    assert command[:2] == ["touchbench", "serve"]
    options = command[2:]
    for address in ("--host", "--port"):  # loopback and a free port here
        at = options.index(address)
        options = options[:at] + options[at + 2 :]
    return Server(
        url=f"http://127.0.0.1:{free_port()}",
        database_url=settings["TOUCHBENCH_DATABASE_URL"],
        work_dir=tmp_path / "work",
        environment={**os.environ, "PYTHONPATH": str(ROOT), **settings},
        log=tmp_path / f"{name}.log",
        arguments=tuple(options),
    )


@pytest.mark.slow
def test_the_compose_stack_as_processes(
    postgres_database: str, dask_cluster: str, tmp_path: Path
) -> None:
    variables = {
        "TOUCHBENCH_DB_PASSWORD": "postgres",
        "TOUCHBENCH_API_KEY": "stack-key-of-the-lab",
        "TOUCHBENCH_ALLOWED_HOSTS": "localhost",
    }
    from sqlalchemy import create_engine, text

    engine = create_engine(postgres_database, isolation_level="AUTOCOMMIT")
    with engine.connect() as connection:
        connection.execute(text("DROP SCHEMA public CASCADE"))
        connection.execute(text("CREATE SCHEMA public"))
    engine.dispose()

    server = _service("api", postgres_database, tmp_path, **variables)
    server.environment["TOUCHBENCH_DASK_SCHEDULER"] = dask_cluster
    robots = _service("predictions", postgres_database, tmp_path, **variables)
    server.start()
    try:
        robots.start()  # after the full service, as the compose file orders them
        api = server.client
        assert httpx.get(f"{server.url}/api/runs").status_code == 401
        path = touch_arff(tmp_path / "touch.arff", n=90)
        with path.open("rb") as handle:
            uploaded = api.post("/api/datasets", files={"file": (path.name, handle)})
        assert uploaded.status_code == 201, uploaded.text
        run = api.post(
            "/api/runs",
            json={
                "dataset": "touch",
                "target": "gesture",
                "classifiers": ["nb", "j48"],
                "folds": 3,
            },
        )
        assert run.status_code == 202, run.text
        done = server.wait_for(f"/api/runs/{run.json()['id']}", finished, timeout=600)
        assert done["status"] == "done" and done["tasks_done"] == 6, done
        board = api.get(f"/api/runs/{done['id']}/leaderboard").json()
        assert [row["n_ok"] for row in board["leaderboard"]] == [3, 3]
        job = api.post("/api/models", json={"run": done["id"]}).json()
        model = server.wait_for(f"/api/jobs/{job['job']}", finished, timeout=600)
        assert model["status"] == "done", model
        instance = {"instances": [{"f0": 4.0, "f1": 0.0, "f2": 0, "f3": 0, "mic": "both"}]}
        # robots predict on the predictions-only process, with the key; it starts nothing
        model_id = model["result"]["model_id"]
        unkeyed = httpx.post(f"{robots.url}/api/models/{model_id}/predict", json=instance)
        assert unkeyed.status_code == 401, unkeyed.text
        refused = robots.client.post("/api/runs", json={"dataset": "touch"})
        assert refused.status_code == 404, refused.text
        for service in (robots, server):
            predicted = service.client.post(f"/api/models/{model_id}/predict", json=instance)
            assert predicted.status_code == 200 and predicted.json()["predictions"][0]["gesture"]
    finally:
        robots.stop()
        server.stop()
    from distributed import Client

    with Client(dask_cluster, timeout="60s") as client:
        prefixes = client.run_on_scheduler(_task_prefixes)
    assert "touchbench" in prefixes, f"the run's tasks did not go to Dask: {prefixes}"


def _task_prefixes(dask_scheduler: Any) -> list[str]:
    return sorted(dask_scheduler.task_prefixes)
