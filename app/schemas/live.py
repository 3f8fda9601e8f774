"""Live sessions on a source the service reads itself (the live view's): which source, and
the recordings uploaded for replay."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from touchbench.app.schemas.base import Request, Schema

#: A stored replay's id: what :func:`app.services.live_sources.save_replay` names it.
REPLAY_ID = r"^[0-9a-f]{32}$"


class LiveSource(Request):
    """The ``source`` of a live WebSocket session's header: the service reads it, paced in
    real time (or ``speed`` times faster), instead of the client sending samples.

    ``replay``: a recording uploaded with ``POST /api/live/recordings``, run once to its end.
    ``simulated``: a simulated sensor, three contact microphones at 44.1 kHz touched
    ``touches`` times (taps and strokes on the head, left arm and right arm), from ``seed``.
    """

    kind: Literal["replay", "simulated"] = Field(description="replay or simulated.")
    replay: str | None = Field(
        default=None,
        pattern=REPLAY_ID,
        description="The id of an uploaded recording (kind replay).",
    )
    touches: int = Field(
        default=8, ge=1, le=1000, description="Touches of the simulated sensor's take."
    )
    seed: int = Field(default=0, ge=0, le=2**31 - 1, description="Seed of the simulated take.")
    speed: float = Field(
        default=1.0, ge=1.0, le=8.0, description="Times real time the source is read at."
    )

    @model_validator(mode="after")
    def _replay_named(self) -> LiveSource:
        if self.kind == "replay" and self.replay is None:
            raise ValueError("a replay source needs the id of an uploaded recording ('replay')")
        if self.kind == "simulated" and self.replay is not None:
            raise ValueError("'replay' applies to a replay source only")
        return self


class LiveReplay(Schema):
    """A recording uploaded for replay in live sessions (``POST /api/live/recordings``)."""

    id: str = Field(description="What a session's source names it by ('replay').")
    name: str = Field(description="The uploaded file's name.")
    seconds: float = Field(description="Its length: how long a replay of it runs at most.")
    samplerate: float
    channels: int


class LiveReplayList(Schema):
    """The recordings uploaded for replay, newest first (``GET /api/live/recordings``)."""

    replays: list[LiveReplay]
