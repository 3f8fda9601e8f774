"""The service's trust boundary for browsers and DNS: which host names it answers and which
web origins may change its store.

A key keeps strangers out, but a browser is a stranger's tool on a trusted machine: any
page it opens can send a form POST or a body-less POST to ``http://127.0.0.1:8000`` (the
browser sends it before asking anything), open a WebSocket there, and, with DNS
rebinding, read the answers under a name of its own.  :class:`Trust` closes both ways in:
a request whose ``Host`` is not one of the service's names is refused, and so is a request
that changes state (any method but GET, HEAD and OPTIONS) or opens a WebSocket with an
``Origin`` that is neither the service's own nor listed.  Clients that are not browsers
(curl, robots, the CLI) send no ``Origin`` and are not affected.
"""

from __future__ import annotations

import json
from collections.abc import Collection

from starlette.datastructures import Headers
from starlette.middleware.cors import CORSMiddleware
from starlette.responses import JSONResponse, Response
from starlette.types import ASGIApp, Receive, Scope, Send

from touchbench.app.api.errors import error_body
from touchbench.app.trust import host_name, origin

#: Methods that do not change state (browsers send them cross-origin as they please; the
#: answers stay unreadable to other origins without CORS).
SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})


class Trust:
    """ASGI middleware: answer only ``hosts``; let only the service's own origin and
    ``origins`` change state or open WebSockets.

    Parameters
    ----------
    app : ASGIApp
        The application behind it.
    hosts : Collection[str]
        Host names answered, as :func:`app.trust.host_name` writes them.
    origins : Collection[str]
        Other origins allowed, as :func:`app.trust.origin` writes them.
    """

    def __init__(self, app: ASGIApp, hosts: Collection[str], origins: Collection[str]) -> None:
        self.app = app
        self.hosts = frozenset(hosts)
        self.origins = frozenset(origins)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        refusal = self.refusal(scope)
        if refusal is None:
            await self.app(scope, receive, send)
            return
        status, kind, message, where = refusal
        body = json.dumps(error_body(kind, message, where)).encode()
        if scope["type"] == "http":
            await send_json(send, "http.response", status, body)
        else:
            await _deny_websocket(scope, receive, send, status, body)

    def refusal(self, scope: Scope) -> tuple[int, str, str, str] | None:
        """Why the request is refused (status, error type, message, where), or None."""
        headers = _headers(scope)
        host = headers.get("host")
        name = host_name(host) if host is not None else None
        if name is None or name not in self.hosts:
            shown = "no Host header" if host is None else f"the host name '{host[:100]}'"
            return (
                400,
                "DisallowedHost",
                f"this service does not answer to {shown} (TOUCHBENCH_ALLOWED_HOSTS lists "
                "the names it answers besides loopback)",
                "headers.Host",
            )
        sent = headers.get("origin")
        changes = scope["type"] == "websocket" or scope.get("method", "GET") not in SAFE_METHODS
        if sent is None or not changes:
            return None
        scheme = "https" if scope.get("scheme") in ("https", "wss") else "http"
        allowed = origin(sent)
        if allowed is not None and (
            allowed == origin(f"{scheme}://{host}") or allowed in self.origins
        ):
            return None
        what = "open a WebSocket on" if scope["type"] == "websocket" else "change"
        return (
            403,
            "Forbidden",
            f"pages from the origin '{sent[:100]}' may not {what} this service (neither its "
            "own origin nor listed in TOUCHBENCH_ALLOWED_ORIGINS)",
            "headers.Origin",
        )


class Cors(CORSMiddleware):
    """Starlette's CORS for the origins listed in ``TOUCHBENCH_ALLOWED_ORIGINS``, with its
    refusal of a preflight (``OPTIONS`` with ``Access-Control-Request-Method``) answered as
    every error of the service is, in JSON, instead of Starlette's plain text."""

    def preflight_response(self, request_headers: Headers) -> Response:
        answer = super().preflight_response(request_headers)
        if answer.status_code < 400:
            return answer
        refused = bytes(answer.body).decode().removeprefix("Disallowed CORS ").split(", ")
        sent = {
            "origin": f"the origin '{request_headers.get('origin', '')[:100]}'",
            "method": f"the method '{request_headers.get('access-control-request-method', '')}'",
            "headers": "the headers "
            f"'{request_headers.get('access-control-request-headers', '')[:200]}'",
            "private-network": "access to a private network",
        }
        what = ", ".join(sent.get(name, name) for name in refused)
        header = "Origin" if refused[0] == "origin" else f"Access-Control-Request-{refused[0]}"
        where = f"headers.{header.title()}"
        headers = {
            key: value
            for key, value in answer.headers.items()
            if key.lower() not in ("content-length", "content-type")
        }
        return JSONResponse(
            error_body(
                "Forbidden",
                f"cross-origin requests are refused for {what} (TOUCHBENCH_ALLOWED_ORIGINS "
                "lists the origins allowed)",
                where,
            ),
            status_code=answer.status_code,
            headers=headers,
        )


def _headers(scope: Scope) -> dict[str, str]:
    """The request's headers that :class:`Trust` reads; a header sent twice is refused as
    unreadable (``host``: no name; ``origin``: no origin)."""
    found: dict[str, str] = {}
    for key, value in scope.get("headers", ()):
        if key in (b"host", b"origin"):
            name = key.decode()
            found[name] = "\x00" if name in found else value.decode("latin-1")
    return found


async def send_json(send: Send, prefix: str, status: int, body: bytes) -> None:
    """Send a whole JSON answer (``prefix``: ``http.response`` or, for a refused WebSocket
    handshake, ``websocket.http.response``)."""
    await send(
        {
            "type": f"{prefix}.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
            ],
        }
    )
    await send({"type": f"{prefix}.body", "body": body})


async def _deny_websocket(
    scope: Scope, receive: Receive, send: Send, status: int, body: bytes
) -> None:
    """Refuse a WebSocket handshake: with the JSON error as an HTTP answer where the server
    can send one, else with a close before the handshake (an HTTP 403)."""
    await receive()  # websocket.connect
    if "websocket.http.response" in scope.get("extensions", {}):
        await send_json(send, "websocket.http.response", status, body)
    else:
        await send({"type": "websocket.close", "code": 1008})
