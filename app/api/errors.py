"""Every error the service answers is JSON: ``{"error": {"type", "message", "where"}}``.

Bad input is a 4xx with the same message the CLI prints: 404 for an unknown id, 409 for a
clash with the store's state, 413 for an upload over the limit, 422 for a body that does
not validate, 400 for anything else the user can fix.  Nothing else should ever happen; if
it does, the answer is a 500 with a one-line message and no stack trace.
"""

from __future__ import annotations

import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import Field
from starlette.exceptions import HTTPException as StarletteHTTPException

from touchbench.app.errors import USER_ERRORS, ConflictError, FieldError, NotFoundError
from touchbench.app.schemas.base import Schema
from touchbench.benchmark.errors import DataFormatError

log = logging.getLogger("touchbench.api")


class ErrorDetail(Schema):
    type: str = Field(description="The kind of error, e.g. NotFoundError, DataFormatError.")
    message: str = Field(description="What is wrong, in one line (as the CLI prints it).")
    where: str | None = Field(description="File and line, attribute or field, if known.")


class ErrorBody(Schema):
    """Every error the service answers."""

    error: ErrorDetail


#: The error answers every route may give, for the OpenAPI document.
ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    400: {"model": ErrorBody, "description": "Bad input (the message says what and where)."},
    401: {"model": ErrorBody, "description": "No API key (when the service has one)."},
    403: {"model": ErrorBody, "description": "Wrong API key."},
    404: {"model": ErrorBody, "description": "No such data set, run, model or job."},
    409: {"model": ErrorBody, "description": "Clashes with the store's state."},
    413: {"model": ErrorBody, "description": "Upload over TOUCHBENCH_MAX_UPLOAD_MB."},
    422: {"model": ErrorBody, "description": "The request does not validate."},
}


class UploadTooLarge(Exception):  # noqa: N818 (answered as 413, not a bug)
    """The request body is larger than ``TOUCHBENCH_MAX_UPLOAD_MB``."""

    def __init__(self, limit: int) -> None:
        super().__init__(f"the upload is larger than the limit of {limit / 2**20:g} MB")


def error_body(kind: str, message: str, where: str | None = None) -> dict[str, Any]:
    return {"error": {"type": kind, "message": message, "where": where}}


def status_of(error: Exception) -> int:
    if isinstance(error, FieldError):
        return 422
    if isinstance(error, NotFoundError):
        return 404
    if isinstance(error, ConflictError):
        return 409
    return 400


def where_of(error: Exception) -> str | None:
    if isinstance(error, FieldError):
        return f"body.{error.field}"
    if isinstance(error, DataFormatError):
        parts = []
        if error.source is not None:
            parts.append(error.source + (f":{error.line}" if error.line is not None else ""))
        elif error.line is not None:
            parts.append(f"line {error.line}")
        if error.attribute is not None:
            parts.append(f"attribute '{error.attribute}'")
        return ", ".join(parts) or None
    return None


def install(app: FastAPI) -> None:
    """Register the handlers that turn every error into the JSON error body."""

    async def user_error(request: Request, error: Exception) -> JSONResponse:
        return JSONResponse(
            error_body(type(error).__name__, str(error), where_of(error)),
            status_code=status_of(error),
        )

    async def too_large(request: Request, error: Exception) -> JSONResponse:
        cause = _caused_by(error, UploadTooLarge) or error
        return JSONResponse(error_body("UploadTooLarge", str(cause), "body"), status_code=413)

    async def invalid(request: Request, error: Exception) -> JSONResponse:
        assert isinstance(error, RequestValidationError)
        problems = error.errors()
        first = problems[0] if problems else {"loc": (), "msg": "invalid request"}
        where = ".".join(str(part) for part in first.get("loc", ()))
        message = "; ".join(
            f"{'.'.join(str(p) for p in problem.get('loc', ()))}: {problem.get('msg')}"
            for problem in problems[:5]
        )
        return JSONResponse(error_body("ValidationError", message, where or None), status_code=422)

    async def http_error(request: Request, error: Exception) -> JSONResponse:
        assert isinstance(error, StarletteHTTPException)
        if _caused_by(error, UploadTooLarge):  # FastAPI wraps errors met reading a form
            return await too_large(request, error)
        headers = getattr(error, "headers", None)
        return JSONResponse(
            error_body(_http_kind(error.status_code), str(error.detail)),
            status_code=error.status_code,
            headers=headers,
        )

    async def unexpected(request: Request, error: Exception) -> JSONResponse:
        log.exception("unexpected error on %s %s", request.method, request.url.path)
        return JSONResponse(
            error_body("InternalError", f"unexpected {type(error).__name__}; see the server log"),
            status_code=500,
        )

    for kind in USER_ERRORS:
        app.add_exception_handler(kind, user_error)
    app.add_exception_handler(UploadTooLarge, too_large)
    app.add_exception_handler(RequestValidationError, invalid)
    app.add_exception_handler(StarletteHTTPException, http_error)
    app.add_exception_handler(Exception, unexpected)


def _caused_by(error: BaseException, kind: type[BaseException]) -> BaseException | None:
    """``error`` or the first exception of ``kind`` in its chain of causes."""
    seen: BaseException | None = error
    while seen is not None:
        if isinstance(seen, kind):
            return seen
        seen = seen.__cause__ or seen.__context__
    return None


def _http_kind(status: int) -> str:
    return {
        401: "Unauthorized",
        403: "Forbidden",
        404: "NotFound",
        405: "MethodNotAllowed",
        413: "UploadTooLarge",
    }.get(status, "HTTPError")
