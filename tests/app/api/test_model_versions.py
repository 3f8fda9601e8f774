"""Versions and aliases on a real service: a live WebSocket session on ``NAME@champion``
switches to the version promoted mid-stream without dropping the stream, refuses one that
extracts its features otherwise, and each answer names its version; the alias routes need a
write key."""

from __future__ import annotations

import contextlib
import json
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest
from websockets.sync.client import ClientConnection, connect

from tests.support.live import as_int16
from tests.support.recordings import extract_sessions
from tests.support.service import Server
from tests.support.synthetic import touch_arff
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.services.datasets import import_file
from touchbench.app.services.models import train
from touchbench.app.services.simulation import SAMPLERATE, write_session
from touchbench.app.store.database import Store

WRITE = "lab-write-key-0123456789"
PREDICT = "robot-predict-key-0123456789"


def _versions(store_url: str, tmp_path: Path) -> list[tuple[float, float, str, str]]:
    """``mic`` versions 1 and 2 on extracted sessions, 3 on an imported file (no recipe);
    the touches of ``unseen.wav``, a session none of them saw."""
    store = Store(store_url)
    try:
        extract_sessions(store, tmp_path, sessions=2, touches=6)
        for classifier in ("cc:j48", "cc:nb"):
            train(store, TrainRequest(dataset="touch", classifier=classifier, name="mic"))
        flat = touch_arff(tmp_path / "flat.arff", n=40)
        import_file(store, ImportRequest(file=flat, name="flat"))
        train(store, TrainRequest(dataset="flat", classifier="nb", target="gesture", name="mic"))
    finally:
        store.dispose()
    _, touches = write_session(tmp_path, "unseen", n_touches=5, seed=99)
    return touches


@pytest.fixture(scope="module")
def prepared(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[Any]]:
    """A store holding :func:`_versions`' models, made once for the tests that copy it,
    and the unseen session's touches (``unseen.wav`` beside it)."""
    folder = tmp_path_factory.mktemp("versions")
    touches = _versions(f"sqlite:///{folder / 'touchbench.db'}", folder)
    return folder, touches


def _copy_of(prepared: tuple[Path, list[Any]], tmp_path: Path) -> list[Any]:
    """The prepared store and session in ``tmp_path`` (the store the server there opens);
    the session's touches."""
    folder, touches = prepared
    for name in ("touchbench.db", "unseen.wav"):
        shutil.copy(folder / name, tmp_path / name)
    return touches


def _until(socket: ClientConnection, seen: list[dict[str, Any]], key: str) -> None:
    """Receive messages into ``seen`` until one holds ``key``."""
    while True:
        seen.append(json.loads(socket.recv(timeout=120)))
        if key in seen[-1]:
            return


@contextlib.contextmanager
def _champion_session(
    server: Server,
    samples: np.ndarray,
    rate: int,
    blocks: list[bytes],
    seen: list[dict[str, Any]],
    until: str = "predictions",
) -> Iterator[ClientConnection]:
    """A live session on ``mic@champion`` that has sent ``blocks`` and received messages
    into ``seen`` up to one holding ``until`` (its first prediction; "": none)."""
    url = server.url.replace("http://", "ws://") + "/api/models/mic@champion/live"
    # no keepalive pings: a loaded machine may leave them unanswered for a while
    with connect(
        url, additional_headers={"X-API-Key": PREDICT}, open_timeout=60, ping_interval=None
    ) as socket:
        socket.send(json.dumps({"samplerate": rate, "channels": samples.shape[1]}))
        for block in blocks:
            socket.send(block)
        if until:
            _until(socket, seen, until)
        yield socket


def _finish(
    socket: ClientConnection, blocks: list[bytes], seen: list[dict[str, Any]], until: str = ""
) -> None:
    """Send the last ``blocks`` and the end, receive into ``seen`` (past a message holding
    ``until`` first) until the server closes the stream as ended."""
    for block in blocks:
        socket.send(block)
    socket.send(json.dumps({"end": True}))
    if until:
        _until(socket, seen, until)
    try:
        while True:
            seen.append(json.loads(socket.recv(timeout=120)))
    except Exception:  # closed: the stream ended
        pass
    assert (socket.close_code, socket.close_reason) == (1000, "stream ended")


