"""Keys on a real ``touchbench serve``: refused at start-up when empty, short or in a file
others can read; several named keys with the roles read, predict and write; the log names
the key of every change of state and never shows a key."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest
from websockets.sync.client import connect

from tests.support.cli_runner import run_cli
from tests.support.service import ROOT, Server, free_port
from tests.support.synthetic import touch_arff

READ = "read-key-of-robot-1"
PREDICT = "predict-key-of-arm-2"
WRITE = "write-key-of-the-lab"
DEFAULT = "default-key-of-the-lab"


def _serve(tmp_path: Path, *arguments: str, **settings: str) -> subprocess.CompletedProcess[str]:
    """``touchbench serve`` expected to refuse to start (it would run until stopped)."""
    environment = {
        key: value
        for key, value in os.environ.items()
        if not key.startswith("TOUCHBENCH_") or key == "TOUCHBENCH_TEST_POSTGRES_URL"
    }
    environment.update({f"TOUCHBENCH_{key.upper()}": value for key, value in settings.items()})
    command = [
        sys.executable,
        "-m",
        "touchbench.app.cli.main",
        "--db",
        f"sqlite:///{tmp_path / 's.db'}",
    ]
    return subprocess.run(
        [*command, "serve", "--port", str(free_port()), *arguments],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=120,
    )


def _key_file(tmp_path: Path, mode: int, text: str, name: str = "keys") -> Path:
    path = tmp_path / name
    path.write_text(text)
    path.chmod(mode)
    return path


def test_bad_keys_and_hosts_stop_the_service_in_one_line(tmp_path: Path) -> None:
    good = f"robot read {READ}\n"
    cases: list[tuple[tuple[str, ...], dict[str, str], str, str | None]] = [
        ((), {"api_key": ""}, "TOUCHBENCH_API_KEY: the key is empty", None),
        ((), {"api_key": "tiny-key-1"}, "TOUCHBENCH_API_KEY: the key is 10", "tiny-key-1"),
        ((), {"api_keys": "robot:read:short-key-2"}, "KEYS entry 1: the key is 11", "short-key-2"),
        ((), {"api_keys": f"robot:admin:{READ}"}, "roles are read, predict, write", READ),
        ((), {"api_key": WRITE, "api_keys": f"lab:read:{WRITE}"}, "two keys are the same", WRITE),
        (
            (),
            {"api_keys": str(_key_file(tmp_path, 0o644, good))},
            "TOUCHBENCH_API_KEYS file keys: readable or writable by others",
            READ,
        ),
        (
            (),
            {"api_keys": str(_key_file(tmp_path, 0o640, good, "keys-640"))},
            "(mode 640); make it private with chmod 600",
            READ,
        ),
        ((), {"api_keys": str(tmp_path / "absent")}, "cannot be read", None),
        ((), {"api_keys": " "}, "TOUCHBENCH_API_KEYS: empty", None),
        (
            (),
            {"api_keys": f"robot:read:{READ},robot:write:{WRITE}"},
            "TOUCHBENCH_API_KEYS entry 2: the key's name is also TOUCHBENCH_API_KEYS entry 1's",
            READ,
        ),
        # a key given in the wrong place is refused without being shown
        ((), {"api_keys": READ}, "TOUCHBENCH_API_KEYS: not name:role:key entries", READ),
        ((), {"api_keys": f"robot:{READ}:read"}, "KEYS entry 1: not a role; roles are", READ),
        ((), {"api_keys": f"{READ}:read:robot"}, "KEYS entry 1: the key is 5 characters", READ),
        (
            (),
            {"api_keys": f"lab:write:{WRITE},{READ}"},
            "TOUCHBENCH_API_KEYS entry 2: not name:role:key",
            READ,
        ),
        (
            (),
            {"api_keys": str(_key_file(tmp_path, 0o600, f"robot {READ} read\n", "swapped"))},
            "TOUCHBENCH_API_KEYS file swapped line 1: not a role",
            READ,
        ),
        # a key that cannot be sent as a header: it would start and refuse every request
        ((), {"api_key": "clé-du-laboratoire-1"}, "printable ASCII characters only", "clé"),
        ((), {"api_key": "key-of-the-lab\x7f-12345"}, "a control or a non-ASCII", "key-of"),
        ((), {"api_keys": "lab:write:key of the lab 1234"}, "KEYS entry 1: the key holds", "lab 1"),
        ((), {"allowed_hosts": "http://lab.example"}, "TOUCHBENCH_ALLOWED_HOSTS:", None),
        ((), {"allowed_origins": "lab.example"}, "TOUCHBENCH_ALLOWED_ORIGINS:", None),
        (
            ("--host", "0.0.0.0"),
            {"api_key": WRITE},
            "0.0.0.0 is reachable from other machines and TOUCHBENCH_ALLOWED_HOSTS is not set",
            WRITE,
        ),
        (  # the empty key no longer passes the guard beyond loopback
            ("--host", "0.0.0.0"),
            {"api_key": "", "allowed_hosts": "lab.example"},
            "TOUCHBENCH_API_KEY: the key is empty",
            None,
        ),
    ]
    for arguments, settings, words, secret in cases:
        done = _serve(tmp_path, *arguments, **settings)
        lines = done.stderr.splitlines()
        assert done.returncode == 2, (settings, done.stderr)
        assert len(lines) == 1 and words in lines[0], (settings, done.stderr)
        assert "Traceback" not in done.stderr and done.stdout == ""
        if secret is not None:
            assert secret not in done.stderr


def test_serve_beyond_loopback_answers_its_configured_names(
    make_sqlite_server: Callable[..., Server],
) -> None:
    server = make_sqlite_server(
        arguments=("--host", "0.0.0.0"), api_key=WRITE, allowed_hosts="lab-pc.example"
    )
    port = server.url.rsplit(":", 1)[1]
    for host, status in ((f"lab-pc.example:{port}", 200), ("127.0.0.1", 200), ("evil", 400)):
        assert server.client.get("/api/runs", headers={"Host": host}).status_code == status


def _client(server: Server, key: str) -> httpx.Client:
    return httpx.Client(base_url=server.url, timeout=120, headers={"X-API-Key": key})


def test_roles_read_predict_and_write(
    capsys: pytest.CaptureFixture[str], make_server: Callable[..., Server], tmp_path: Path
) -> None:
    keys = _key_file(
        tmp_path,
        0o600,
        f"# name role key\nrobot1 read {READ}\n\narm2 predict {PREDICT}\n",
    )
    server = make_server(
        arguments=("--log-level", "info"),
        api_key=DEFAULT,
        api_keys=f"{keys}",
    )
    url = server.database_url
    assert (
        run_cli(capsys, url, "import", str(touch_arff(tmp_path / "t.arff")), "--name", "t").code
        == 0
    )
    assert run_cli(capsys, url, "train", "t", "-c", "nb", "--target", "gesture").code == 0
    model = server.client.get("/api/models").json()["models"][0]
    predict = f"/api/models/{model['id']}/predict"
    instance = {"instances": [{"f0": 1.0, "f1": 2.0, "f2": 0.0, "f3": 0.0, "mic": "both"}]}
    upload = touch_arff(tmp_path / "u.arff", n=30, seed=4)
    run = {"dataset": "t", "target": "gesture", "classifiers": ["nb"], "folds": 3}
    reader, predictor, writer = (_client(server, key) for key in (READ, PREDICT, WRITE))
    try:
        # read: every GET, nothing else
        assert reader.get("/api/datasets").status_code == 200
        assert reader.get(f"/api/models/{model['id']}").status_code == 200
        assert (
            reader.get("/").status_code == 200
            and reader.get("/fragments/datasets").status_code == 200
        )
        for method, path, body in (
            ("DELETE", "/api/datasets/t", None),
            ("POST", "/api/runs", run),
            ("POST", predict, instance),
            ("POST", "/api/models", {"run": 1}),
        ):
            answer = reader.request(method, path, json=body)
            assert answer.status_code == 403, (method, path, answer.text)
            assert "'robot1' is a read key" in answer.json()["error"]["message"]
        with upload.open("rb") as handle:
            refused = reader.post("/api/datasets", files={"file": (upload.name, handle)})
        assert refused.status_code == 403
        # predict: predictions and uploads too, but no runs and no deleting
        assert predictor.post(predict, json=instance).status_code == 200
        with upload.open("rb") as handle:
            uploaded = predictor.post(
                "/api/datasets", files={"file": (upload.name, handle)}, data={"name": "u"}
            )
        assert uploaded.status_code == 201, uploaded.text
        for method, path, body in (
            ("DELETE", "/api/datasets/u", None),
            ("DELETE", f"/api/models/{model['id']}", None),
            ("POST", "/api/runs", run),
        ):
            answer = predictor.request(method, path, json=body)
            assert answer.status_code == 403, (method, path, answer.text)
            assert "needs a write key" in answer.json()["error"]["message"]
        # a wrong key, an empty one and no key
        assert httpx.get(f"{server.url}/api/runs", headers={"X-API-Key": ""}).status_code == 403
        assert (
            httpx.get(f"{server.url}/api/runs", headers={"X-API-Key": READ + "x"}).status_code
            == 403
        )
        assert httpx.get(f"{server.url}/api/runs").status_code == 401
        # write (TOUCHBENCH_API_KEY, named default): everything
        assert server.client.post("/api/runs", json=run).status_code == 202
        assert server.client.delete("/api/datasets/u").status_code == 200
        assert server.client.delete(f"/api/models/{model['id']}").status_code == 200
        assert writer.get("/api/runs").status_code == 403  # not a key of this service
    finally:
        for client in (reader, predictor, writer):
            client.close()
    # the live WebSocket predicts: read is refused, predict gets as far as the model
    url_ws = server.url.replace("http://", "ws://") + "/api/models/nope/live"
    header = '{"samplerate": 44100, "channels": 1, "api_key": "%s"}'
    for key, words in ((READ, "'robot1' is a read key"), (PREDICT, "no model 'nope'")):
        with connect(url_ws, open_timeout=30) as socket:
            socket.send(header % key)
            with pytest.raises(Exception, match=words):
                socket.recv(timeout=30)

    server.stop()
    assert server.log is not None
    log = server.log.read_text()
    for line in (
        f"POST /api/models/{model['id']}/predict by key 'arm2'",
        "POST /api/datasets by key 'arm2'",
        "POST /api/runs by key 'default'",
        "DELETE /api/datasets/u by key 'default'",
        f"DELETE /api/models/{model['id']} by key 'default'",
    ):
        assert line in log, line
    assert "by key 'robot1'" not in log  # its changes were refused; its reads are not logged
    for secret in (READ, PREDICT, WRITE, DEFAULT):
        assert secret not in log


def _fragments(secret: str, length: int = 10) -> set[str]:
    """Every run of ``length`` characters of ``secret``: what a cut-short log line shows."""
    return {secret[i : i + length] for i in range(len(secret) - length + 1)}


@pytest.mark.parametrize("level", ["debug", "info", "warning"])
def test_no_key_reaches_the_log_at_any_level(
    level: str, make_sqlite_server: Callable[..., Server]
) -> None:
    """Keys sent every way a client may send one (the X-API-Key header of a request and of
    a WebSocket handshake, a query parameter, a JSON body, the live header message), right
    and wrong, appear in no line of the service's log, whatever its level."""
    wrong = "wrong-key-nobody-was-given-1"
    server = make_sqlite_server(
        arguments=("--log-level", level), api_key=DEFAULT, api_keys=f"arm2:predict:{PREDICT}"
    )
    assert server.client.get("/api/runs").status_code == 200
    assert httpx.get(f"{server.url}/api/runs", headers={"X-API-Key": wrong}).status_code == 403
    assert httpx.get(f"{server.url}/api/runs", params={"api_key": DEFAULT}).status_code == 401
    sent = server.client.post("/api/runs", json={"api_key": DEFAULT, "dataset": wrong})
    assert sent.status_code in (404, 422), sent.text
    live = server.url.replace("http://", "ws://") + "/api/models/nope/live"
    for handshake, message, words in (
        (PREDICT, PREDICT, "no model 'nope'"),
        (None, DEFAULT, "no model 'nope'"),
        (None, wrong, "wrong API key"),
        (wrong, None, "wrong API key"),
    ):
        headers = {"X-API-Key": handshake} if handshake else {}
        header = {"samplerate": 44100, "channels": 1}
        if message:
            header["api_key"] = message
        with connect(live, additional_headers=headers, open_timeout=30) as socket:
            socket.send(json.dumps(header))
            with pytest.raises(Exception, match=words):
                socket.recv(timeout=30)
    server.stop()
    assert server.log is not None
    log = server.log.read_text()
    for secret in (DEFAULT, PREDICT, wrong):
        shown = {fragment for fragment in _fragments(secret) if fragment in log}
        assert not shown, (level, shown)
    # the log did say what was sent, without the keys
    if level == "debug":
        assert "< x-api-key: ***" in log and "with a key: not shown" in log
    if level in ("debug", "info"):
        assert '"GET /api/runs?api_key=*** HTTP/1.1" 401' in log
        assert "POST /api/runs by key 'default'" in log
    else:
        assert "INFO:" not in log and "DEBUG:" not in log


