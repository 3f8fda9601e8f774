"""A page from another origin, in a real headless Chromium, tries what the issue found open on
a keyless service: a multipart upload, a body-less ``POST /api/runs/N/resume`` and the live
WebSocket.  The service refuses all three and its store does not change; the same page from
a listed origin gets through (so the page's attempts are real); the dashboard on the
service's own origin keeps working."""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Iterator
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Response, expect

from tests.support.browser import Tab
from tests.support.service import Server, cancelled_run
from tests.support.synthetic import touch_arff

#: The attacker's page: it sends what a browser sends without asking (no-cors requests and
#: a WebSocket handshake) and says how each went.
ATTACK = """<!doctype html>
<html><head><meta charset="utf-8"><title>a page on another site</title></head><body>
<script>
async function attack(service, run) {
  const outcome = {};
  const form = new FormData();
  form.append("file", await (await fetch("stolen.arff")).blob(), "stolen.arff");
  form.append("name", "stolen");
  try {
    await fetch(service + "/api/datasets", {method: "POST", body: form, mode: "no-cors"});
    outcome.upload = "sent";
  } catch (error) { outcome.upload = String(error); }
  try {
    await fetch(service + "/api/runs/" + run + "/resume", {method: "POST", mode: "no-cors"});
    outcome.resume = "sent";
  } catch (error) { outcome.resume = String(error); }
  outcome.socket = await new Promise((resolve) => {
    const socket = new WebSocket(service.replace("http://", "ws://") + "/api/models/nope/live");
    socket.onopen = () => { socket.close(); resolve("open"); };
    socket.onerror = () => resolve("refused");
  });
  return outcome;
}
</script></body></html>
"""


@pytest.fixture
def foreign_site(tmp_path: Path) -> Iterator[str]:
    """A second web server on loopback (another port: another origin) serving the page."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "attack.html").write_text(ATTACK)
    touch_arff(site / "stolen.arff", n=30, seed=9)

    class Quiet(SimpleHTTPRequestHandler):
        def log_message(self, format: str, *args: Any) -> None:
            pass

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(site)))
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}"
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join()


def _attack(
    tab: Tab, site: str, service: str, run_id: int
) -> tuple[dict[str, str], dict[str, int]]:
    """The page's outcome, and the status the service answered each request with (as the
    browser's network layer saw it: the page itself cannot read no-cors answers)."""
    statuses: dict[str, int] = {}

    def seen(response: Response) -> None:
        if response.url.startswith(service) and response.request.method == "POST":
            statuses[response.url.removeprefix(service)] = response.status

    tab.page.on("response", seen)
    tab.page.goto(f"{site}/attack.html")
    outcome: dict[str, str] = tab.page.evaluate("([s, r]) => attack(s, r)", [service, run_id])
    tab.page.remove_listener("response", seen)
    return outcome, statuses


def _names(server: Server) -> set[str]:
    return {row["name"] for row in server.client.get("/api/datasets").json()["datasets"]}


def test_a_page_on_another_origin_cannot_change_the_store(
    capsys: pytest.CaptureFixture[str],
    make_sqlite_server: Callable[..., Server],
    foreign_site: str,
    tab: Tab,
    tmp_path: Path,
) -> None:
    server = make_sqlite_server()  # no key: any page could write before
    run_id = cancelled_run(capsys, server, tmp_path)
    resume = f"/api/runs/{run_id}/resume"

    outcome, statuses = _attack(tab, foreign_site, server.url, run_id)
    assert outcome == {"upload": "sent", "resume": "sent", "socket": "refused"}
    assert statuses == {"/api/datasets": 403, resume: 403}
    assert _names(server) == {"touch"}
    assert server.client.get(f"/api/runs/{run_id}").json()["status"] == "cancelled"

    # the dashboard on the service's own origin still uploads
    page = tab.page
    page.goto(server.url + "/")
    form = page.locator("#upload")
    form.locator("input[name=file]").set_input_files(str(touch_arff(tmp_path / "mine.arff", n=45)))
    form.locator("input[name=name]").fill("mine")
    form.locator("button[type=submit]").click()
    expect(form.locator(".outcome")).to_contain_text("Imported 'mine'")
    expect(page.locator("#datasets-list")).to_contain_text("mine")
    tab.shot("own-origin-upload")
    assert _names(server) == {"touch", "mine"}

    # the same page from an origin the service lists gets through: its attempts are real
    server.stop()
    listed = make_sqlite_server(allowed_origins=foreign_site)
    outcome, statuses = _attack(tab, foreign_site, listed.url, run_id)
    assert outcome == {"upload": "sent", "resume": "sent", "socket": "open"}
    assert statuses == {"/api/datasets": 201, resume: 202}
    assert _names(listed) == {"touch", "mine", "stolen"}
    assert listed.client.get(f"/api/runs/{run_id}").json()["status"] != "cancelled"