def test_a_live_session_follows_the_champion_mid_stream(
    make_sqlite_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_sqlite_server(
        api_keys=f"lab:write:{WRITE},robot:predict:{PREDICT}", live_follow_seconds="0"
    )
    touches = _versions(server.database_url, tmp_path)
    lab = httpx.Client(base_url=server.url, headers={"X-API-Key": WRITE}, timeout=60)
    robot = httpx.Client(base_url=server.url, headers={"X-API-Key": PREDICT}, timeout=60)
    refused = robot.post("/api/models/mic@1/promote")
    assert refused.status_code == 403 and "needs a write key" in refused.text
    assert lab.post("/api/models/mic@1/promote").json()["model"] == "mic@1"

    samples, rate = as_int16(tmp_path / "unseen.wav")
    assert rate == SAMPLERATE
    frames = 2048
    # each part ends as a touch begins: the one before it is over and answered
    cuts = [int(touches[1][0] * rate), int(touches[3][0] * rate), len(samples)]
    parts, start = [], 0
    for cut in cuts:
        part = samples[start:cut]
        parts.append([part[i : i + frames].tobytes() for i in range(0, len(part), frames)])
        start = cut
    seen: list[dict[str, Any]] = []
    with _champion_session(server, samples, rate, parts[0], seen) as socket:
        # the first touch, by version 1
        moved = lab.post("/api/models/mic@2/promote")
        assert moved.json() == {"alias": "champion", "model": "mic@2", "version": 2, "previous": 1}
        for block in parts[1]:
            socket.send(block)
        _until(socket, seen, "switched")
        lab.post("/api/models/mic@3/promote").raise_for_status()  # no recipe: not taken
        _finish(socket, parts[2], seen, until="warning")

    answers = [m["model"] for m in seen if "predictions" in m]
    assert len(answers) == 5  # every touch of the stream, none dropped by the switch
    first = answers.count("mic@1")
    assert first >= 1 and answers == ["mic@1"] * first + ["mic@2"] * (5 - first)
    assert 5 - first >= 1
    switched = [m for m in seen if "switched" in m]
    assert switched == [{"switched": "mic@2", "from": "mic@1"}]
    assert seen.index(switched[0]) == first  # said before the first answer of version 2
    warnings = [m["warning"] for m in seen if "warning" in m]
    assert len(warnings) == 1 and "'mic@3' extracts its features otherwise" in warnings[0]

    back = lab.post("/api/models/mic/rollback")
    assert back.json() == {"alias": "champion", "model": "mic@2", "version": 2, "previous": 3}
    listed = {m["version"]: m["aliases"] for m in lab.get("/api/models").json()["models"]}
    assert listed == {1: [], 2: ["champion"], 3: []}
    again = lab.post("/api/models/mic/rollback")
    assert again.json()["model"] == "mic@1"
    bad = lab.post("/api/models/mic@1/aliases", json={"alias": "2"})
    assert bad.status_code == 422 and bad.json()["error"]["where"] == "body.alias"
    features = robot.get("/api/models/mic@champion").json()["features"]
    instance = dict.fromkeys(features, 0.0)
    predicted = robot.post("/api/models/mic@champion/predict", json={"instances": [instance]})
    assert predicted.status_code == 200 and predicted.json()["model"] == "mic@1"
    lab.close()
    robot.close()


def test_deleting_the_alias_a_live_session_follows_keeps_its_version(
    make_sqlite_server: Callable[..., Server],
    tmp_path: Path,
    prepared: tuple[Path, list[Any]],
) -> None:
    """``DELETE /api/models/NAME/aliases/ALIAS`` needs a write key, says 404 for a missing
    alias and 409 for a version it no longer points at; a session on ``NAME@champion``
    keeps answering with its version and says so once."""
    touches = _copy_of(prepared, tmp_path)
    server = make_sqlite_server(
        api_keys=f"lab:write:{WRITE},robot:predict:{PREDICT}", live_follow_seconds="0"
    )
    lab = httpx.Client(base_url=server.url, headers={"X-API-Key": WRITE}, timeout=60)
    robot = httpx.Client(base_url=server.url, headers={"X-API-Key": PREDICT}, timeout=60)
    lab.post("/api/models/mic@1/promote").raise_for_status()

    samples, rate = as_int16(tmp_path / "unseen.wav")
    frames, cut = 2048, int(touches[2][0] * rate)
    parts = [samples[:cut], samples[cut:]]
    blocks = [[p[i : i + frames].tobytes() for i in range(0, len(p), frames)] for p in parts]
    seen: list[dict[str, Any]] = []
    with _champion_session(server, samples, rate, blocks[0], seen) as socket:
        refused = robot.delete("/api/models/mic/aliases/champion")
        assert refused.status_code == 403 and "needs a write key" in refused.text
        stale = lab.delete("/api/models/mic@2/aliases/champion")
        assert stale.status_code == 409 and "points at version 1, not 2" in stale.text
        gone = lab.delete("/api/models/mic/aliases/champion")
        assert gone.status_code == 200, gone.text
        assert gone.json() == {"alias": "champion", "model": "mic@1", "version": 1}
        _finish(socket, blocks[1], seen)

    answers = [m["model"] for m in seen if "predictions" in m]
    assert answers == ["mic@1"] * 5  # every touch, by the version the session held
    warnings = [m["warning"] for m in seen if "warning" in m]
    assert len(warnings) == 1 and "has no alias 'champion'" in warnings[0]
    assert "the session keeps its model" in warnings[0]
    missing = lab.delete("/api/models/mic/aliases/champion")
    assert missing.status_code == 404 and "has no alias 'champion'" in missing.text
    assert lab.delete("/api/models/mic/aliases/latest").status_code == 422
    new_session = robot.get("/api/models/mic@champion")
    assert new_session.status_code == 404


def test_a_flood_of_alias_moves_drops_no_stream_and_no_request(
    make_sqlite_server: Callable[..., Server],
    tmp_path: Path,
    prepared: tuple[Path, list[Any]],
) -> None:
    """Promote, rollback and alias in a loop while a session on ``mic@champion`` streams
    (following checked at every block): every touch is answered, by a version the alias
    named; no request fails with a 5xx; the session switches at most once per block.

    The flood starts once the session has answered its first touch: a session that opens
    while the flood has the alias on ``mic@3`` (no recipe) is refused, rightly, and the
    session's start (the feature stack imported in a worker thread) may take a while."""
    import threading

    touches = _copy_of(prepared, tmp_path)
    server = make_sqlite_server(
        api_keys=f"lab:write:{WRITE},robot:predict:{PREDICT}", live_follow_seconds="0"
    )
    lab = httpx.Client(base_url=server.url, headers={"X-API-Key": WRITE}, timeout=60)
    lab.post("/api/models/mic@1/promote").raise_for_status()
    statuses: list[int] = []
    stop = threading.Event()

    def flood() -> None:
        moves = [
            ("/api/models/mic@2/promote", None),
            ("/api/models/mic/rollback", None),
            ("/api/models/mic@3/aliases", {"alias": "champion"}),  # not taken: no recipe
            ("/api/models/mic@1/promote", None),
        ]
        while not stop.is_set():
            for path, body in moves:
                statuses.append(lab.post(path, json=body).status_code)

    samples, rate = as_int16(tmp_path / "unseen.wav")
    frames, cut = 2048, int(touches[1][0] * rate)  # the first touch whole, then the flood
    parts = [samples[:cut], samples[cut:]]
    first, rest = ([p[i : i + frames].tobytes() for i in range(0, len(p), frames)] for p in parts)
    blocks = [*first, *rest]
    seen: list[dict[str, Any]] = []
    flooding = threading.Thread(target=flood)
    with _champion_session(server, samples, rate, first, seen) as socket:
        flooding.start()
        try:
            _finish(socket, rest, seen)
        finally:
            stop.set()
            flooding.join()
    answers = [m["model"] for m in seen if "predictions" in m]
    switches = [m for m in seen if "switched" in m]
    warnings = [m for m in seen if "warning" in m]
    print(
        f"{len(statuses)} alias requests ({sorted(set(statuses))}) during {len(blocks)} "
        f"blocks: {len(answers)} answers, {len(switches)} switches, {len(warnings)} warnings"
    )
    assert statuses and all(status < 500 for status in statuses)
    assert set(statuses) <= {200, 409}  # a rollback with nothing to go back to: 409
    assert len(answers) == 5 and set(answers) <= {"mic@1", "mic@2"}
    assert len(switches) + len(warnings) <= len(blocks)
    assert lab.get("/healthz").status_code == 200


def test_concurrent_alias_changes_answer_409_never_500(
    make_server: Callable[..., Server], store_url: str
) -> None:
    """Issue 36 item 6: set, move, roll back and delete one alias from four clients at once,
    on SQLite and PostgreSQL: each change answers 200, or 404/409 when another one changed
    the alias first; never a 500; and the alias points at one existing version after."""
    import threading
    from concurrent.futures import ThreadPoolExecutor

    from touchbench.app.store.models import save_model

    store = Store(store_url)
    try:
        for _ in range(3):
            save_model(
                store, classifier="nb", params={}, schema={}, targets=["g"], artifact=b"m",
                name="mic",
            )  # fmt: skip
    finally:
        store.dispose()
    server = make_server()
    changes = [
        ("POST", "/api/models/mic@1/aliases", {"alias": "champion"}),
        ("DELETE", "/api/models/mic/aliases/champion", None),
        ("POST", "/api/models/mic@2/promote", None),
        ("DELETE", "/api/models/mic@2/aliases/champion", None),
        ("POST", "/api/models/mic/rollback", None),
        ("POST", "/api/models/mic@3/aliases", {"alias": "champion"}),
    ]
    statuses: list[int] = []
    errors: list[str] = []
    start = threading.Barrier(4)

    def client(offset: int) -> None:
        with httpx.Client(base_url=server.url, timeout=120) as http:
            start.wait()
            for i in range(40):
                method, path, body = changes[(offset + i) % len(changes)]
                answer = http.request(method, path, json=body)
                statuses.append(answer.status_code)
                if answer.status_code >= 500:
                    errors.append(f"{method} {path}: {answer.text[:300]}")

    with ThreadPoolExecutor(4) as clients:  # a client's own failure is raised here
        list(clients.map(client, range(4)))
    assert not errors, errors[:3]
    assert len(statuses) == 160 and set(statuses) <= {200, 404, 409}, sorted(set(statuses))
    assert statuses.count(200) >= 20
    listed = server.client.get("/api/models").json()["models"]
    assert sum(m["aliases"].count("champion") for m in listed) <= 1
    champion = server.client.get("/api/models/mic@champion")
    assert champion.status_code in (200, 404), champion.text
