"""The live view in a real headless Chromium against a real ``touchbench serve`` behind an API
key: a simulated take uploaded from the page and replayed, every touch marked with the labels
the model gives it; the champion moved mid-stream, the switch shown and the next touches
answered by the new version; a page on another origin cannot open the stream nor upload a
take.  One service for the module, two versions of a tiny model (J48) trained on two short
simulated sessions."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Page, expect
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from tests.support.browser import ARTIFACTS, Tab, static_site
from tests.support.service import Server, servers
from touchbench.app.schemas.extraction import ExtractRequest
from touchbench.app.schemas.models import AliasRequest, TrainRequest
from touchbench.app.services.live import open_live
from touchbench.app.services.models import move_alias, train
from touchbench.app.services.simulation import write_contact_mic_sessions, write_session
from touchbench.app.store.database import Store
from touchbench.drivers.replay import FileReplaySource

KEY = "live-view-key-of-the-lab"
MODEL = "touch"
#: The take replayed: touches the model never saw.
TAKE_TOUCHES, TAKE_SEED = 4, 99
#: A stream ends within seconds; the first one also pays for the service's imports.
STREAM_TIMEOUT = 60_000
#: Touches of the simulated take the champion moves in (about 9 s at twice real time).
SWITCH_TOUCHES = 8


@pytest.fixture(scope="module")
def live_service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Server, Path]]:
    """A service with ``touch@1`` (J48, champion) and ``touch@2`` (ZeroR) trained on the
    same extraction, reading the store again before every block; and a take to replay."""
    folder = tmp_path_factory.mktemp("live-view")
    url = f"sqlite:///{folder / 'touchbench.db'}"
    store = Store(url)
    try:
        recordings, labels = write_contact_mic_sessions(folder / "sessions", trials=2, n_touches=8)
        extract_and_store(store, recordings, labels)
        train(store, TrainRequest(dataset="touch", classifier="cc:j48", name=MODEL))
        train(store, TrainRequest(dataset="touch", classifier="cc:zeror", name=MODEL))
        move_alias(store, AliasRequest(model=f"{MODEL}@1"))
    finally:
        store.dispose()
    take, _ = write_session(folder, "take", n_touches=TAKE_TOUCHES, seed=TAKE_SEED)
    builds = servers(url, folder)
    build = next(builds)
    yield build(api_key=KEY, live_follow_seconds="0"), take
    next(builds, None)


def extract_and_store(store: Store, recordings: list[Path], labels: Path) -> None:
    from touchbench.app.services.extraction import extract_and_store as extract

    extract(store, ExtractRequest(recordings=recordings, labels=labels, name="touch"))


def expected_touches(server: Server, take: Path, model: str) -> list[dict[str, Any]]:
    """What the model says of each touch of the take, from the service's own live session
    fed in this process (not through the page)."""
    store = Store(server.database_url)
    try:
        with FileReplaySource(take, block_length=4096) as source:
            session = open_live(
                store, model, samplerate=source.samplerate, n_channels=source.n_channels
            )
            found = []
            for block in source.blocks():
                found += session.feed(block.samples, block.time)
            found += session.finish()
    finally:
        store.dispose()
    return [touch.to_json() for touch in found]


def open_view(tab: Tab, server: Server, model: str) -> Page:
    """The live view at a projector's size, the key entered at the top, the model named."""
    page = tab.page
    page.set_viewport_size({"width": 1280, "height": 720})
    page.goto(server.url + "/live")
    page.get_by_label("API key").fill(KEY)
    page.get_by_role("button", name="Use").click()
    expect(page.locator("#api-key-state")).to_have_text("key in use (this tab)")
    page.get_by_label("Model", exact=True).fill(model)
    return page


def marks(page: Page) -> list[dict[str, Any]]:
    """The touches the page marked, oldest first."""
    rows = page.locator("#live-touches tbody tr.touch")
    found = []
    for i in reversed(range(rows.count())):
        row = rows.nth(i)
        found.append(
            {
                "start": float(row.get_attribute("data-start") or "nan"),
                "end": float(row.get_attribute("data-end") or "nan"),
                "labels": json.loads(row.get_attribute("data-labels") or "{}"),
                "model": row.get_attribute("data-model"),
                "text": row.inner_text(),
            }
        )
    return found


