"""Uploads: a body-size limit enforced while the body streams in (a lower one, and a depth
limit, for JSON bodies; a line limit for the text files of a form), uploaded files saved
under safe names, and requests built from a form's fields."""

from __future__ import annotations

import json
import re
import shutil
from collections.abc import Awaitable, Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

from fastapi import UploadFile
from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from touchbench.app.api.counting import DepthScan
from touchbench.app.api.errors import UploadTooLarge, error_body, status_of, where_of
from touchbench.app.api.multipart_lines import Chooser, MultipartLines, boundary_of
from touchbench.app.errors import USER_ERRORS, AppError, client_words
from touchbench.app.schemas.base import Request

RequestType = TypeVar("RequestType", bound=Request)

#: Bytes copied at a time from an upload to its file.
CHUNK = 1 << 20
_UNSAFE = re.compile(r"[^\w.+-]+")
#: ``rules(scope, declared)``: the line rules of the files of an upload whose body says it
#: is ``declared`` bytes long (None when not said), None when its lines are not checked.
LineRules = Callable[[Scope, int | None], Awaitable[Chooser | None]]


class RefusedBeforeBodyError(Exception):
    """Raised by line rules: the request is answered ``error`` before its body is read
    (nothing in it could change the answer: a file posted to a model that is not there).

    Parameters
    ----------
    error : Exception
        The route's own error, answered as the route would answer it.
    """

    def __init__(self, error: Exception) -> None:
        super().__init__(str(error))
        self.error = error


class JsonTooLarge(UploadTooLarge):
    """A JSON body larger than ``TOUCHBENCH_MAX_JSON_MB`` (answered 413 as any upload)."""

    def __init__(self, limit: int) -> None:
        Exception.__init__(
            self,
            f"the JSON body is larger than the limit of {limit / 2**20:g} MB (the setting "
            "TOUCHBENCH_MAX_JSON_MB raises the limit)",
        )


