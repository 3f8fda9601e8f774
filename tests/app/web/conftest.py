"""A real headless Chromium (Debian's, driven by Playwright) for the web-page tests, the
services they drive (real uvicorn on loopback), and helpers to read the page's figures.

Screenshots of every step go to ``test-artifacts/web/<test name>/`` at the repository root
(ignored by git), replaced on each run.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator

import pytest
from playwright.sync_api import Browser, sync_playwright

from tests.support.browser import ARTIFACTS, CHROMIUM, Tab


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    """Chromium for the module's tests. Not for the session: Playwright's sync API keeps an
    event loop running in the main thread while it is open, and a later module's test that
    calls ``asyncio.run`` would be refused."""
    assert CHROMIUM.is_file(), f"no Chromium at {CHROMIUM}: run scripts/install.sh"
    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=str(CHROMIUM), headless=True)
        yield launched
        launched.close()


#: A projector's screen: every new page is shown readable at this size (docs/web.md).
PROJECTOR = {"width": 1280, "height": 720}


@pytest.fixture
def tab(browser: Browser, request: pytest.FixtureRequest) -> Iterator[Tab]:
    """A fresh tab (its own session storage) on a laptop-sized screen; the test fails if
    the page threw an error or broke its Content-Security-Policy."""
    yield from _tab(browser, request, {"width": 1366, "height": 850})


@pytest.fixture
def projector_tab(browser: Browser, request: pytest.FixtureRequest) -> Iterator[Tab]:
    """A fresh tab on a projector's 1280x720 screen (:data:`PROJECTOR`)."""
    yield from _tab(browser, request, PROJECTOR)


def _tab(
    browser: Browser, request: pytest.FixtureRequest, viewport: dict[str, int]
) -> Iterator[Tab]:
    folder = ARTIFACTS / request.node.name
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    context = browser.new_context(viewport=viewport)  # type: ignore[arg-type]
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
