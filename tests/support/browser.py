"""Reading the web page in a real browser: a tab with its screenshots, and a figure's texts."""

from __future__ import annotations

import base64
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from playwright.sync_api import Page

from tests.support.figures import svg_texts
from tests.support.service import ROOT

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
