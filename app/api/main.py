"""The JSON API's part of the service: its routers, error answers and upload limits.

The application is made by :func:`app.main.create_app`, which wires this and the web page.
"""

from __future__ import annotations

from fastapi import Depends, FastAPI

from touchbench.app.api import errors
from touchbench.app.api.deps import require_api_key
from touchbench.app.api.routes import (
    datasets,
    extractors,
    health,
    jobs,
    live,
    live_replays,
    models,
    recordings,
    runs,
)
from touchbench.app.api.upload_rules import line_rules
from touchbench.app.api.uploads import BodyLimit
from touchbench.app.settings import Settings


def install(app: FastAPI, settings: Settings) -> None:
    """Add the API's routes (behind the API key but for health and the live WebSocket, which
    checks it itself), its error handlers and the upload limit to ``app``."""
    errors.install(app)
    app.add_middleware(
        BodyLimit,
        limit=settings.max_upload_bytes,
        json_limit=settings.max_json_bytes,
        line_rules=line_rules,
    )
    protected = [Depends(require_api_key)]
    app.include_router(health.router)
    app.include_router(live.router)  # checks the API key itself: see its module
    for router in (
        recordings.router,
        datasets.router,
        runs.router,
        models.router,
        models.predictions,
        jobs.router,
        extractors.router,
        live_replays.router,
    ):
        app.include_router(router, dependencies=protected, responses=errors.ERROR_RESPONSES)