def test_without_keys_changes_are_logged_as_keyless(
    make_sqlite_server: Callable[..., Server],
) -> None:
    server = make_sqlite_server(arguments=("--log-level", "info"))
    assert server.client.delete("/api/datasets/none").status_code == 404
    forged = "/api/datasets/x%0AINFO%3A%20%20%20%20%20DELETE%20everything%20by%20key%20lab"
    assert server.client.delete(forged).status_code == 404
    server.stop()
    assert server.log is not None
    log = server.log.read_text()
    assert "DELETE /api/datasets/none by key (none: the service has no key)" in log
    assert f"DELETE {forged} by key (none" in log  # as sent: no line of its own
    assert "\nINFO:     DELETE everything by key lab" not in log


def test_every_route_a_predict_key_may_change_exists_and_lets_it_in(tmp_path: Path) -> None:
    from fastapi.testclient import TestClient

    from touchbench.app.api.deps import PREDICT_ROUTES
    from touchbench.app.main import create_app
    from touchbench.app.settings import Settings

    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 's.db'}",
        work_dir=tmp_path / "work",
        api_keys=f"arm:predict:{PREDICT},robot:read:{READ}",
    )
    app = create_app(settings)
    paths = app.openapi()["paths"]
    for method, path in PREDICT_ROUTES:
        assert method.lower() in paths.get(path, {}), (method, path)
    with TestClient(app, base_url="http://localhost") as client:
        for method, path in sorted(PREDICT_ROUTES):
            url = path.replace("{model_ref}", "nope")
            for key, allowed in ((PREDICT, True), (READ, False)):
                answer = client.request(method, url, headers={"X-API-Key": key})
                assert (answer.status_code != 403) is allowed, (key, path, answer.text)
