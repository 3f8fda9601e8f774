"""Jobs other than runs: extraction of uploaded sessions, training."""

from __future__ import annotations

from fastapi import APIRouter, Request, Response

from app.api.deps import PageDep, StoreDep, paginate
from app.schemas.jobs import JobList, JobSchema
from app.store.jobs import count_jobs, get_job, list_jobs, request_job_cancel

router = APIRouter(prefix="/api/jobs", tags=["jobs"])


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
    return request_job_cancel(store, job_id).for_client()
