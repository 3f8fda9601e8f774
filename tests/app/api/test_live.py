"""``WS /api/models/{id}/live`` on a real server: a stream of PCM blocks in, one message per
touch out (what ``touchbench live --json`` prints); bad streams closed with a reason."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import soundfile

from tests.support.cli_runner import run_cli
from tests.support.live import as_int16, pcm_blocks, stream, ws_url
from tests.support.recordings import extract_sessions
from tests.support.service import Server
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.services.models import train
from touchbench.app.services.simulation import write_session
from touchbench.app.store.database import Store


@pytest.fixture
def live_model(tmp_path: Path, sqlite_store_url: str) -> tuple[str, Path]:
    """A model trained on extracted sessions, and a session it never saw."""
    store = Store(sqlite_store_url)
    try:
        extract_sessions(store, tmp_path, sessions=3, touches=8)
        model = train(store, TrainRequest(dataset="touch", classifier="cc:j48"))
    finally:
        store.dispose()
    unseen, _ = write_session(tmp_path, "unseen", n_touches=5, seed=99)
    return model.name, unseen


def test_live_over_a_websocket_says_what_live_says(
    capsys: pytest.CaptureFixture[str],
    make_sqlite_server: Callable[..., Server],
    live_model: tuple[str, Path],
    tmp_path: Path,
) -> None:
    name, unseen = live_model
    server = make_sqlite_server(api_key="live-key-of-the-lab")
    rate, channels, blocks = pcm_blocks(unseen)
    messages, code, reason = stream(
        ws_url(server, name),
        {"samplerate": rate, "channels": channels, "format": "S16LE"},
        blocks,
        headers={"X-API-Key": "live-key-of-the-lab"},
    )
    assert (code, reason) == (1000, "stream ended")
    # the CLI on the same samples (as 16-bit PCM, as the socket received them)
    as_sent = tmp_path / "as-sent.wav"
    soundfile.write(as_sent, as_int16(unseen)[0], rate, subtype="PCM_16")
    cli = run_cli(
        capsys, server.database_url, "live", "--model", name, "--replay", str(as_sent), "--json"
    )
    assert cli.code == 0, cli.err
    expected = [json.loads(line) for line in cli.out.splitlines() if line.strip()]
    assert len(messages) == len(expected) == 5

    def comparable(touch: dict[str, Any]) -> tuple[Any, ...]:
        return (
            round(touch["start"], 4),
            round(touch["end"], 4),
            {t: p["value"] for t, p in touch["predictions"].items()},
        )

    assert [comparable(m) for m in messages] == [comparable(e) for e in expected]
    assert all(m["latency_ms"] >= 0 for m in messages)


def test_bad_streams_are_closed_with_a_reason(
    make_sqlite_server: Callable[..., Server], live_model: tuple[str, Path]
) -> None:
    name, _ = live_model
    server = make_sqlite_server(api_key="live-key-of-the-lab")
    url = ws_url(server, name)
    key = {"X-API-Key": "live-key-of-the-lab"}
    good = {"samplerate": 44100, "channels": 3, "format": "S16LE"}
    cases: list[tuple[dict[str, Any], list[bytes], dict[str, str], int, str]] = [
        (good, [], {}, 1008, "API key"),
        ({**good, "api_key": "wrong"}, [], {}, 1008, "wrong API key"),
        ({**good, "api_key": "live-key-of-the-lab", "channels": 2}, [], {}, 1008, "3-channel"),
        ({**good, "samplerate": "fast"}, [], key, 1007, "samplerate"),
        ({**good, "format": "MP3"}, [], key, 1007, "format"),
        (good, [b"\x00" * 7], key, 1007, "frames"),
    ]
    for header, blocks, headers, code, words in cases:
        _, got_code, reason = stream(url, header, blocks, headers)
        assert got_code == code and words in reason, (header, got_code, reason)
    _, code, reason = stream(
        server.url.replace("http://", "ws://") + "/api/models/nope/live", good, [], key
    )
    assert code == 1008 and "no model 'nope'" in reason
    assert server.client.get("/healthz").status_code == 200  # the server is still up
