"""``GET /healthz``: the store answers, and which version serves."""

from __future__ import annotations

from importlib import metadata

from fastapi import APIRouter
from fastapi.responses import JSONResponse
from sqlalchemy import text

from touchbench.app.api.deps import StoreDep
from touchbench.app.schemas.base import Schema

router = APIRouter(tags=["health"])


class Health(Schema):
    status: str
    version: str
    store: str


@router.get("/healthz", response_model=Health, responses={503: {"model": Health}})
def healthz(store: StoreDep) -> JSONResponse | Health:
    """Whether the service can reach its store (no API key needed)."""
    version = metadata.version("touchbench")
    try:
        with store.engine.connect() as connection:
            connection.execute(text("SELECT 1"))
    except Exception as error:  # the store is down: say so, do not crash
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        body = Health(status="unavailable", version=version, store=reason)
        return JSONResponse(body.to_json(), status_code=503)
    return Health(status="ok", version=version, store="ok")
