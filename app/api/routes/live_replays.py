"""``/api/live/recordings``: recordings uploaded for replay in live sessions (the live view's
source ``{"kind": "replay", "replay": ID}``)."""

from __future__ import annotations

import shutil
from typing import Annotated

from fastapi import APIRouter, File, UploadFile, status
from starlette.concurrency import run_in_threadpool

from touchbench.app.api.deps import ServiceDep
from touchbench.app.api.uploads import save_upload
from touchbench.app.schemas.live import LiveReplay, LiveReplayList
from touchbench.app.services.live_sources import (
    list_replays,
    new_replay_folder,
    replay_folder,
    save_replay,
)

router = APIRouter(prefix="/api/live", tags=["models"])


@router.post("/recordings", status_code=status.HTTP_201_CREATED, response_model=LiveReplay)
async def upload_replay(
    service: ServiceDep,
    recording: Annotated[
        UploadFile, File(description="A recording in any format extraction reads.")
    ],
) -> LiveReplay:
    """Keep a recording for replay (at most ``TOUCHBENCH_LIVE_SOURCE_SECONDS`` long; the
    newest ``TOUCHBENCH_LIVE_REPLAYS`` are kept)."""
    settings = service.settings
    folder = new_replay_folder(settings.work_dir)
    try:
        saved = await run_in_threadpool(save_upload, recording, folder, "recording")
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return await run_in_threadpool(
        save_replay,
        folder,
        saved.name,
        max_seconds=settings.live_source_seconds,
        keep=settings.live_replays,
    )


@router.get("/recordings", response_model=LiveReplayList)
def replays(service: ServiceDep) -> LiveReplayList:
    """The recordings kept for replay, newest first."""
    return LiveReplayList(replays=list_replays(replay_folder(service.settings.work_dir)))
