"""Long work the service queues instead of doing in a request: benchmark runs (the runs table
is their queue), extraction of an uploaded recording session, training a model.

The request stores what is asked (``queued``) and answers at once; a dispatcher
(:mod:`app.jobs.dispatcher`) hands each queued item to a worker process, which claims it
and calls :func:`execute_job` or :func:`app.services.runs.execute_run`.
"""

from __future__ import annotations

# Imports inside functions: start-up time: a job of one kind loads only its own service
# (extraction loads the feature stack, training scikit-learn).
import os
import shutil
import socket
from typing import Any

from pydantic import ValidationError

from app.errors import USER_ERRORS, AppError
from app.schemas.base import Request
from app.schemas.extraction import ExtractRequest
from app.schemas.jobs import JOB_REQUESTS, JobKind, JobSchema
from app.schemas.models import TrainRequest
from app.store.database import Store
from app.store.jobs import claim_job, create_job, finish_job, get_job


def submit_extraction(store: Store, request: ExtractRequest) -> JobSchema:
    """Queue the extraction of an upload (its ``folder`` is deleted when the job ends).

    Everything that can be refused without reading the recordings is refused here, before
    the job exists: the extractor, event detection and their options (by the request
    itself), the data set's name.

    Raises
    ------
    FieldError, ConflictError
        As :func:`app.services.extraction.check_extraction` does.
    """
    from app.services.extraction import check_extraction

    check_extraction(store, request)
    return _submit(store, "extract", request)


def submit_training(store: Store, request: TrainRequest) -> JobSchema:
    """Queue training, once :func:`app.services.models.check_training` found nothing to
    refuse (before the job exists)."""
    from app.services.models import check_training

    check_training(store, request)
    return _submit(store, "train", request)


def _submit(store: Store, kind: JobKind, request: Request) -> JobSchema:
    """A queued job carrying ``request``, to be taken by a worker on this host."""
    return create_job(
        store, kind, {**request.model_dump(mode="json"), "host": socket.gethostname()}
    )


def job_request(job: JobSchema) -> Request:
    """The typed request a job carries (its ``params`` without the host).

    Raises
    ------
    AppError
        The params are not a request of the job's kind (a job queued by another version).
    """
    params = {key: value for key, value in job.params.items() if key != "host"}
    try:
        return JOB_REQUESTS[job.kind].model_validate(params)
    except ValidationError as error:
        problem = error.errors(include_url=False)[0]
        where = ".".join(str(part) for part in problem["loc"]) or "request"
        raise AppError(
            f"job {job.id} does not hold a valid {job.kind} request ({where}: {problem['msg']})"
        ) from None


def execute_job(store: Store, job_id: int) -> JobSchema | None:
    """Claim and carry out a queued job; ``None`` if another process claimed it first.

    Bad input (a recording that cannot be read, an unknown classifier) ends the job
    ``failed`` with the same one-line message the CLI prints; the job's upload folder is
    removed either way.
    """
    job = get_job(store, job_id)
    if not claim_job(store, job.id):
        return None
    folder = job.params.get("folder") if job.kind == "extract" else None
    try:
        try:
            result = _carry_out(store, job_request(job))
        finally:  # before the job ends, so that whoever sees it ended finds no upload left
            if folder:
                shutil.rmtree(folder, ignore_errors=True)
    except USER_ERRORS as error:
        finish_job(store, job.id, "failed", error=_client_words(str(error), folder))
    except KeyboardInterrupt:
        finish_job(store, job.id, "interrupted", error="interrupted")
        raise
    except Exception as error:
        message = f"unexpected {type(error).__name__}: {error}"
        finish_job(store, job.id, "failed", error=_client_words(message, folder))
    else:
        finish_job(store, job.id, "done", result=result)
    return get_job(store, job.id)


def _client_words(message: str, folder: str | None) -> str:
    """``message`` with the upload folder left out of its paths: the client knows its files
    by their names, and the service's folders are not its business."""
    if not folder:
        return message
    return message.replace(folder.rstrip(os.sep) + os.sep, "").replace(folder, "the upload")


def _carry_out(store: Store, request: Request) -> dict[str, Any]:
    """The result of a job's request: the new data set, or the new model."""
    if isinstance(request, ExtractRequest):
        from app.services.extraction import extract_and_store

        summary = extract_and_store(store, request).to_json()
        return {"dataset_id": summary["id"], **summary}
    assert isinstance(request, TrainRequest)
    from app.services.models import train

    model = train(store, request)
    return {"model_id": model.id, **model.to_json()}
