"""Models: train (a job, 202), list, describe, delete, predict (JSON instances or a file), their
ONNX twins (made by a job, 202; read as stored), and the aliases of their versions (alias,
promote, rollback, delete an alias).

``{model_ref}`` is an id, ``NAME`` (its newest version), ``NAME@VERSION`` or ``NAME@ALIAS``.
"""

from __future__ import annotations

# Imports inside functions: start-up time: scikit-learn (behind the model service) loads
# in the service's warm-up thread, not before it answers its first request.
import functools
import tempfile
import time
from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, File, Form, Request, Response, UploadFile, status

from touchbench.app.api.deps import PageDep, Service, ServiceDep, StoreDep, paginate, request_size
from touchbench.app.api.direct import DirectRoute
from touchbench.app.api.uploads import form_request, in_client_words, save_upload
from touchbench.app.errors import ConflictError, NotFoundError
from touchbench.app.schemas.jobs import JobCreated
from touchbench.app.schemas.models import (
    AliasBody,
    AliasDeleted,
    AliasMoved,
    AliasRequest,
    ExportRequest,
    ModelList,
    ModelSchema,
    PredictFileRequest,
    PredictionReport,
    PredictRequest,
    TrainRequest,
)
from touchbench.app.services.jobs import submit_export, submit_training
from touchbench.app.services.registry import count_models, delete_model, find_model, list_models

#: What changes the registry (train, twins, delete, aliases): the full service only.
router = APIRouter(prefix="/api/models", tags=["models"])
#: What a robot reads and asks (list, describe, the ONNX twin, predict a file): also served by a
#: predictions-only process (``touchbench serve --predictions-only``).
serving = APIRouter(prefix="/api/models", tags=["models"])
#: Predictions of JSON instances: documented by FastAPI, answered by a direct handler (the
#: request costs FastAPI more than a quick model's prediction; see ``app.api.direct``).
predictions = APIRouter(prefix="/api/models", tags=["models"], route_class=DirectRoute)


@router.post("", status_code=status.HTTP_202_ACCEPTED, response_model=JobCreated)
def train(body: TrainRequest, service: ServiceDep) -> JobCreated:
    """Train a classifier on a data set (``dataset`` + ``classifier``), or a run's best
    classifier (``run``), as a job; the job's result names the model.  What training would
    refuse (a name taken, a run without results, a target without known values) is refused
    before the job exists."""
    job = submit_training(service.store, body)
    service.dispatcher.wake()
    return JobCreated(job=job.id, status=job.status, kind=job.kind)


@serving.get("", response_model=ModelList)
def models(store: StoreDep, page: PageDep, request: Request, response: Response) -> ModelList:
    """The models, oldest first, a page of at most 1,000 (``X-Total-Count``, ``Link``)."""
    paginate(request, response, page, count_models(store))
    listed = list_models(store, page=page)
    return ModelList(models=[m.to_schema() for m in listed])


@serving.get("/{model_ref}", response_model=ModelSchema)
def model(model_ref: str, store: StoreDep) -> ModelSchema:
    """A model; ``onnx.problem`` says why its twin could not be loaded, once this service
    tried (its predictions with engine auto then run the model itself)."""
    return find_model(store, model_ref).to_schema()


@serving.get(
    "/{model_ref}/onnx",
    response_class=Response,
    responses={200: {"content": {"application/octet-stream": {}}}},
)
def onnx_graph(model_ref: str, store: StoreDep) -> Response:
    """The model's ONNX twin as one graph (input ``features``, outputs ``label`` and
    ``probabilities``; attribute and label names in its metadata), as stored: 404 when it
    has none (``POST`` to this path makes one, a job), 409 while a job makes it."""
    from touchbench.app.services.export import TwinMissing, TwinUnderWay, stored_twin

    try:
        info, graph = stored_twin(store, model_ref)
    except TwinMissing as missing:
        raise NotFoundError(
            f"{missing}; POST /api/models/{model_ref}/onnx makes it (a job), or train the "
            'model with "onnx": true'
        ) from None
    except TwinUnderWay as under_way:
        raise ConflictError(
            f"{under_way}; GET /api/jobs/{under_way.job} says when it is done"
        ) from None
    return Response(
        graph,
        media_type="application/octet-stream",
        headers={"Content-Disposition": f'attachment; filename="model-{info.id}.onnx"'},
    )


@router.post("/{model_ref}/onnx", status_code=status.HTTP_202_ACCEPTED, response_model=JobCreated)
def make_onnx(model_ref: str, service: ServiceDep) -> JobCreated:
    """Make the model's ONNX twin (again), checked on its training instances, as a job; while
    one is under way for the model, it is the answer.  What the export would refuse without
    converting (a classifier without a converter, a deleted data set) is refused at once."""
    job, created = submit_export(service.store, ExportRequest(model=model_ref))
    if created:
        service.dispatcher.wake()
    return JobCreated(job=job.id, status=job.status, kind=job.kind)


