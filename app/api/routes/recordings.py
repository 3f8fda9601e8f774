"""``POST /api/datasets/recordings``: a robot uploads a recording session; extraction runs
as a job whose result is the new data set."""

from __future__ import annotations

import shutil
import uuid
from typing import Annotated

from fastapi import APIRouter, File, Form, UploadFile, status

from app.api.deps import ServiceDep
from app.api.uploads import form_request, save_upload
from app.errors import FieldError
from app.schemas.extraction import MAX_RECORDINGS, ExtractRequest
from app.schemas.jobs import JobCreated
from app.services.jobs import submit_extraction

router = APIRouter(prefix="/api/datasets", tags=["datasets"])


@router.post("/recordings", status_code=status.HTTP_202_ACCEPTED, response_model=JobCreated)
def upload_session(
    service: ServiceDep,
    recordings: Annotated[
        list[UploadFile],
        File(description="Recordings in any format extraction reads."),
    ],
    labels: Annotated[
        UploadFile | None,
        File(description="Labels CSV: file,start,end,TARGET... or file,TARGET..."),
    ] = None,
    extractor: Annotated[str | None, Form(description="Default: uc3m-audio.")] = None,
    events: Annotated[str | None, Form()] = None,
    name: Annotated[str | None, Form()] = None,
    samplerate: Annotated[float | None, Form()] = None,
    segment: Annotated[float | None, Form()] = None,
    topic: Annotated[str | None, Form()] = None,
) -> JobCreated:
    """Save the session and queue its extraction (answer: the job's id, status 202).

    Everything that can be refused without reading the recordings (the extractor, event
    detection, the data set's name) is refused before anything is saved or queued.
    """
    if len(recordings) > MAX_RECORDINGS:
        raise FieldError(
            "recordings", f"at most {MAX_RECORDINGS} recordings per upload, got {len(recordings)}"
        )
    fields = {
        "extractor": extractor,
        "events": events,
        "name": name,
        "samplerate": samplerate,
        "segment": segment,
        "topic": topic,
    }
    # Checked before a byte is saved, with the files' names as placeholders.
    form_request(
        ExtractRequest,
        recordings=[r.filename or "recording" for r in recordings],
        **fields,
    )
    folder = service.settings.work_dir / "uploads" / uuid.uuid4().hex
    try:
        names = [save_upload(r, folder, f"recording-{i}").name for i, r in enumerate(recordings)]
        labels_name = save_upload(labels, folder, "labels.csv").name if labels else None
        request = form_request(
            ExtractRequest, recordings=names, labels=labels_name, folder=folder, **fields
        )
        job = submit_extraction(service.store, request)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    service.dispatcher.wake()
    return JobCreated(job=job.id, status=job.status, kind=job.kind)
