"""The live view: a frame without data (as every page, see :mod:`app.web.routes.pages`)
whose script opens the live WebSocket (:mod:`app.api.routes.live`) on a source the service
reads itself, and draws what it says."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from touchbench.app.web.rendering import render

router = APIRouter(include_in_schema=False)


@router.get("/live", response_class=HTMLResponse)
def live() -> HTMLResponse:
    """Pick a model and a source, then watch the signal, the touches and their labels."""
    return render("live.html.j2", title="live view")
