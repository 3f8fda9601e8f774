"""Reading figures and pages as text: an SVG's strings, and any fetch of another origin."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

SVG = "{http://www.w3.org/2000/svg}"
#: What would make a browser fetch something: links, sources, CSS urls and imports.
FETCHES = re.compile(
    r"(href|src)\s*=\s*[\"']?\s*(https?:)?//|url\(\s*[\"']?(https?:)?//|@import", re.I
)


def svg_texts(svg: str) -> list[str]:
    """Every text string of an SVG document, in order (tspans joined per text element)."""
    root = ET.fromstring(svg)
    return ["".join(element.itertext()).strip() for element in root.iter(f"{SVG}text")]
