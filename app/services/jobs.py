"""Long work the service queues instead of doing in a request: benchmark runs (the runs table
is their queue), extraction of an uploaded recording session, training a model, making a
model's ONNX twin, and the answers after a run (an ablation, permutation importance, a
learning curve), which keep what they finished as the job's result while they run.

The request stores what is asked (``queued``) and answers at once; a dispatcher
(:mod:`app.jobs.dispatcher`) hands each queued item to a worker process, which claims it
and calls :func:`execute_job` or :func:`app.services.runs.execute_run`.
"""

from __future__ import annotations

# Imports inside functions: start-up time: a job of one kind loads only its own service
# (extraction loads the feature stack, training scikit-learn).
import _thread
import os
import shutil
import socket
import threading
from collections.abc import Callable
from typing import Any

from pydantic import ValidationError

from touchbench.app.errors import USER_ERRORS, AppError, client_words
from touchbench.app.schemas.ablation import AblationRequest
from touchbench.app.schemas.base import Request, Schema
from touchbench.app.schemas.extraction import ExtractRequest
from touchbench.app.schemas.importance import ImportanceRequest
from touchbench.app.schemas.jobs import JOB_REQUESTS, JobKind, JobSchema
from touchbench.app.schemas.learning import LearningCurveRequest
from touchbench.app.schemas.models import ExportRequest, TrainRequest
from touchbench.app.schemas.status import Status
from touchbench.app.store.database import Store
from touchbench.app.store.exports import queue_export
from touchbench.app.store.jobs import (
    claim_job,
    create_job,
    finish_job,
    get_job,
    job_heartbeat,
    record_job_progress,
    start_job,
)
from touchbench.app.store.ownership import process_owner

#: The kind of job of each request that answers a question after a run.
ANSWER_KINDS: dict[type[Request], JobKind] = {
    AblationRequest: "ablation",
    ImportanceRequest: "importance",
    LearningCurveRequest: "learning-curve",
}

#: Seconds a job's work has, once asked to stop, to end by itself (the interrupt reaches
#: Python code at once, native code only when it returns) before its process ends it.
STOP_GRACE = 5.0


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
    from touchbench.app.services.extraction import check_extraction

    check_extraction(store, request)
    return _submit(store, "extract", request)


def submit_training(store: Store, request: TrainRequest) -> JobSchema:
    """Queue training, once :func:`app.services.models.check_training` found nothing to
    refuse (before the job exists)."""
    from touchbench.app.services.models import check_training

    check_training(store, request)
    return _submit(store, "train", request)


def submit_export(store: Store, request: ExportRequest) -> tuple[JobSchema, bool]:
    """Queue the making of a model's ONNX twin, once
    :func:`app.services.export.check_export` found nothing to refuse; at most one such job
    per model at a time: a request while one is under way is answered with that job.

    Returns
    -------
    tuple of (JobSchema, bool)
        The job, and whether it was queued now.
    """
    from touchbench.app.services.export import check_export

    info = check_export(store, request)
    job_id, created = queue_export(store, info.id, request.format)
    return get_job(store, job_id), created


def submit_answer(
    store: Store, request: AblationRequest | ImportanceRequest | LearningCurveRequest
) -> JobSchema:
    """Queue an ablation, permutation importance or a learning curve, once its request was
    checked against the store (the run, its classifiers, the data set...)."""
    _check_answer(store, request)
    return _submit(store, ANSWER_KINDS[type(request)], request)


def carry_out_here(
    store: Store,
    request: AblationRequest | ImportanceRequest | LearningCurveRequest,
    *,
    jobs: int = 1,
    on_progress: Callable[[Schema], None] = lambda partial: None,
) -> tuple[int, dict[str, Any]]:
    """Carry out an answer's work in this process (the command line), as a job of its own
    that the store keeps, with its progress, for the API and the web page to show.

    Returns
    -------
    tuple of (int, dict)
        The job's id and its result.

    Raises
    ------
    AppError, ConfigurationError
        As the work raises them (the job ends ``failed`` with the same message).
    KeyboardInterrupt
        The job ends ``interrupted`` (``cancelled`` when the API cancelled it).
    """
    _check_answer(store, request)
    owner = process_owner()
    job = start_job(
        store,
        ANSWER_KINDS[type(request)],
        {**request.model_dump(mode="json"), "host": socket.gethostname()},
        owner=owner,
    )
    stopper = _Stopper(store, job.id, None)
    beat = job_heartbeat(store, job.id, owner, stopper.stop)
    beat.start()

    def progress(partial: Schema) -> None:
        record_job_progress(store, job.id, partial.to_json())
        on_progress(partial)

    try:
        try:
            result = _carry_out(store, request, jobs=jobs, on_progress=progress)
        finally:  # before the end is recorded, which the heartbeat would take for a cancel
            beat.stop()
    except KeyboardInterrupt:
        stopper.finish(
            Status.CANCELLED if stopper.asked else Status.INTERRUPTED, error=Status.INTERRUPTED
        )
        raise
    except USER_ERRORS as error:
        stopper.finish(Status.FAILED, error=str(error))
        raise
    except Exception as error:
        stopper.finish(Status.FAILED, error=f"unexpected {type(error).__name__}: {error}")
        raise
    else:
        stopper.finish(Status.DONE, result=result)
    return job.id, result


