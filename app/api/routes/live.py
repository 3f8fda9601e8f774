"""``WS /api/models/{model}/live``: live predictions on a stream of samples.

The client sends a JSON header ``{"samplerate": 44100, "channels": 3, "format": "S16LE"}``
(``format``: S16LE, S32LE or F32LE; ``engine``: auto, onnx or native, as for a
prediction; ``api_key`` here when the handshake could not carry the ``X-API-Key``
header), then binary messages of interleaved samples, and
``{"end": true}`` when its stream ends.  The server sends one JSON message per detected touch,
as ``touchbench live --json`` prints it (its ``model`` says which version answered), and
closes with a reason on bad input: 1008 for a
missing or wrong key or a model that cannot run live, 1007 for a malformed header or block,
1009 for a block over the size limit, 1000 when the stream ended.

A header with a ``source`` (``{"source": {"kind": "replay", "replay": ID}}`` or
``{"source": {"kind": "simulated", "touches": 8}}``) instead of the stream's format asks the
service to read that source itself (the live view): see :mod:`app.api.live_feed`.

A session on ``NAME@ALIAS`` (or ``NAME``, the newest version) follows it: when the alias
moves, the next touches are answered by the new version without the stream being
dropped, and the server sends ``{"switched": "NAME@3", "from": "NAME@2"}`` first; a new
version that extracts its features otherwise is not taken, and ``{"warning": "..."}`` says
so once.
"""

from __future__ import annotations

import asyncio
import json
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from starlette.concurrency import run_in_threadpool

from touchbench.app.api.deps import KeyRefused, Service, key_name
from touchbench.app.api.live_feed import (
    INTERNAL,
    INVALID,
    NORMAL,
    POLICY,
    TOO_BIG,
    serve_source,
    source_spec,
)
from touchbench.app.api.live_feed import Closed as _Closed
from touchbench.app.errors import USER_ERRORS
from touchbench.app.schemas.models import Engine
from touchbench.drivers.errors import DriverError
from touchbench.drivers.pcm import SAMPLE_FORMATS, decode_pcm

if TYPE_CHECKING:  # start-up time: the feature stack loads with the first session
    from touchbench.app.services.live import LiveSession

router = APIRouter(tags=["models"])

#: Seconds the client has to send its header.
HEADER_TIMEOUT = 10.0
#: Longest block, in seconds of audio.
MAX_BLOCK_SECONDS = 10.0


@router.websocket("/api/models/{model_ref}/live")
async def live(websocket: WebSocket, model_ref: str) -> None:
    service: Service = websocket.app.state.service
    await websocket.accept()
    try:
        header = await _header(websocket)
        _check_key(service, websocket, header)
        if "source" in header:  # the service reads the source itself: see live_feed
            engine = _engine(header)

            async def opened(samplerate: float, channels: int) -> LiveSession:
                try:
                    return await run_in_threadpool(
                        _open, service, model_ref, samplerate, channels, engine
                    )
                except USER_ERRORS as error:
                    raise _Closed(POLICY, str(error)) from None

            await serve_source(websocket, service, source_spec(header), opened)
        samplerate, channels, sample_format = _stream_format(header)
        engine = _engine(header)
        try:
            session = await run_in_threadpool(
                _open, service, model_ref, samplerate, channels, engine
            )
        except USER_ERRORS as error:
            raise _Closed(POLICY, str(error)) from None
        frame = channels * np.dtype(SAMPLE_FORMATS[sample_format][0]).itemsize
        limit = int(MAX_BLOCK_SECONDS * samplerate) * frame
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                return
            if message.get("bytes") is not None:
                data: bytes = message["bytes"]
                if len(data) > limit:
                    raise _Closed(TOO_BIG, f"a block holds at most {MAX_BLOCK_SECONDS:g} s")
                try:
                    block = decode_pcm(data, channels=channels, sample_format=sample_format)
                except DriverError as error:
                    raise _Closed(INVALID, str(error)) from None
                touches = await run_in_threadpool(session.feed, block)
                for event in session.take_events():
                    await websocket.send_json(event)
            else:
                if _json(message.get("text")).get("end") is not True:
                    raise _Closed(INVALID, 'text messages after the header must be {"end": true}')
                touches = await run_in_threadpool(session.finish)
                for touch in touches:
                    await websocket.send_json(touch.to_json())
                raise _Closed(NORMAL, "stream ended")
            for touch in touches:
                await websocket.send_json(touch.to_json())
    except _Closed as closed:
        await websocket.close(code=closed.code, reason=closed.reason)
    except USER_ERRORS as error:
        await websocket.close(code=POLICY, reason=str(error)[:120])
    except WebSocketDisconnect:
        return
    except Exception as error:  # never crash the server: say what happened, close
        await websocket.close(code=INTERNAL, reason=f"unexpected {type(error).__name__}")