class BodyLimit:
    """ASGI middleware: a request body over ``limit`` bytes (``json_limit`` for a JSON
    body) is refused with 413, a JSON body nested too deep with 422
    (:class:`app.api.counting.DepthScan`), and a form's text file with a line longer than
    its reader allows as that reader would refuse it (``line_rules``,
    :class:`app.api.multipart_lines.MultipartLines`), at the chunk where it passes the
    limit.

    A declared ``Content-Length`` over the limit is refused before any byte is read; a
    body without one is counted as it arrives and refused as soon as it passes the limit,
    so that nothing larger is ever spooled to memory or disk.  A JSON body is gathered
    here (the route reads it whole anyway), and answered here when refused: a route's
    body parser would turn any error met reading the body into a 400.  A form is handed
    on chunk by chunk as it comes; a line too long is answered here, and the form parser
    then told that the client went away, so that the route never runs.
    """

    def __init__(
        self,
        app: ASGIApp,
        limit: int,
        json_limit: int | None = None,
        line_rules: LineRules | None = None,
    ) -> None:
        self.app = app
        self.limit = limit
        self.json_limit = limit if json_limit is None else min(limit, json_limit)
        self.line_rules = line_rules

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        json_body = _is_json(scope)
        limit = self.json_limit if json_body else self.limit
        too_large = JsonTooLarge if json_body else UploadTooLarge
        declared = _content_length(scope)
        if declared is not None and declared > limit:
            await _answer(send, 413, "UploadTooLarge", str(too_large(limit)))
            return
        if json_body:
            await self._json(scope, receive, send)
            return
        seen = 0
        try:
            lines = await self._lines(scope, declared)
        except RefusedBeforeBodyError as refused:
            await _answer_error(send, refused.error)
            return
        answered = False

        async def counted() -> Message:
            nonlocal seen, answered
            if answered:
                return {"type": "http.disconnect"}
            message = await receive()
            if message["type"] == "http.request":
                body = message.get("body", b"")
                seen += len(body)
                if seen > limit:
                    raise too_large(limit)
                found = lines.feed(body) if lines is not None else None
                if found is not None:
                    await _answer_error(send, found.error)
                    # the form parser stops as for a client gone; the route never runs
                    answered = True
                    return {"type": "http.disconnect"}
            return message

        async def unless_answered(message: Message) -> None:
            if not answered:  # the app's answer to the "disconnect" goes nowhere
                await send(message)

        await self.app(scope, counted, unless_answered)

    async def _lines(self, scope: Scope, declared: int | None) -> MultipartLines | None:
        """The scanner of the lines of a form's text files, None for any other body."""
        if self.line_rules is None:
            return None
        boundary = None
        for key, value in scope.get("headers", ()):
            if key == b"content-type":
                boundary = boundary_of(value)
                break
        if boundary is None:
            return None
        choose = await self.line_rules(scope, declared)
        return MultipartLines(boundary, choose) if choose is not None else None

    async def _json(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Gather a JSON body, refuse it when too large or too deep, else hand it on."""
        chunks: list[bytes] = []
        size = 0
        depth = DepthScan()
        while True:
            message = await receive()
            if message["type"] != "http.request":  # the client went away: say so onwards
                await self.app(scope, _replayed(message, receive), send)
                return
            chunks.append(message.get("body", b""))
            size += len(chunks[-1])
            if size > self.json_limit:
                await _answer(send, 413, "UploadTooLarge", str(JsonTooLarge(self.json_limit)))
                return
            more = message.get("more_body", False)
            # the depth as the bytes come, before any parser: a deep body is refused at its
            # first chunks, not gathered
            problem = depth.feed(chunks[-1], last=not more)
            if problem is not None:
                await _answer(send, 422, "ValidationError", f"body: {problem}")
                return
            if not more:
                break
        body = b"".join(chunks)
        whole = {"type": "http.request", "body": body, "more_body": False}
        await self.app(scope, _replayed(whole, receive), send)


def _replayed(first: Message, receive: Receive) -> Receive:
    """``receive`` that gives ``first`` before the messages still to come."""
    given = False

    async def replay() -> Message:
        nonlocal given
        if given:
            return await receive()
        given = True
        return first

    return replay


def safe_name(name: str | None, fallback: str) -> str:
    """A file name without folders, hidden dots or odd characters."""
    base = Path(name or "").name
    base = _UNSAFE.sub("_", base).lstrip(".")
    return base[:120] or fallback


def save_upload(upload: UploadFile, folder: Path, fallback: str) -> Path:
    """Copy an uploaded file into ``folder`` under its safe name; returns its path.

    Raises
    ------
    AppError
        Two uploads of one request share a name.
    """
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / safe_name(upload.filename, fallback)
    if target.exists():
        raise AppError(f"two uploaded files are named '{target.name}'; names must differ")
    with target.open("wb") as out:
        shutil.copyfileobj(upload.file, out, CHUNK)
    return target


@contextmanager
def in_client_words(folder: Path) -> Iterator[None]:
    """Bad input met reading the uploaded files of ``folder`` is answered naming them as
    the client does (``take.wav: ...``), never by the service's own folder."""
    try:
        yield
    except USER_ERRORS as error:
        for name in ("message", "source"):  # the parts a DataFormatError words itself from
            value = getattr(error, name, None)
            if isinstance(value, str):
                setattr(error, name, client_words(value, str(folder)))
        error.args = tuple(
            client_words(arg, str(folder)) if isinstance(arg, str) else arg for arg in error.args
        )
        raise


def form_request(kind: type[RequestType], **fields: Any) -> RequestType:
    """The request ``kind`` made of a form's fields (``None``: the request's default).

    Raises
    ------
    RequestValidationError
        A field the request refuses, located as ``body.FIELD`` as FastAPI locates a JSON
        body's (a rule of the request raises its :class:`~app.errors.FieldError`, which the
        service answers the same way).
    """
    try:
        return kind(**{name: value for name, value in fields.items() if value is not None})
    except ValidationError as error:
        problems = error.errors(include_url=False, include_input=False, include_context=False)
        raise RequestValidationError(
            [{**problem, "loc": ("body", *problem["loc"])} for problem in problems]
        ) from None


def _is_json(scope: Scope) -> bool:
    """Whether the request says its body is JSON (``application/json``, ``.../x+json``)."""
    for key, value in scope.get("headers", ()):
        if key == b"content-type":
            kind = value.split(b";", 1)[0].strip().lower()
            return kind == b"application/json" or (
                kind.startswith(b"application/") and kind.endswith(b"+json")
            )
    return False


def _content_length(scope: Scope) -> int | None:
    for key, value in scope.get("headers", ()):
        if key == b"content-length":
            try:
                return int(value)
            except ValueError:
                return None
    return None


async def _answer_error(send: Send, error: Exception) -> None:
    """Answer ``error`` here as the service's handlers answer it from a route."""
    await _answer(send, status_of(error), type(error).__name__, str(error), where_of(error))


async def _answer(
    send: Send, status: int, kind: str, message: str, where: str | None = "body"
) -> None:
    """Answer the request here, in the service's error body, and close the connection
    (the rest of a refused body is not read)."""
    body: Any = json.dumps(error_body(kind, message, where))
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [(b"content-type", b"application/json"), (b"connection", b"close")],
        }
    )
    await send({"type": "http.response.body", "body": body.encode()})
