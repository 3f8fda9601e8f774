"""``POST /api/datasets/recordings``: a robot uploads a recording session; extraction runs
as a job whose result is the new data set."""

from __future__ import annotations

import shutil
import uuid
from typing import Annotated

from fastapi import APIRouter, File, Form, UploadFile, status

from app.api.deps import ServiceDep
from app.api.uploads import save_upload
from app.errors import AppError
from app.schemas.jobs import JobCreated
from app.services.jobs import submit_extraction

router = APIRouter(prefix="/api/datasets", tags=["datasets"])

#: Recordings one upload may hold.
MAX_RECORDINGS = 1000


@router.post("/recordings", status_code=status.HTTP_202_ACCEPTED, response_model=JobCreated)
def upload_session(
    service: ServiceDep,
    recordings: Annotated[
        list[UploadFile],
        File(description="Recordings in any format `touchbench extract` reads."),
    ],
    labels: Annotated[
        UploadFile | None,
        File(description="Labels CSV: file,start,end,TARGET... or file,TARGET..."),
    ] = None,
    extractor: Annotated[str, Form(max_length=40)] = "uc3m-audio",
    events: Annotated[str | None, Form(max_length=20)] = None,
    name: Annotated[str | None, Form(max_length=200)] = None,
    samplerate: Annotated[float | None, Form(gt=0)] = None,
    segment: Annotated[float | None, Form(gt=0)] = None,
    topic: Annotated[str | None, Form(max_length=200)] = None,
) -> JobCreated:
    """Save the session and queue its extraction (answer: the job's id, status 202)."""
    from features.extractors import EXTRACTORS

    if extractor not in EXTRACTORS:
        raise AppError(f"unknown extractor '{extractor}' (known: {', '.join(EXTRACTORS)})")
    if len(recordings) > MAX_RECORDINGS:
        raise AppError(f"at most {MAX_RECORDINGS} recordings per upload, got {len(recordings)}")
    folder = service.settings.work_dir / "uploads" / uuid.uuid4().hex
    try:
        names = [save_upload(r, folder, f"recording-{i}").name for i, r in enumerate(recordings)]
        labels_name = save_upload(labels, folder, "labels.csv").name if labels else None
        job = submit_extraction(
            service.store,
            folder,
            names,
            labels=labels_name,
            options={
                "extractor": extractor,
                "events": events,
                "name": name,
                "samplerate": samplerate,
                "segment": segment,
                "topic": topic,
            },
        )
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    service.dispatcher.wake()
    return JobCreated(job=job.id, status=job.status, kind=job.kind)
