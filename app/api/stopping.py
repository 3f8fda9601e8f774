"""A request cut short by the service's stop is answered 503 in JSON, like every error of
the service, instead of uvicorn's plain-text 500.

Ctrl-C or SIGTERM gives the requests in flight :data:`app.cli.stopping.GRACE` seconds;
uvicorn then cancels those still computing (a heavy page, an import) and answers each
whose response has not begun with ``500 Internal Server Error``.  Nothing went wrong with
them, though: the service is going away, and the client may send the request again once
it is back.
"""

from __future__ import annotations

import asyncio
import json

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from touchbench.app.api.errors import error_body
from touchbench.app.api.trust import send_json

#: What a client whose request the stop cut short reads.
STOPPING = error_body(
    "ServiceUnavailable",
    "the service is stopping (Ctrl-C or SIGTERM) and cut this request short; send it again "
    "once the service is back",
)


class CutByStop:
    """ASGI middleware: answer 503 with :data:`STOPPING` for an HTTP request cancelled
    before its response began, then let the cancellation go on."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False

        async def sending(message: Message) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, receive, sending)
        except asyncio.CancelledError:
            if not started:  # else the client reads a cut answer, as any cut connection
                await send_json(send, "http.response", 503, json.dumps(STOPPING).encode())
            raise
