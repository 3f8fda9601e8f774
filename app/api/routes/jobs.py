"""Jobs other than runs: extraction of uploaded sessions, training, and the answers after a
run (an ablation, permutation importance, a learning curve), started here (202)."""

from __future__ import annotations

from fastapi import APIRouter, Request, Response, status

from touchbench.app.api.deps import PageDep, ServiceDep, StoreDep, paginate
from touchbench.app.errors import ConflictError, NotFoundError
from touchbench.app.schemas.ablation import AblationRequest
from touchbench.app.schemas.importance import ImportanceRequest
from touchbench.app.schemas.jobs import JobCreated, JobList, JobSchema
from touchbench.app.schemas.learning import LearningCurveRequest
from touchbench.app.services.jobs import submit_answer
from touchbench.app.services.lifecycle import cancel_job, count_jobs, get_job, list_jobs

router = APIRouter(prefix="/api/jobs", tags=["jobs"])


def _started(
    request: AblationRequest | ImportanceRequest | LearningCurveRequest, service: ServiceDep
) -> JobCreated:
    job = submit_answer(service.store, request)
    service.dispatcher.wake()
    return JobCreated(job=job.id, status=job.status, kind=job.kind)


@router.post("/ablation", status_code=status.HTTP_202_ACCEPTED, response_model=JobCreated)
def ablation(body: AblationRequest, service: ServiceDep) -> JobCreated:
    """Rerun a finished run's classifiers without each group of features (``bench
    --ablate-groups``); the job's result is the answer, what is finished of it while it
    runs."""
    return _started(body, service)


@router.post("/importance", status_code=status.HTTP_202_ACCEPTED, response_model=JobCreated)
def importance(body: ImportanceRequest, service: ServiceDep) -> JobCreated:
    """Permutation importance of a run's classifier on its folds (``touchbench
    importance``), the folds done so far in the job's result while it runs."""
    return _started(body, service)


@router.post("/learning-curve", status_code=status.HTTP_202_ACCEPTED, response_model=JobCreated)
def learning_curve(body: LearningCurveRequest, service: ServiceDep) -> JobCreated:
    """Learning curves of classifiers on a data set (``touchbench learning-curve``); the
    curves so far in the job's result while it runs."""
    return _started(body, service)


@router.get("", response_model=JobList)
def jobs(store: StoreDep, page: PageDep, request: Request, response: Response) -> JobList:
    """The jobs, oldest first, a page of at most 1,000 (``X-Total-Count``, ``Link``)."""
    paginate(request, response, page, count_jobs(store))
    return JobList(jobs=[job.for_client() for job in list_jobs(store, page=page)])


@router.get("/{job_id}", response_model=JobSchema)
def job(job_id: int, store: StoreDep) -> JobSchema:
    """A job's status and, once done, its result (the new data set or model)."""
    return get_job(store, job_id).for_client()


@router.post("/{job_id}/cancel", response_model=JobSchema)
def cancel(job_id: int, store: StoreDep) -> JobSchema:
    """Cancel a queued job at once; a running one becomes ``cancelling`` and stops within
    about half a second (work in native code within a few seconds)."""
    return cancel_job(store, job_id).for_client()


@router.get(
    "/{job_id}/learning-curve.svg",
    response_class=Response,
    responses={200: {"content": {"image/svg+xml": {}}}},
)
def learning_curve_svg(job_id: int, store: StoreDep) -> Response:
    """The curves of a learning-curve job, as far as it has come."""
    # start-up time: matplotlib loads with the first figure drawn
    from touchbench.app.reports.figures import learning_figure
    from touchbench.app.reports.plots import svg_text
    from touchbench.app.schemas.learning import LearningCurveResult

    job = get_job(store, job_id)
    if job.kind != "learning-curve":
        raise NotFoundError(f"job {job.id} is a {job.kind} job, not a learning curve")
    if not job.result:
        raise ConflictError(f"job {job.id} has not scored a fold yet")
    figure = learning_figure(LearningCurveResult.model_validate(job.result))
    return Response(svg_text(figure), media_type="image/svg+xml")