def _open(
    service: Service, model_ref: str, samplerate: float, channels: int, engine: Engine
) -> LiveSession:
    """The session, opened in a worker thread: the first one imports the feature stack and
    scikit-learn, which must not hold the event loop (and its other sockets' pings) up."""
    from touchbench.app.services.live import open_live  # start-up time: see above

    return open_live(
        service.store,
        model_ref,
        samplerate=samplerate,
        n_channels=channels,
        engine=engine,
        cache=service.models,
        follow_seconds=service.settings.live_follow_seconds,
    )


async def _header(websocket: WebSocket) -> dict[str, Any]:
    try:
        message = await asyncio.wait_for(websocket.receive(), HEADER_TIMEOUT)
    except TimeoutError:
        raise _Closed(INVALID, f"no header within {HEADER_TIMEOUT:g} s") from None
    if message["type"] == "websocket.disconnect":
        raise WebSocketDisconnect(code=message.get("code", 1000))
    return _json(message.get("text"))


def _json(text: str | None) -> dict[str, Any]:
    try:
        value = json.loads(text or "")
    except ValueError:
        raise _Closed(INVALID, "expected a JSON object") from None
    if not isinstance(value, dict):
        raise _Closed(INVALID, "expected a JSON object")
    return value


def _check_key(service: Service, websocket: WebSocket, header: dict[str, Any]) -> None:
    """A live session predicts: it needs a key with the ``predict`` role (when the service
    has keys), from the handshake's ``X-API-Key`` header or the header message."""
    given = websocket.headers.get("x-api-key") or header.get("api_key")
    try:
        key_name(service.settings, given if isinstance(given, str) else None, "predict")
    except KeyRefused as refused:
        reason = "this service needs an API key (X-API-Key or api_key)"
        raise _Closed(POLICY, reason if refused.status == 401 else str(refused)) from None


def _engine(header: dict[str, Any]) -> Engine:
    engine = header.get("engine", "auto")
    if engine not in ("auto", "onnx", "native"):
        raise _Closed(INVALID, "header: 'engine' must be auto, onnx or native")
    return cast(Engine, engine)


def _stream_format(header: dict[str, Any]) -> tuple[float, int, str]:
    samplerate = header.get("samplerate")
    channels = header.get("channels")
    kind = str(header.get("format", "S16LE")).upper()
    if (
        not isinstance(samplerate, int | float)
        or isinstance(samplerate, bool)
        or not (0 < samplerate <= 1_000_000)
    ):
        raise _Closed(INVALID, "header: 'samplerate' must be a number of Hz up to 1e6")
    if not isinstance(channels, int) or isinstance(channels, bool) or not 0 < channels <= 256:
        raise _Closed(INVALID, "header: 'channels' must be a whole number from 1 to 256")
    if kind not in SAMPLE_FORMATS:
        raise _Closed(INVALID, f"header: 'format' must be one of {', '.join(SAMPLE_FORMATS)}")
    return float(samplerate), channels, kind
