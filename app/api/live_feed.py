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

import numpy as np
from fastapi import WebSocket, WebSocketDisconnect
from pydantic import ValidationError
from starlette.concurrency import run_in_threadpool

from touchbench.app.errors import USER_ERRORS
from touchbench.app.schemas.live import LiveSource

if TYPE_CHECKING:
    from touchbench.app.api.deps import Service
    from touchbench.app.services.live import LiveSession, TouchPrediction
    from touchbench.drivers.source import Block, Source

POLICY, INVALID, TOO_BIG, NORMAL, INTERNAL, TRY_AGAIN = 1008, 1007, 1009, 1000, 1011, 1013
#: Seconds between two signal messages (the touches go at once).
SIGNAL_SECONDS = 0.05
#: Most seconds of the source fed at once when the service has fallen behind.
CATCH_UP_SECONDS = 1.0


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
    reader = _Reader(source, session, clock, speed)
    signal: list[list[float]] = []
    first, last_sent = 0.0, clock
    stopped = False
    try:
        due = await run_in_threadpool(reader.read)
        while due is not None and not stopped:
            wait = due - time.perf_counter()
            if wait > 0:
                await asyncio.wait({heard}, timeout=wait)
            if heard.done():
                stopped = _stop(heard.result())
            at, columns, touches, due = await run_in_threadpool(reader.step)
            first = first if signal else at
            signal += columns
            now = time.perf_counter()
            if touches or session.events or now - last_sent >= SIGNAL_SECONDS:
                await websocket.send_json({"signal": _signal(first, reader.step_seconds, signal)})
                signal, last_sent = [], now
                await send(touches)
        if signal:
            await websocket.send_json({"signal": _signal(first, reader.step_seconds, signal)})
        await send(await run_in_threadpool(session.finish))
    finally:
        heard.cancel()
    raise Closed(NORMAL, "stream ended" if stopped else "source ended")


class _Reader:
    """The source's blocks into the session, each when it is due (``clock`` + its end /
    ``speed``, on ``time.perf_counter()``); blocks already due when one is fed (the
    service fell behind) are fed with it, so that it catches up instead of lagging more."""

    def __init__(self, source: Source, session: LiveSession, clock: float, speed: float) -> None:
        self.blocks = source.blocks()
        self.samplerate = source.samplerate
        self.session = session
        self.clock = clock
        self.speed = speed
        self.next: Block | None = None
        self.step_seconds = 0.0

    def _due(self, block: Block) -> float:
        return self.clock + (block.time + block.samples.shape[1] / self.samplerate) / self.speed

    def read(self) -> float | None:
        """Read the next block ahead; when it is due (None: the source ended)."""
        self.next = next(self.blocks, None)
        if self.next is None:
            return None
        if not self.step_seconds:
            self.step_seconds = self.next.samples.shape[1] / self.samplerate
        return self._due(self.next)

    def step(self) -> tuple[float, list[list[float]], list[TouchPrediction], float | None]:
        """Feed the block read ahead and those due since: the source time of the first,
        their peaks (one column per block), the touches that ended in them, and when the
        next block is due (None: the source ended)."""
        from touchbench.app.services.live_sources import peaks  # start-up time: see live

        assert self.next is not None, "read() first"
        taken = [self.next]
        due = self.read()
        most = max(1, int(CATCH_UP_SECONDS / self.step_seconds))
        while due is not None and due <= time.perf_counter() and len(taken) < most:
            assert self.next is not None
            taken.append(self.next)
            due = self.read()
        samples = (
            taken[0].samples
            if len(taken) == 1
            else np.concatenate([block.samples for block in taken], axis=1)
        )
        # Arrived when the last of them was due: a block is late by what the service fell
        # behind, as a sound card's would wait in its queue.
        arrived = self._due(taken[-1])
        touches = self.session.feed(samples, taken[0].time, arrived=arrived)
        return taken[0].time, [peaks(block.samples) for block in taken], touches, due


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
