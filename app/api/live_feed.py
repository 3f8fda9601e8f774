"""Live sessions on a source the service reads itself: the ``source`` of the live
WebSocket's header (:class:`app.schemas.live.LiveSource`), what the live view opens.

The service reads the source paced in real time (``speed`` times faster at most), one block
of about 12 ms at a time, feeds the session and sends, besides the messages of a session
fed by its client (a touch, ``switched``, ``warning``):

* first ``{"source": {"name", "kind", "samplerate", "channels", "speed", "model",
  "started_at"}}``, ``started_at`` the service's clock (seconds since the epoch) when the
  source's time 0 was read;
* ``{"signal": {"time", "step", "peaks"}}`` every 50 ms or so: per channel, the largest
  magnitude of each block since the last one, the first block starting at ``time`` s of
  the source, each ``step`` s long;
* in each touch, ``ended_at``: the service's clock when the touch's last sample was read,
  so that a client on the same clock sees how long after a touch's end it showed it.

The client sends nothing more but ``{"end": true}`` to stop early.  The session ends with
the source (close 1000, ``source ended``); one source per connection, and at most
``live_sources`` of them at once per service process (1013 beyond).
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Awaitable, Callable, Mapping
from typing import TYPE_CHECKING, Any

from fastapi import WebSocket, WebSocketDisconnect
from pydantic import ValidationError
from starlette.concurrency import run_in_threadpool

from touchbench.app.errors import USER_ERRORS
from touchbench.app.schemas.live import LiveSource

if TYPE_CHECKING:
    from touchbench.app.api.deps import Service
    from touchbench.app.services.live import LiveSession, TouchPrediction
    from touchbench.drivers.source import Source

POLICY, INVALID, TOO_BIG, NORMAL, INTERNAL, TRY_AGAIN = 1008, 1007, 1009, 1000, 1011, 1013
#: Seconds between two signal messages (the touches go at once).
SIGNAL_SECONDS = 0.05


class Closed(Exception):  # noqa: N818 (ends the session with a close frame)
    def __init__(self, code: int, reason: str) -> None:
        super().__init__(reason)
        self.code = code
        self.reason = reason[:120]  # a close reason is at most 123 bytes


def source_spec(header: dict[str, Any]) -> LiveSource:
    """The header's ``source``, checked; a refusal names the field (``source.kind: ...``)."""
    try:
        return LiveSource.model_validate(header["source"])
    except ValidationError as error:
        problem = error.errors()[0]
        where = ".".join(str(part) for part in ("source", *problem["loc"]))
        raise Closed(INVALID, f"header: {where}: {problem['msg']}") from None


async def serve_source(
    websocket: WebSocket,
    service: Service,
    spec: LiveSource,
    open_session: Callable[[float, int], Awaitable[LiveSession]],
) -> None:
    """Read the source ``spec`` names into a session (``open_session(samplerate,
    channels)``) and send what it says, until the source or the client ends it.

    Raises
    ------
    Closed
        Always, at the end: how to close the socket.
    """
    from touchbench.app.services.live_sources import open_source  # start-up time: see live

    state = websocket.app.state
    open_now = getattr(state, "live_sources_open", 0)
    if open_now >= service.settings.live_sources:
        raise Closed(TRY_AGAIN, f"the service reads {open_now} live sources already; try later")
    state.live_sources_open = open_now + 1
    try:
        settings = service.settings
        try:
            source = await run_in_threadpool(
                open_source, settings.work_dir, spec, max_seconds=settings.live_source_seconds
            )
        except USER_ERRORS as error:
            raise Closed(POLICY, str(error)) from None
        try:
            session = await open_session(source.samplerate, source.n_channels)
            await _stream(websocket, source, session, spec.speed)
        finally:
            source.close()
    finally:
        state.live_sources_open -= 1


async def _stream(websocket: WebSocket, source: Source, session: LiveSession, speed: float) -> None:
    from touchbench.app.services.live_sources import peaks

    started, clock = time.time(), time.perf_counter()
    await websocket.send_json(
        {
            "source": {
                "name": source.name.rsplit("/", 1)[-1],
                "samplerate": source.samplerate,
                "channels": source.n_channels,
                "speed": speed,
                "model": session.label,
                "started_at": started,
            }
        }
    )

    async def send(touches: list[TouchPrediction]) -> None:
        for event in session.take_events():
            await websocket.send_json(event)
        for touch in touches:
            message = touch.to_json()
            message["ended_at"] = round(started + touch.end / speed, 6)
            await websocket.send_json(message)

    heard = asyncio.ensure_future(websocket.receive())
    blocks = source.blocks()
    signal: list[list[float]] = []
    first, step, last_sent = 0.0, 0.0, clock
    stopped = False
    try:
        while not stopped:
            block = await run_in_threadpool(next, blocks, None)
            if block is None:
                break
            length = block.samples.shape[1]
            due = clock + (block.time + length / source.samplerate) / speed
            wait = due - time.perf_counter()
            if wait > 0:
                await asyncio.wait({heard}, timeout=wait)
            if heard.done():
                stopped = _stop(heard.result())
            touches = await run_in_threadpool(
                session.feed, block.samples, block.time, arrived=time.perf_counter()
            )
            if not signal:
                first, step = block.time, length / source.samplerate
            signal.append(peaks(block.samples))
            now = time.perf_counter()
            if touches or session.events or now - last_sent >= SIGNAL_SECONDS:
                await websocket.send_json({"signal": _signal(first, step, signal)})
                signal, last_sent = [], now
                await send(touches)
        if signal:
            await websocket.send_json({"signal": _signal(first, step, signal)})
        await send(await run_in_threadpool(session.finish))
    finally:
        heard.cancel()
    raise Closed(NORMAL, "stream ended" if stopped else "source ended")


def _signal(first: float, step: float, columns: list[list[float]]) -> dict[str, Any]:
    """One signal message: per channel, its peaks of the blocks since the last one."""
    return {
        "time": round(first, 6),
        "step": step,
        "peaks": [list(channel) for channel in zip(*columns, strict=True)],
    }


def _stop(message: Mapping[str, Any]) -> bool:
    """True: the client's message ends the session (``{"end": true}``); anything else is
    refused (the service reads the samples itself), a disconnection ends it at once."""
    if message["type"] == "websocket.disconnect":
        raise WebSocketDisconnect(code=message.get("code", 1000))
    try:
        value = json.loads(message.get("text") or "")
    except ValueError:
        value = None
    if isinstance(value, dict) and value.get("end") is True:
        return True
    raise Closed(INVALID, 'this session reads its own source: send only {"end": true}')