def test_a_replayed_take_has_every_touch_marked_with_its_labels(
    live_service: tuple[Server, Path], tab: Tab
) -> None:
    server, take = live_service
    expected = expected_touches(server, take, f"{MODEL}@1")
    assert len(expected) == TAKE_TOUCHES  # the model's detector finds every touch of the take

    page = open_view(tab, server, f"{MODEL}@1")
    page.get_by_label("Recording (replay)").check()
    expect(page.get_by_label("Touches")).to_be_hidden()
    page.get_by_label("Upload a recording").set_input_files(str(take))
    expect(page.locator("#live-status")).to_contain_text("Uploaded take.wav")
    expect(page.locator("#live-replay")).to_contain_text("take.wav")
    page.get_by_label("Speed").select_option("4")
    page.get_by_role("button", name="Start").click()
    expect(page.locator("#live-source")).to_contain_text(
        "touch@1 on take.wav", timeout=STREAM_TIMEOUT
    )
    expect(page.locator("#live-touches tbody tr.touch").first).to_be_visible(timeout=STREAM_TIMEOUT)
    tab.shot("first-touch")
    expect(page.locator("#live-touches")).to_have_attribute(
        "data-state", "ended", timeout=STREAM_TIMEOUT
    )
    expect(page.locator("#live-status")).to_have_text(
        f"The source ended: {TAKE_TOUCHES} touches marked."
    )

    shown = marks(page)
    assert len(shown) == len(expected)
    for mark, touch in zip(shown, expected, strict=True):
        assert abs(mark["start"] - touch["start"]) < 1e-3
        assert abs(mark["end"] - touch["end"]) < 1e-3
        labels = {target: p["value"] for target, p in touch["predictions"].items()}
        assert mark["labels"] == labels
        assert mark["model"] == f"{MODEL}@1"
        for target, value in labels.items():
            assert f"{target}: {value}" in mark["text"]
    delays = page.locator("#live-touches tbody tr.touch").evaluate_all(
        "rows => rows.map(row => row.dataset.delayMs)"
    )
    assert all(delay is not None and float(delay) > 0 for delay in delays), delays
    # the last touch, large, with its probabilities
    last = page.locator("#live-last")
    expect(last).to_contain_text(f"Touch {TAKE_TOUCHES} at")
    for target, prediction in expected[-1]["predictions"].items():
        expect(last).to_contain_text(target)
        expect(last).to_contain_text(str(prediction["value"]))

    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "live.png"))
    tab.shot("ended")


def test_the_champion_moved_mid_stream_shows_the_switch(
    live_service: tuple[Server, Path], tab: Tab
) -> None:
    server, _ = live_service
    page = open_view(tab, server, f"{MODEL}@champion")
    expect(page.locator("#live-replay")).to_be_hidden()
    page.get_by_label("Touches").fill(str(SWITCH_TOUCHES))
    page.get_by_label("Seed").fill("7")
    page.get_by_label("Speed").select_option("2")
    page.get_by_role("button", name="Start").click()
    expect(page.locator("#live-touches tbody tr.touch").first).to_be_visible(timeout=STREAM_TIMEOUT)
    moved = server.client.post(f"/api/models/{MODEL}@2/promote")
    assert moved.status_code == 200, moved.text

    switch = page.locator("#live-switch")
    expect(switch).to_be_visible(timeout=STREAM_TIMEOUT)
    expect(switch).to_contain_text(f"{MODEL}@1 → {MODEL}@2")
    tab.shot("switched")
    expect(page.locator("#live-touches")).to_have_attribute(
        "data-state", "ended", timeout=STREAM_TIMEOUT
    )
    models = [mark["model"] for mark in marks(page)]
    assert len(models) == SWITCH_TOUCHES
    first_new = models.index(f"{MODEL}@2")  # some touch after the move came from the new one
    assert models[:first_new] == [f"{MODEL}@1"] * first_new and first_new >= 1
    assert models[first_new:] == [f"{MODEL}@2"] * (len(models) - first_new)
    # the switch sits in the table between the last touch of the old version and the first
    # of the new one (newest first)
    rows = page.locator("#live-touches tbody tr")
    texts = [rows.nth(i).inner_text() for i in range(rows.count())]
    at = next(i for i, text in enumerate(texts) if text.startswith("switched"))
    assert f"{MODEL}@2" in texts[at - 1] and f"{MODEL}@1" in texts[at + 1]
    server.client.post(f"/api/models/{MODEL}@1/promote").raise_for_status()


def test_the_keyboard_starts_and_stops_a_session(
    live_service: tuple[Server, Path], tab: Tab
) -> None:
    server, _ = live_service
    page = open_view(tab, server, f"{MODEL}@1")
    page.get_by_label("Touches").fill("100")  # minutes of real time: stopped long before
    page.get_by_label("Seed").focus()
    page.keyboard.press("Enter")  # submits the form
    stop = page.get_by_role("button", name="Stop")
    expect(stop).to_be_enabled(timeout=STREAM_TIMEOUT)
    expect(page.locator("#live-touches")).to_have_attribute(
        "data-state", "running", timeout=STREAM_TIMEOUT
    )
    stop.focus()
    page.keyboard.press("Enter")
    expect(page.locator("#live-touches")).to_have_attribute(
        "data-state", "ended", timeout=STREAM_TIMEOUT
    )
    expect(page.locator("#live-status")).to_contain_text("Stopped: ")
    expect(page.get_by_role("button", name="Start")).to_be_enabled()


