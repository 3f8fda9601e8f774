"""The web page wired into the service.

Pages are frames without data, served to anyone who reaches the service.  Everything that
shows data is a fragment, guarded by the same API-key dependency as the JSON API: a browser
cannot add a header to a navigation, so the page's script fetches the fragments (and calls
the JSON API for actions) with the ``X-API-Key`` header, the key entered once and kept in
the tab's session storage.  No cookie is involved, so no other site can make a browser
send a request that carries the key (no cross-site request forgery).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fastapi import FastAPI
from fastapi.staticfiles import StaticFiles

from touchbench.app.web.rendering import STATIC
from touchbench.app.web.routes import (
    compare,
    datasets,
    jobs,
    live,
    models,
    pages,
    recordings,
    runs,
)


def install(app: FastAPI, dependencies: Sequence[Any]) -> None:
    """Add the pages, the fragments (behind ``dependencies``) and the static files."""
    app.include_router(pages.router)
    app.include_router(live.router)  # a page: no data, the socket checks the key
    for router in (
        datasets.router,
        runs.router,
        models.router,
        compare.router,
        jobs.router,
        recordings.router,
    ):
        app.include_router(router, dependencies=list(dependencies))
    app.mount("/static", StaticFiles(directory=STATIC), name="static")
