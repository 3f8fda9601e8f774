"""What a predictions-only process (``touchbench serve --predictions-only``) does not serve:
one 404 that says so, for every other path and method, instead of a bare "Not Found" or
"Method Not Allowed" that reads like a wrong path or a missing model."""

from __future__ import annotations

from fastapi import APIRouter, Request

from touchbench.app.errors import NotFoundError

router = APIRouter(include_in_schema=False)

METHODS = ["GET", "HEAD", "POST", "PUT", "PATCH", "DELETE", "OPTIONS"]


# Registered last: Starlette prefers any route matching both path and method, so this one
# answers only what no prediction route does (a path served for another method included).
@router.api_route("/{path:path}", methods=METHODS)
async def served_elsewhere(request: Request, path: str) -> None:
    raise NotFoundError(
        f"{request.method} /{path} is not served here: this process serves predictions only "
        "(touchbench serve --predictions-only); the full service on the same store answers it"
    )
