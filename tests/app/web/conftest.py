"""A real headless Chromium (Debian's, driven by Playwright) for the web-page tests, the
services they drive (real uvicorn on loopback), and helpers to read the page's figures.

Screenshots of every step go to ``test-artifacts/web/<test name>/`` at the repository root
(ignored by git), replaced on each run.
"""

from __future__ import annotations

import base64
import functools
import os
import re
import shutil
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Browser, Page, sync_playwright

from tests.app.api.conftest import (  # noqa: F401 (fixtures of the real service)
    ROOT,
    make_server,
    make_sqlite_server,
    server,
)
from tests.app.test_plots import svg_texts

ARTIFACTS = ROOT / "test-artifacts" / "web"
#: Debian's Chromium (scripts/install.sh installs it); TOUCHBENCH_CHROMIUM overrides.
CHROMIUM = Path(os.environ.get("TOUCHBENCH_CHROMIUM", "/usr/bin/chromium"))
DATA_SVG = re.compile(r"^data:image/svg\+xml;base64,(.+)$")


@dataclass
class Tab:
    """A browser tab, the folder of its screenshots and what went wrong in it."""

    page: Page
    folder: Path
    page_errors: list[str] = field(default_factory=list)
    policy_violations: list[str] = field(default_factory=list)
    shots: list[Path] = field(default_factory=list)

    def shot(self, name: str) -> Path:
        """A full-page screenshot, numbered in order, once images have loaded."""
        self.page.wait_for_function("[...document.images].every(image => image.complete)")
        path = self.folder / f"{len(self.shots) + 1:02d}-{name}.png"
        self.page.screenshot(path=str(path), full_page=True)
        self.shots.append(path)
        return path


def figure_texts(src: str | None) -> list[str]:
    """The text strings of a figure the page shows as a ``data:`` SVG image."""
    assert src is not None, "the figure has no source"
    match = DATA_SVG.match(src)
    assert match, f"not an SVG data URI: {src[:60]}"
    return svg_texts(base64.b64decode(match.group(1)).decode("utf-8"))


@pytest.fixture(scope="session")
def browser() -> Iterator[Browser]:
    assert CHROMIUM.is_file(), f"no Chromium at {CHROMIUM}: run scripts/install.sh"
    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=str(CHROMIUM), headless=True)
        yield launched
        launched.close()


@pytest.fixture
def tab(browser: Browser, request: pytest.FixtureRequest) -> Iterator[Tab]:
    """A fresh tab (its own session storage) on a laptop-sized screen; the test fails if
    the page threw an error or broke its Content-Security-Policy."""
    folder = ARTIFACTS / request.node.name
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    context = browser.new_context(viewport={"width": 1366, "height": 850})
    context.set_default_timeout(30_000)
    page = context.new_page()
    opened = Tab(page, folder)
    page.on("pageerror", lambda error: opened.page_errors.append(str(error)))
    page.on(
        "console",
        lambda message: (
            opened.policy_violations.append(message.text)
            if "Content Security Policy" in message.text
            else None
        ),
    )
    yield opened
    context.close()
    assert not opened.page_errors, opened.page_errors
    assert not opened.policy_violations, opened.policy_violations


@contextmanager
def static_site(folder: Path) -> Iterator[str]:
    """A second web server on loopback (another port: another origin) serving ``folder``;
    its URL."""

    class Quiet(SimpleHTTPRequestHandler):
        def log_message(self, format: str, *args: Any) -> None:
            pass

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(folder)))
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}"
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join()
