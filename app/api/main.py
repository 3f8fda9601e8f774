"""The JSON API's part of the service: its routers, error answers and upload limits.

The application is made by :func:`app.main.create_app`, which wires this and the web page.
"""

from __future__ import annotations

from fastapi import APIRouter, Depends, FastAPI

from touchbench.app.api import errors
from touchbench.app.api.deps import require_api_key
from touchbench.app.api.routes import (
    datasets,
    elsewhere,
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

#: The routers of a predictions-only process (``Settings.predictions_only``): what robots
#: ask; nothing that changes the store or queues work.
PREDICTION_ROUTERS: tuple[APIRouter, ...] = (models.serving, models.predictions)

#: The routers only the full service has.
MANAGEMENT_ROUTERS: tuple[APIRouter, ...] = (
    recordings.router,
    datasets.router,
    runs.router,
    models.router,
    jobs.router,
    extractors.router,
    live_replays.router,
)


def install(app: FastAPI, settings: Settings) -> None:
    """Add the API's routes (behind the API key but for health and the live WebSocket, which
    checks it itself), its error handlers and the upload limit to ``app``: every route, or
    those of :data:`PREDICTION_ROUTERS` when ``settings.predictions_only``."""
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
    routers = PREDICTION_ROUTERS
    if not settings.predictions_only:
        routers = (*MANAGEMENT_ROUTERS, *routers)
    for router in routers:
        app.include_router(router, dependencies=protected, responses=errors.ERROR_RESPONSES)
    if settings.predictions_only:
        app.include_router(elsewhere.router)  # last: what no route above answers
