"""``POST /api/datasets/recordings``: a robot uploads a recording session; extraction runs
as a job whose result is the new data set."""

from __future__ import annotations

import json
import shutil
import uuid
from typing import Annotated, Any

from fastapi import APIRouter, File, Form, UploadFile, status

from touchbench.app.api.deps import ServiceDep
from touchbench.app.api.uploads import form_request, in_client_words, save_upload
from touchbench.app.errors import FieldError
from touchbench.app.schemas.extraction import DEFAULT_EXTRACTOR, ExtractRequest
from touchbench.app.schemas.jobs import JobCreated
from touchbench.app.services.jobs import submit_extraction

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
    extractor: Annotated[str | None, Form(description=f"Default: {DEFAULT_EXTRACTOR}.")] = None,
    events: Annotated[str | None, Form()] = None,
    name: Annotated[str | None, Form()] = None,
    samplerate: Annotated[float | None, Form()] = None,
    segment: Annotated[float | None, Form()] = None,
    topic: Annotated[str | None, Form()] = None,
    fields: Annotated[
        list[str] | None,
        Form(description="Numeric fields of `topic`, or CSV columns, read as channels."),
    ] = None,
    time_column: Annotated[
        str | None, Form(description="The time column of CSV recordings, if not a usual name.")
    ] = None,
    time_unit: Annotated[
        str, Form(description="auto, s, ms, us or ns: the unit of that time column.")
    ] = "auto",
    channels: Annotated[
        int | None, Form(description="Channels of raw PCM in bags without AudioInfo.")
    ] = None,
    sample_format: Annotated[
        str | None, Form(description="S16LE, S32LE or F32LE: raw PCM in bags without AudioInfo.")
    ] = None,
    options: Annotated[
        str | None,
        Form(
            description="Options of the extractor and the event detector as a JSON object "
            '(`{"threshold": 12}`), as `-O name=value` on the command line.'
        ),
    ] = None,
) -> JobCreated:
    """Save the session and queue its extraction (answer: the job's id, status 202).

    Everything that can be refused without reading the recordings is refused before the job
    exists: the extractor, event detection and bounds before anything is saved, the data
    set's name and the labels file before the job is queued (the saved files are then
    removed).
    """
    values = {
        "extractor": extractor,
        "events": events,
        "name": name,
        "samplerate": samplerate,
        "segment": segment,
        "topic": topic,
        "fields": fields,
        "time_column": time_column,
        "time_unit": time_unit,
        "channels": channels,
        "sample_format": sample_format,
        "options": _options(options),
    }
    # Checked before a byte is saved (the files' names stand for them), so that a refused
    # request leaves nothing on the disk.
    form_request(
        ExtractRequest,
        recordings=[r.filename or "recording" for r in recordings],
        **values,
    )
    folder = service.settings.work_dir / "uploads" / uuid.uuid4().hex
    try:
        names = [save_upload(r, folder, f"recording-{i}").name for i, r in enumerate(recordings)]
        labels_name = save_upload(labels, folder, "labels.csv").name if labels else None
        request = form_request(
            ExtractRequest, recordings=names, labels=labels_name, folder=folder, **values
        )
        with in_client_words(folder):  # the labels file by the client's name, not our folder
            job = submit_extraction(service.store, request)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    service.dispatcher.wake()
    return JobCreated(job=job.id, status=job.status, kind=job.kind)


def _options(text: str | None) -> dict[str, Any] | None:
    """The ``options`` form field's JSON object (``None``: none given)."""
    if text is None or not text.strip():
        return None
    try:
        value = json.loads(text)
    except ValueError:
        raise FieldError("options", "is not JSON: give an object of option -> value") from None
    if not isinstance(value, dict):
        raise FieldError("options", "is not a JSON object of option -> value")
    return value