#: A page of another site: it tries to open the live view's stream and to upload a take.
ATTACK = """<!doctype html>
<html><head><meta charset="utf-8"><title>another site</title></head><body>
<script>
async function attack(service, key) {
  const outcome = {};
  const form = new FormData();
  form.append("recording", new Blob(["not audio"]), "take.wav");
  try {
    await fetch(service + "/api/live/recordings", {method: "POST", body: form, mode: "no-cors"});
    outcome.upload = "sent";
  } catch (error) { outcome.upload = String(error); }
  outcome.socket = await new Promise((resolve) => {
    const url = service.replace("http://", "ws://") + "/api/models/touch%40champion/live";
    const socket = new WebSocket(url);
    socket.onopen = () => socket.send(JSON.stringify(
      {api_key: key, source: {kind: "simulated", touches: 2}}));
    socket.onmessage = () => { socket.close(); resolve("streamed"); };
    socket.onerror = () => resolve("refused");
  });
  return outcome;
}
</script></body></html>
"""


@pytest.fixture
def foreign_site(tmp_path: Path) -> Iterator[str]:
    """Another origin (a second web server on loopback) serving the page."""
    (tmp_path / "attack.html").write_text(ATTACK)
    with static_site(tmp_path) as url:
        yield url


def test_a_page_on_another_origin_cannot_open_the_stream(
    live_service: tuple[Server, Path], foreign_site: str, tab: Tab
) -> None:
    server, _ = live_service
    before = server.client.get("/api/live/recordings").json()["replays"]
    statuses: dict[str, int] = {}
    tab.page.on(
        "response",
        lambda response: (
            statuses.__setitem__(response.url, response.status)
            if response.url.startswith(server.url)
            else None
        ),
    )
    tab.page.goto(f"{foreign_site}/attack.html")
    # even a page that holds the key (stolen) is refused for its origin
    outcome = tab.page.evaluate("([s, k]) => attack(s, k)", [server.url, KEY])
    assert outcome == {"upload": "sent", "socket": "refused"}
    assert statuses == {f"{server.url}/api/live/recordings": 403}
    assert server.client.get("/api/live/recordings").json()["replays"] == before


def _refusal(server: Server, model: str, header: dict[str, Any]) -> tuple[int, str]:
    """The close code and reason of a live session opened with ``header``."""
    address = server.url.replace("http://", "ws://") + f"/api/models/{model}/live"
    with connect(address, additional_headers={"X-API-Key": KEY}, open_timeout=60) as socket:
        socket.send(json.dumps(header))
        try:
            while True:
                socket.recv(timeout=60)
        except ConnectionClosed:
            pass
        assert socket.close_code is not None
        return socket.close_code, socket.close_reason or ""


def test_sources_the_service_cannot_read_are_refused_in_one_line(
    live_service: tuple[Server, Path], tmp_path: Path
) -> None:
    server, _ = live_service
    not_audio = tmp_path / "notes.wav"
    not_audio.write_text("not a recording")
    answer = server.client.post(
        "/api/live/recordings", files={"recording": ("notes.wav", not_audio.read_bytes())}
    )
    assert answer.status_code == 400, answer.text
    message = answer.json()["error"]["message"]
    assert message.startswith("notes.wav: ") and str(server.work_dir) not in message
    kept = server.client.get("/api/live/recordings").json()["replays"]
    assert all(replay["name"] != "notes.wav" for replay in kept)
    assert len(list((server.work_dir / "live-replays").iterdir())) == len(kept)  # nothing left

    model = f"{MODEL}@1"
    cases: list[tuple[dict[str, Any], int, str]] = [
        ({"source": {"kind": "camera"}}, 1007, "source.kind"),
        ({"source": {"kind": "simulated", "speed": 100}}, 1007, "source.speed"),
        ({"source": {"kind": "replay"}}, 1007, "needs the id of an uploaded recording"),
        ({"source": {"kind": "replay", "replay": "0" * 32}}, 1008, "no uploaded recording"),
        ({"source": {"kind": "simulated", "touches": 1000}}, 1008, "LIVE_SOURCE_SECONDS"),
    ]
    for header, code, words in cases:
        got, reason = _refusal(server, model, header)
        assert got == code and words in reason, (header, got, reason)
    # without the key in the header or the handshake: refused before the source is read
    address = server.url.replace("http://", "ws://") + f"/api/models/{model}/live"
    with connect(address, open_timeout=60) as socket:
        socket.send(json.dumps({"source": {"kind": "simulated", "touches": 1}}))
        with pytest.raises(ConnectionClosed):
            socket.recv(timeout=60)
        assert socket.close_code == 1008 and "API key" in (socket.close_reason or "")
