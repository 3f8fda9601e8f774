"""The service's trust boundary for browsers and DNS, on a real ``touchbench serve``: it
answers only its host names, refuses state changes and WebSocket handshakes from foreign
origins with or without a key, and keeps CORS closed unless origins are listed."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from tests.support.service import Server, cancelled_run, servers
from tests.support.synthetic import touch_arff

FOREIGN = "http://127.0.0.1:9"  # another port of the same machine is another origin
KEY = "trust-key-of-the-lab"


def _upload(api: httpx.Client, path: Path, name: str, **headers: str) -> httpx.Response:
    with path.open("rb") as handle:
        return api.post(
            "/api/datasets",
            files={"file": (path.name, handle)},
            data={"name": name},
            headers=headers,
        )


def _names(api: httpx.Client) -> set[str]:
    answer = api.get("/api/datasets")
    assert answer.status_code == 200, answer.text
    return {row["name"] for row in answer.json()["datasets"]}


@pytest.fixture(scope="module")
def plain(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """A service on SQLite with the default settings (no key, no hosts or origins listed),
    started once for the tests that send it only what it must refuse or what writes nothing
    (each test that changes its state or its settings starts a service of its own)."""
    folder = tmp_path_factory.mktemp("trust-plain")
    builder = servers(f"sqlite:///{folder / 'touchbench.db'}", folder)
    yield next(builder)()
    for _ in builder:  # stops the service
        pass


def _refused(answer: httpx.Response, status: int, kind: str, where: str) -> dict[str, Any]:
    assert answer.status_code == status, answer.text
    assert answer.headers["content-type"] == "application/json"
    error: dict[str, Any] = answer.json()["error"]
    assert (error["type"], error["where"]) == (kind, where)
    return error


def test_other_host_names_are_refused_as_dns_rebinding_would_send_them(
    plain: Server, tmp_path: Path
) -> None:
    server = plain
    port = server.url.rsplit(":", 1)[1]
    api = server.client
    data = touch_arff(tmp_path / "touch.arff", n=30)
    for host in (f"evil.example:{port}", "evil.example", f"127.0.0.1.evil.example:{port}"):
        for path in ("/api/datasets", "/healthz", "/"):
            error = _refused(
                api.get(path, headers={"Host": host}), 400, "DisallowedHost", "headers.Host"
            )
            assert host in error["message"] and "TOUCHBENCH_ALLOWED_HOSTS" in error["message"]
        _refused(_upload(api, data, "rebound", Host=host), 400, "DisallowedHost", "headers.Host")
    for host in (f"localhost:{port}", f"LOCALHOST:{port}", f"[::1]:{port}", f"127.0.0.1:{port}"):
        assert api.get("/api/datasets", headers={"Host": host}).status_code == 200, host
    assert _names(api) == set()  # the refused upload wrote nothing


def test_allowed_hosts_are_answered_besides_loopback(
    make_sqlite_server: Callable[..., Server],
) -> None:
    server = make_sqlite_server(allowed_hosts="lab-pc.example, 192.168.7.20")
    port = server.url.rsplit(":", 1)[1]
    for host in (f"lab-pc.example:{port}", "Lab-PC.example", f"192.168.7.20:{port}", "localhost"):
        assert server.client.get("/api/runs", headers={"Host": host}).status_code == 200, host
    for host in ("lab-pc.example.evil.example", "192.168.7.21", "evil.example"):
        answer = server.client.get("/api/runs", headers={"Host": host})
        _refused(answer, 400, "DisallowedHost", "headers.Host")


def test_state_changes_from_a_foreign_origin_are_refused_and_from_its_own_accepted(
    capsys: pytest.CaptureFixture[str], make_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_server()  # no key: the case where any page could write
    api = server.client
    run_id = cancelled_run(capsys, server, tmp_path)
    data = touch_arff(tmp_path / "other.arff", n=30, seed=2)
    for foreign in (FOREIGN, "http://evil.example", "null", "http://localhost:1"):
        error = _refused(
            _upload(api, data, "stolen", Origin=foreign), 403, "Forbidden", "headers.Origin"
        )
        assert foreign in error["message"] and "TOUCHBENCH_ALLOWED_ORIGINS" in error["message"]
        resumed = api.post(f"/api/runs/{run_id}/resume", headers={"Origin": foreign})
        _refused(resumed, 403, "Forbidden", "headers.Origin")
        deleted = api.delete("/api/datasets/touch", headers={"Origin": foreign})
        _refused(deleted, 403, "Forbidden", "headers.Origin")
        # reading is not refused, and the answer carries no CORS header a browser would honour
        read = api.get("/api/datasets", headers={"Origin": foreign})
        assert read.status_code == 200 and "access-control-allow-origin" not in read.headers
    assert _names(api) == {"touch"}
    assert api.get(f"/api/runs/{run_id}").json()["status"] == "cancelled"

    # the service's own origin (the dashboard) and clients that send no Origin
    assert _upload(api, data, "own", Origin=server.url).status_code == 201
    other = touch_arff(tmp_path / "third.arff", n=30, seed=3)
    assert _upload(api, other, "curl").status_code == 201
    assert _names(api) == {"touch", "own", "curl"}
    resumed = api.post(f"/api/runs/{run_id}/resume", headers={"Origin": server.url})
    assert resumed.status_code == 202 and resumed.json()["status"] == "queued", resumed.text
    cancelled = api.post(f"/api/runs/{run_id}/cancel")  # no Origin
    assert cancelled.status_code == 200, cancelled.text


def test_a_key_does_not_let_a_foreign_origin_in(
    make_sqlite_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_sqlite_server(api_key=KEY)
    api = server.client  # sends the key
    data = touch_arff(tmp_path / "touch.arff", n=30)
    _refused(_upload(api, data, "stolen", Origin=FOREIGN), 403, "Forbidden", "headers.Origin")
    resumed = api.post("/api/runs/1/resume", headers={"Origin": FOREIGN})  # 404 without Origin
    _refused(resumed, 403, "Forbidden", "headers.Origin")
    assert _names(api) == set()
    assert _upload(api, data, "own", Origin=server.url).status_code == 201
    assert api.post("/api/runs/1/resume").status_code == 404


def test_websocket_handshakes_from_a_foreign_origin_are_refused(plain: Server) -> None:
    server = plain
    url = server.url.replace("http://", "ws://") + "/api/models/nope/live"
    for foreign in (FOREIGN, "http://evil.example", "null"):
        with pytest.raises(InvalidStatus) as refused:
            connect(url, origin=foreign, open_timeout=30)  # type: ignore[arg-type]
        response = refused.value.response
        assert response.status_code == 403
        assert b"Forbidden" in response.body and b"WebSocket" in response.body
    for origin in (server.url, None):  # its own origin, and a robot's client (no Origin)
        with connect(url, origin=origin, open_timeout=30) as socket:  # type: ignore[arg-type]
            socket.send('{"samplerate": 44100, "channels": 1}')
            with pytest.raises(Exception, match="no model 'nope'"):
                socket.recv(timeout=30)


def test_cors_stays_closed_unless_origins_are_listed(
    plain: Server, make_sqlite_server: Callable[..., Server], tmp_path: Path
) -> None:
    preflight = {"Origin": FOREIGN, "Access-Control-Request-Method": "POST"}
    closed = plain
    answer = closed.client.options("/api/datasets", headers=preflight)
    assert answer.status_code >= 400 and "access-control-allow-origin" not in answer.headers

    listed = make_sqlite_server(allowed_origins=f"{FOREIGN}, https://lab.example")
    answer = listed.client.options(
        "/api/datasets", headers={**preflight, "Access-Control-Request-Headers": "x-api-key"}
    )
    assert answer.status_code == 200
    assert answer.headers["access-control-allow-origin"] == FOREIGN
    assert "x-api-key" in answer.headers["access-control-allow-headers"].lower()
    other = listed.client.options(
        "/api/datasets", headers={**preflight, "Origin": "http://evil.example"}
    )
    assert "access-control-allow-origin" not in other.headers
    uploaded = _upload(listed.client, touch_arff(tmp_path / "t.arff", n=30), "t", Origin=FOREIGN)
    assert uploaded.status_code == 201
    assert uploaded.headers["access-control-allow-origin"] == FOREIGN
    refused = _upload(listed.client, tmp_path / "t.arff", "u", Origin="http://evil.example")
    _refused(refused, 403, "Forbidden", "headers.Origin")
    assert _names(listed.client) == {"t"}
