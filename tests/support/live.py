"""Talking to the service's live WebSocket: its URL, a take's PCM blocks, a stream."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import soundfile
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from tests.support.service import Server


def pcm_blocks(path: Path, frames: int = 2048) -> tuple[int, int, list[bytes]]:
    samples, rate = as_int16(path)
    blocks = [
        np.ascontiguousarray(samples[i : i + frames]).tobytes()
        for i in range(0, len(samples), frames)
    ]
    return rate, samples.shape[1], blocks


def stream(
    url: str, header: dict[str, Any], blocks: list[bytes], headers: dict[str, str] | None = None
) -> tuple[list[dict[str, Any]], int, str]:
    """Send a header and blocks, then the end; the messages and the close code and reason."""
    messages: list[dict[str, Any]] = []
    with connect(url, additional_headers=headers or {}, open_timeout=60) as socket:
        try:
            socket.send(json.dumps(header))
            for block in blocks:
                socket.send(block)
            socket.send(json.dumps({"end": True}))
            while True:
                messages.append(json.loads(socket.recv(timeout=120)))
        except ConnectionClosed:
            pass
        assert socket.close_code is not None
        return messages, socket.close_code, socket.close_reason or ""


def ws_url(server: Server, model: str) -> str:
    return server.url.replace("http://", "ws://") + f"/api/models/{model}/live"


def as_int16(path: Path) -> tuple[np.ndarray, int]:
    """A recording's samples as 16-bit PCM, shape (n_frames, channels)."""
    samples, rate = soundfile.read(path, always_2d=True)
    return np.round(np.clip(samples, -1, 1) * 32767).astype("<i2"), int(rate)
