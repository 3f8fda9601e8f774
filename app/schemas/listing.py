"""``GET /api/datasets``, ``/api/runs``, ``/api/models``, ``/api/jobs``: which rows of a
listing to answer, at most :data:`MAX_LISTED` of them, oldest first from ``offset``."""

from __future__ import annotations

from pydantic import Field

from touchbench.app.schemas.base import Request

#: Most rows one listing answers: what a store accumulates over years stays out of one answer.
MAX_LISTED = 1000
#: Largest offset (a row id's range).
MAX_OFFSET = 2**31 - 1


class Page(Request):
    """Rows ``offset`` to ``offset + limit - 1`` of a listing, in the order of creation."""

    offset: int = Field(default=0, ge=0, le=MAX_OFFSET, description="Rows to skip.")
    limit: int = Field(default=MAX_LISTED, ge=1, le=MAX_LISTED, description="Most rows to answer.")
