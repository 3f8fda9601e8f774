"""How the web page answers: templates rendered with the report's Jinja environment
(autoescaped), security headers on every page and fragment, and figures as ``data:`` images.

Figures are matplotlib SVG, whose elements carry ``style`` attributes; inline in the page
they would need ``style-src 'unsafe-inline'``.  As ``<img src="data:image/svg+xml;...">``
they are documents of their own, drawn whatever the page's policy, so the policy stays
strict: nothing inline, nothing from another origin.
"""

from __future__ import annotations

# Imports inside functions: start-up time: the report templates and matplotlib load when a
# page first needs them.
import base64
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import quote, urlencode

from fastapi.responses import HTMLResponse

from touchbench.app.errors import AppError
from touchbench.benchmark.errors import BenchmarkError

if TYPE_CHECKING:  # Jinja, matplotlib and the statistics load with the first page, not at start
    from jinja2 import Environment
    from markupsafe import Markup
    from matplotlib.figure import Figure

TEMPLATES = Path(__file__).with_name("templates")
STATIC = Path(__file__).with_name("static")

#: Scripts and styles from this origin only (no inline code, no ``eval``), images from
#: here or ``data:`` (the figures), requests to this origin only, no frames, no plugins.
CONTENT_SECURITY_POLICY = "; ".join(
    (
        "default-src 'none'",
        "script-src 'self'",
        "style-src 'self'",
        "img-src 'self' data:",
        "connect-src 'self'",
        "form-action 'self'",
        "base-uri 'none'",
        "frame-ancestors 'none'",
    )
)
SECURITY_HEADERS = {
    "Content-Security-Policy": CONTENT_SECURITY_POLICY,
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cache-Control": "no-store",
}


@cache
def environment() -> Environment:
    """The report's environment with the web templates searched first, and the filters the
    web templates use."""
    from touchbench.app.reports.html import template_environment

    env = template_environment(TEMPLATES)
    env.filters["segment"] = lambda value: quote(str(value), safe="")
    env.filters["query"] = lambda pairs: urlencode(
        [(k, v) for k, v in pairs.items() if v not in (None, "")]
    )
    env.filters["when"] = lambda moment: moment.strftime("%Y-%m-%d %H:%M:%S") if moment else "-"
    return env


def render(template: str, /, **context: Any) -> HTMLResponse:
    """A template as an HTML answer with the security headers."""
    return HTMLResponse(rendered(template, **context), headers=SECURITY_HEADERS)


def rendered(template: str, /, **context: Any) -> Markup:
    """A template rendered (autoescaped) as markup another template shows as it is."""
    from markupsafe import Markup

    return Markup(environment().get_template(template).render(**context))


@dataclass(frozen=True)
class Plot:
    """A figure as the page shows it.

    Attributes
    ----------
    caption : str
    uri : str or None
        ``data:image/svg+xml;base64,...``; ``None`` when it could not be drawn.
    error : str or None
        Why it could not be drawn (a run with one classifier has no CD diagram, ...).
    """

    caption: str
    uri: str | None = None
    error: str | None = None


def draw(caption: str, build: Callable[[], Figure]) -> Plot:
    """Build a figure and encode it, or say why it cannot be drawn."""
    try:
        figure = build()
    except (AppError, BenchmarkError) as error:
        return Plot(caption, error=str(error))
    return Plot(caption, uri=svg_data_uri(figure))


def svg_data_uri(figure: Figure) -> str:
    """The figure as a ``data:`` URI of its SVG (text kept as text)."""
    from touchbench.app.reports.plots import svg_text

    encoded = base64.b64encode(svg_text(figure).encode("utf-8")).decode("ascii")
    return f"data:image/svg+xml;base64,{encoded}"