def _check_answer(
    store: Store, request: AblationRequest | ImportanceRequest | LearningCurveRequest
) -> None:
    if isinstance(request, AblationRequest):
        from touchbench.app.services.ablation import check_ablation

        check_ablation(store, request)
    elif isinstance(request, ImportanceRequest):
        from touchbench.app.services.importance import check_importance

        check_importance(store, request)
    else:
        from touchbench.app.services.learning import check_learning_curve

        check_learning_curve(store, request)


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
    removed either way.  A cancel, heard through the job's heartbeat, interrupts the work
    (see :class:`_Stopper`) and ends the job ``cancelled``.  Meant for the main thread of a
    job process (:mod:`app.jobs.process`).
    """
    job = get_job(store, job_id)
    owner = process_owner()
    if not claim_job(store, job.id, owner=owner):
        return None
    folder = job.params.get("folder") if job.kind == "extract" else None
    stopper = _Stopper(store, job.id, folder)
    beat = job_heartbeat(store, job.id, owner, stopper.stop)
    beat.start()
    try:
        try:
            result = _carry_out(
                store,
                job_request(job),
                on_progress=lambda partial: record_job_progress(store, job.id, partial.to_json()),
            )
        finally:
            # before the end is recorded, which the heartbeat would take for a cancel
            beat.stop()
            # before the job ends, so that whoever sees it ended finds no upload left
            if folder:
                shutil.rmtree(folder, ignore_errors=True)
    except KeyboardInterrupt:
        if not stopper.asked:
            stopper.finish(Status.INTERRUPTED, error=Status.INTERRUPTED)
            raise
        stopper.finish(Status.CANCELLED)
    except USER_ERRORS as error:
        stopper.finish(Status.FAILED, error=client_words(str(error), folder))
    except Exception as error:
        message = f"unexpected {type(error).__name__}: {error}"
        stopper.finish(Status.FAILED, error=client_words(message, folder))
    else:
        stopper.finish(Status.DONE, result=result)
    return get_job(store, job.id)


class _Stopper:
    """Ends a job once, whoever comes first: its own work, or a cancel.

    A cancel interrupts the main thread (a KeyboardInterrupt where the work is), which ends
    the job ``cancelled``; work in native code (a fit inside libsvm) hears the interrupt
    only when it returns, so after :data:`STOP_GRACE` seconds the process records the
    cancel itself, removes the upload and exits.
    """

    def __init__(self, store: Store, job_id: int, folder: str | None) -> None:
        self._store = store
        self._job_id = job_id
        self._folder = folder
        self._lock = threading.Lock()
        self._finished = False
        self.asked = False

    def stop(self) -> None:
        """The heartbeat heard a cancel (called in its thread)."""
        with self._lock:
            if self._finished:  # the job's own end, seen by a heartbeat still running
                return
            self.asked = True
        _thread.interrupt_main()
        timer = threading.Timer(STOP_GRACE, self._end_process)
        timer.daemon = True
        timer.start()

    def finish(self, status: Status, **values: Any) -> None:
        """Record how the job ended, unless that is done already."""
        with self._lock:
            if self._finished:
                return
            self._finished = True
            finish_job(self._store, self._job_id, status, **values)

    def _end_process(self) -> None:
        with self._lock:
            if self._finished:
                return
            self._finished = True
            finish_job(self._store, self._job_id, Status.CANCELLED)
            if self._folder:
                shutil.rmtree(self._folder, ignore_errors=True)
        os._exit(1)


def _carry_out(
    store: Store,
    request: Request,
    *,
    jobs: int = 1,
    on_progress: Callable[[Schema], None] = lambda partial: None,
) -> dict[str, Any]:
    """The result of a job's request: the new data set, the new model, or the answer."""
    if isinstance(request, AblationRequest):
        from touchbench.app.services.ablation import run_ablation

        return run_ablation(store, request, jobs=jobs, on_progress=on_progress).to_json()
    if isinstance(request, ImportanceRequest):
        from touchbench.app.services.importance import run_importance

        return run_importance(store, request, on_progress=on_progress).to_json()
    if isinstance(request, LearningCurveRequest):
        from touchbench.app.services.learning import learning_curve

        return learning_curve(store, request, jobs=jobs, on_progress=on_progress).to_json()
    if isinstance(request, ExtractRequest):
        from touchbench.app.services.extraction import extract_and_store

        summary = extract_and_store(store, request).to_json()
        return {"dataset_id": summary["id"], **summary}
    if isinstance(request, ExportRequest):
        from touchbench.app.services.export import export_model

        return export_model(store, request)[0].to_json()
    assert isinstance(request, TrainRequest)
    from touchbench.app.services.models import train

    model = train(store, request)
    return {"model_id": model.id, **model.to_json()}