@router.delete("/{model_ref}", response_model=ModelSchema)
def remove(model_ref: str, service: ServiceDep) -> ModelSchema:
    gone = delete_model(service.store, model_ref)
    service.forget(gone.id)
    return gone.to_schema()


@router.post("/{model_ref}/aliases", response_model=AliasMoved)
def alias(model_ref: str, body: AliasBody, store: StoreDep) -> AliasMoved:
    """Point ``NAME@alias`` at the version ``model_ref`` names (``touchbench alias``)."""
    from touchbench.app.services.models import move_alias

    return move_alias(store, AliasRequest(model=model_ref, alias=body.alias)).to_schema()


@router.delete("/{model_ref}/aliases/{alias}", response_model=AliasDeleted)
def unalias(model_ref: str, alias: str, store: StoreDep) -> AliasDeleted:
    """Delete ``NAME@alias`` (``touchbench alias --delete``): 404 when there is no such
    alias, 409 when ``model_ref`` names a version (``NAME@3``) the alias no longer points
    at; live sessions following it keep their version and say so once."""
    from touchbench.app.services.models import remove_alias

    return remove_alias(store, AliasRequest(model=model_ref, alias=alias))


@router.post("/{model_ref}/promote", response_model=AliasMoved)
def promote(model_ref: str, store: StoreDep) -> AliasMoved:
    """Make the version ``model_ref`` names the champion: predictions and live sessions on
    ``NAME@champion`` answer with it from now on (``touchbench promote``)."""
    from touchbench.app.services.models import move_alias

    return move_alias(store, AliasRequest(model=model_ref)).to_schema()


@router.post("/{model_ref}/rollback", response_model=AliasMoved)
def rollback(model_ref: str, store: StoreDep, body: AliasBody | None = None) -> AliasMoved:
    """Point the champion (or ``alias``) of the model back at the version it pointed at
    before its last move (``touchbench rollback``)."""
    from touchbench.app.services.models import roll_back

    alias = "champion" if body is None else body.alias
    return roll_back(store, AliasRequest(model=model_ref, alias=alias)).to_schema()


@predictions.post("/{model_ref}/predict", response_model=PredictionReport)
async def predict_instances(model_ref: str, body: PredictRequest, service: ServiceDep) -> Response:
    """Predict instances given as ``{attribute: value}`` (matched to the model by name):
    per instance and target the predicted label and the class probabilities."""
    size = request_size(body.instances)
    content = await service.placement.run(
        model_ref,
        size,
        functools.partial(_predict_records, service, model_ref, body, size),
    )
    return Response(content, media_type="application/json")


def _predict_records(service: Service, model_ref: str, body: PredictRequest, size: int) -> bytes:
    """The prediction report as JSON (written here once, not validated again against the
    response model it was built from); its CPU time is recorded for ``size``."""
    from touchbench.app.services.models import records_report

    info, trained = service.models.get(service.store, model_ref, body.engine)
    start = time.thread_time()
    report = records_report(info, trained, body.instances, missing=body.missing)
    service.placement.record(info.id, time.thread_time() - start, size)
    return report.model_dump_json().encode()


@serving.post("/{model_ref}/predict/file", response_model=PredictionReport)
def predict_upload(
    model_ref: str,
    service: ServiceDep,
    file: Annotated[
        UploadFile,
        File(
            description="ARFF or CSV with the model's attributes, or a raw recording (WAV, "
            "FLAC, a CSV time series, a bag) of a model trained on extracted features."
        ),
    ],
    engine: Annotated[
        str | None,
        Form(description="auto (default), onnx or native: what runs the predictions."),
    ] = None,
) -> PredictionReport:
    """Predict every instance of an uploaded ARFF or CSV file (accuracy when it carries the
    targets), or of a raw recording, whose instances are extracted with the model's own
    recipe (as ``touchbench predict MODEL take.wav``).  The upload is bounded by the
    service's upload limit (``max_upload_mb``), and so is the extraction's work."""
    from touchbench.app.services.models import predict_file

    with tempfile.TemporaryDirectory(dir=_work_dir(service)) as folder:
        fields = {"model": model_ref, "engine": engine}
        asked = form_request(PredictFileRequest, file=Path(folder) / "upload", **fields)
        # The model before the upload is read: an unknown one is answered at once (loaded
        # here, it is in the cache that predict_file's loader reads).
        service.models.get(service.store, asked.model, asked.engine)
        path = save_upload(file, Path(folder), "upload.arff")
        request = form_request(PredictFileRequest, file=path, source_name=path.name, **fields)
        with in_client_words(Path(folder)):  # the client's names, not our folder
            return predict_file(service.store, request, loader=service.models.get)


def _work_dir(service: ServiceDep) -> Path:
    service.settings.work_dir.mkdir(parents=True, exist_ok=True)
    return service.settings.work_dir
